"""The units of a run's outputs: speed index, airspeed and dynamic pressure kept apart.

Every stage works in the problem's speed index ``V`` (eq. 6: the structure sees
``alpha V^2 y``); what ``V`` means is the problem's own
:class:`~casflutter.structure.SpeedConvention` (``modal_structure().speed``, e.g.
``V = U / U_ref``), which converts it to the airspeed ``U`` [m/s] when the problem has a
speed scale and to the dynamic pressure ``q = rho U^2 / 2`` [Pa] when it knows the air
density.  :func:`speed_values` writes one speed with every unit named
(``{"speed_index": ..., "airspeed_m_s": ..., "dynamic_pressure_Pa": ...}``), so that no output
holds a bare number whose unit the reader must guess.
"""

from __future__ import annotations

import math

from ..structure import SpeedConvention

__all__ = ["speed_scale", "speed_values", "interval_values", "units_block", "sensor_units",
           "FLAP_UNIT"]

#: Unit of the flap deflection ``v`` of every problem (the truths' ``aero_forces``).
FLAP_UNIT = "rad"


def speed_scale(problem) -> SpeedConvention:
    """The :class:`~casflutter.structure.SpeedConvention` of a truth or a wing problem.

    Parameters
    ----------
    problem : object
        Anything with ``modal_structure()``.

    Returns
    -------
    SpeedConvention
    """
    return problem.modal_structure().speed


def _num(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def speed_values(V, scale: SpeedConvention) -> dict | None:
    """One speed index with its airspeed and dynamic pressure, each key naming its unit.

    Parameters
    ----------
    V : float or None
        Speed index.
    scale : SpeedConvention

    Returns
    -------
    dict or None
        ``speed_index``, and ``airspeed_m_s`` / ``dynamic_pressure_Pa`` when the problem has
        them (``None`` for a non-finite end of an interval); ``None`` when ``V`` is ``None``.
    """
    if V is None:
        return None
    V = float(V)
    out = {"speed_index": _num(V)}
    if scale.has_airspeed:
        out["airspeed_m_s"] = _num(scale.airspeed(V)) if math.isfinite(V) else None
    if scale.has_dynamic_pressure:
        out["dynamic_pressure_Pa"] = (_num(scale.dynamic_pressure(V)) if math.isfinite(V)
                                      else None)
    return out


def interval_values(pair, scale: SpeedConvention) -> dict | None:
    """A speed interval ``(lo, hi)`` in every unit: ``{"speed_index": [lo, hi],
    "airspeed_m_s": [...], "dynamic_pressure_Pa": [...]}`` (``None`` without an interval)."""
    if pair is None:
        return None
    lo, hi = speed_values(pair[0], scale), speed_values(pair[1], scale)
    return {k: [lo[k], hi[k]] for k in lo}


def units_block(scale: SpeedConvention) -> dict:
    """The ``units`` entry of ``summary.json``: what each kind of number is measured in.

    Returns
    -------
    dict
        ``V`` (the speed index and its definition), ``airspeed_m_s``,
        ``dynamic_pressure_Pa`` (``None`` when the problem has no such scale), ``freq_hz``,
        ``time``.
    """
    return {"V": scale.speed_index_label + ": every key V, V0, *_V, V_* that is not named "
                 "*_m_s or *_Pa",
            "airspeed_m_s": "m/s" if scale.has_airspeed else None,
            "dynamic_pressure_Pa": "Pa" if scale.has_dynamic_pressure else None,
            "freq_hz": scale.frequency_unit,
            "time": scale.time_unit}


def sensor_units(problem, structure, custom_rows: bool) -> tuple[str, ...]:
    """The unit of each sensor reading ``zm`` (eq. 7).

    The problem's ``sensor_units()`` are of the displacement its rows read; a velocity or
    acceleration sensor reads that per time unit (squared).  Rows given in the run
    configuration (``custom_rows``) are in modal coordinates, whose unit is the problem's
    mode normalisation.

    Returns
    -------
    tuple of str
        One unit per sensor.
    """
    n = int(structure.n_sensors)
    base = ("",) * n
    given = getattr(problem, "sensor_units", None)
    if not custom_rows and isinstance(given, tuple) and len(given) == n:
        return given          # a wing file gives the unit of each reading itself
    if not custom_rows and callable(given):
        got = tuple(given())
        if len(got) == n:
            base = got
    t = structure.time_unit
    per = {"displacement": "", "velocity": f"/{t}", "acceleration": f"/{t}^2"}.get(
        structure.sensor, "")
    out = []
    for u in base:
        if not u:
            out.append(f"modal displacement{per} (Hs rows of the problem's mode normalisation)")
        elif u == "-":
            out.append(f"1{per}" if per else "-")
        else:
            out.append(f"{u}{per}")
    return tuple(out)
