"""The units of a run's outputs: speed index, airspeed and dynamic pressure kept apart.

Every stage works in the problem's speed index ``V`` (eq. 6: the structure sees
``alpha V^2 y``); what ``V`` means is the problem's own convention
(``modal_structure().speed_index``, e.g. ``V = U / U_ref``).  A problem that knows its speed
scale converts it to the airspeed ``U`` [m/s] (``problem.airspeed(V)``) and, when it knows
the air density, to the dynamic pressure ``q = rho U^2 / 2`` [Pa].  :class:`SpeedScale`
gathers these conversions, and :func:`speed_values` writes one speed with every unit named
(``{"speed_index": ..., "airspeed_m_s": ..., "dynamic_pressure_Pa": ...}``), so that no output
holds a bare number whose unit the reader must guess.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

__all__ = ["SpeedScale", "speed_scale", "speed_values", "interval_values", "units_block",
           "sensor_units", "FLAP_UNIT"]

#: Unit of the flap deflection ``v`` of every problem (the truths' ``aero_forces``).
FLAP_UNIT = "rad"


@dataclass(frozen=True)
class SpeedScale:
    """The speed conventions of a problem.

    Attributes
    ----------
    definition : str
        What the speed index is (``modal_structure().speed_index``).
    time_unit : str
        Unit of time of the problem (frequencies are in rad per this unit).
    to_airspeed : callable or None
        Speed index -> airspeed [m/s] (``None``: the problem has no speed scale).
    to_dynamic_pressure : callable or None
        Speed index -> dynamic pressure [Pa] (``None``: no air density known).
    """

    definition: str
    time_unit: str = "s"
    to_airspeed: Callable[[float], float] | None = None
    to_dynamic_pressure: Callable[[float], float] | None = None

    @property
    def speed_index_label(self) -> str:
        """``"speed index (<definition>)"``."""
        return f"speed index ({self.definition})"


def speed_scale(problem) -> SpeedScale:
    """The :class:`SpeedScale` of a truth or a wing problem.

    Parameters
    ----------
    problem : object
        Anything with ``modal_structure()``; ``airspeed(V)`` [m/s] when it has a speed scale,
        and ``dynamic_pressure(V)`` [Pa] or ``params.rho`` [kg/m^3] for the dynamic pressure.

    Returns
    -------
    SpeedScale
    """
    ms = problem.modal_structure()
    to_u = getattr(problem, "airspeed", None)
    to_u = to_u if callable(to_u) else None
    to_q = None
    if callable(getattr(problem, "dynamic_pressure", None)):
        if getattr(problem, "rho", 1.0) is not None:
            to_q = problem.dynamic_pressure
    elif to_u is not None:
        rho = getattr(getattr(problem, "params", None), "rho", None)
        if isinstance(rho, (int, float)) and math.isfinite(rho) and rho > 0:
            to_q = lambda V, _u=to_u, _r=float(rho): 0.5 * _r * _u(V) ** 2  # noqa: E731
    return SpeedScale(str(ms.speed_index), str(ms.time_unit), to_u, to_q)


def _num(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def speed_values(V, scale: SpeedScale) -> dict | None:
    """One speed index with its airspeed and dynamic pressure, each key naming its unit.

    Parameters
    ----------
    V : float or None
        Speed index.
    scale : SpeedScale

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
    if scale.to_airspeed is not None:
        out["airspeed_m_s"] = _num(scale.to_airspeed(V)) if math.isfinite(V) else None
    if scale.to_dynamic_pressure is not None:
        out["dynamic_pressure_Pa"] = (_num(scale.to_dynamic_pressure(V)) if math.isfinite(V)
                                      else None)
    return out


def interval_values(pair, scale: SpeedScale) -> dict | None:
    """A speed interval ``(lo, hi)`` in every unit: ``{"speed_index": [lo, hi],
    "airspeed_m_s": [...], "dynamic_pressure_Pa": [...]}`` (``None`` without an interval)."""
    if pair is None:
        return None
    lo, hi = speed_values(pair[0], scale), speed_values(pair[1], scale)
    return {k: [lo[k], hi[k]] for k in lo}


def units_block(scale: SpeedScale) -> dict:
    """The ``units`` entry of ``summary.json``: what each kind of number is measured in.

    Returns
    -------
    dict
        ``V`` (the speed index and its definition), ``airspeed_m_s``,
        ``dynamic_pressure_Pa`` (``None`` when the problem has no such scale), ``freq_hz``,
        ``time``.
    """
    t = scale.time_unit
    return {"V": scale.speed_index_label + ": every key V, V0, *_V, V_* that is not named "
                 "*_m_s or *_Pa",
            "airspeed_m_s": "m/s" if scale.to_airspeed is not None else None,
            "dynamic_pressure_Pa": "Pa" if scale.to_dynamic_pressure is not None else None,
            "freq_hz": "Hz" if t == "s" else f"cycles per time unit {t}",
            "time": t}


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
    if not custom_rows and callable(getattr(problem, "sensor_units", None)):
        got = tuple(problem.sensor_units())
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
