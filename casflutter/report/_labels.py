"""Axis labels a person reads: sensor names with their units, 1-based mode numbers."""

from __future__ import annotations

__all__ = ["sensor_unit", "sensor_labels"]

_POWER = {"displacement": "", "velocity": "/{t}", "acceleration": "/{t}²"}


def sensor_unit(unit: str, kind: str, time_unit: str = "s") -> str:
    """Unit of a sensor reading ``Hs u`` (``unit``) differentiated as ``kind`` says.

    Parameters
    ----------
    unit : str
        Unit of ``Hs u`` (``""`` or ``"-"`` when the problem gives none).
    kind : {"displacement", "velocity", "acceleration"}
        What the sensor reads.
    time_unit : str
        The problem's time unit.

    Returns
    -------
    str
        E.g. ``"m/s²"``; ``"modal units"`` (with the time power) when ``unit`` is empty.
    """
    t = time_unit if time_unit.isalpha() else f"({time_unit})"
    base = unit if unit and unit != "-" else ("-" if unit == "-" else "modal units")
    power = _POWER.get(kind, "").format(t=t)
    if not power:
        return base
    return f"1{power}" if base == "-" else f"{base}{power}"


def sensor_labels(names, units, kind: str, time_unit: str = "s") -> list[str]:
    """``"name [unit]"`` per sensor (see :func:`sensor_unit`).

    Parameters
    ----------
    names : sequence of str
        Sensor names (``zm[j]`` are renamed ``sensor j+1``).
    units : sequence of str
        Units of ``Hs u`` per sensor (missing entries count as empty).
    kind : str
        The sensors' kind.
    time_unit : str
        The problem's time unit.

    Returns
    -------
    list of str
    """
    names = list(names)
    units = list(units) + [""] * (len(names) - len(units))
    out = []
    for j, (n, u) in enumerate(zip(names, units)):
        if n.startswith("zm["):
            n = f"sensor {j + 1}"
        out.append(f"{n} [{sensor_unit(u, kind, time_unit)}]")
    return out
