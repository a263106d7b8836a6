"""Axis labels a person reads: sensor names with their units, frequencies in the problem's
time, 1-based mode numbers."""

from __future__ import annotations

__all__ = ["sensor_unit", "sensor_labels", "frequency_unit", "label_unit"]

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


#: frequencies of a problem in nondimensional time, as a figure writes them
_NONDIMENSIONAL = {"1/omega_theta": "Ω/ω_θ"}


def frequency_unit(time_unit: str) -> str | None:
    """The unit of an angular frequency in a problem's time: ``None`` for seconds (the
    caller chooses Hz or rad/s), else the nondimensional frequency (``"Ω/ω_θ"`` for the
    typical section's time ``1/omega_theta``, ``"rad/(T)"`` for another time unit ``T``).

    Parameters
    ----------
    time_unit : str
        The problem's time unit (``ModalStructure.time_unit``).

    Returns
    -------
    str or None
    """
    if time_unit == "s":
        return None
    return _NONDIMENSIONAL.get(time_unit, f"rad/({time_unit})")


def label_unit(label: str) -> str:
    """The unit of an axis label ``"name [unit]"`` (``""`` when it has none).

    Parameters
    ----------
    label : str
        E.g. from :func:`sensor_labels`.

    Returns
    -------
    str
    """
    return label.rsplit(" [", 1)[1].rstrip("]") if label.endswith("]") and " [" in label else ""
