"""Time channels of records: the sampling time their stamps give, and the words for a
channel that is not uniform or that contradicts a sampling time given instead of it.

Shared by the record readers (:mod:`._records`: CSV, NPZ, MATLAB) and the wing files
(:mod:`casflutter.truth`), which read the same kinds of channels.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TIME_NAMES", "positive_number", "significant_digits", "stamp_resolution",
           "uniform_step", "not_uniform", "time_contradiction", "time_contradicts"]

#: Names of a time channel, looked for (case-insensitively) when ``dt`` is given instead of
#: a time channel, to check the two against each other (:func:`time_contradiction`).
TIME_NAMES = ("t", "time")


def positive_number(x) -> bool:
    """Whether ``x`` is a positive finite real number (a usable sampling time)."""
    if isinstance(x, (bool, np.bool_, str, bytes)):
        return False
    try:
        return bool(np.isfinite(float(x)) and float(x) > 0)
    except (TypeError, ValueError):
        return False


def significant_digits(text: str) -> int:
    """Significant digits written in a number's text (``"0.00400000019"`` -> 9)."""
    mantissa = text.strip().lstrip("+-").split("e")[0].split("E")[0]
    return len("".join(ch for ch in mantissa if ch.isdigit()).lstrip("0"))


def stamp_resolution(t: np.ndarray, stored=None, digits: int | None = None) -> float:
    """The largest error of one time step ``t[k+1] - t[k]`` that rounding the time stamps as
    they are stored can make.

    Each stamp is the time rounded to the stored number type, off by at most half its
    spacing at the largest ``|t|``; a step, the difference of two stamps, by at most one
    spacing.  Integer stamps are exact.  Text (a CSV column, ``stored`` None) carries no
    number type: the resolution of its written significant digits (``digits``, the most
    any stamp has) at the largest ``|t|``, and at least single precision's spacing (time
    stamps are often recorded in single precision and written out in full).

    Parameters
    ----------
    t : ndarray
        The time stamps (as float64).
    stored : numpy dtype, optional
        The number type the stamps were stored in (None: text).
    digits : int, optional
        Significant digits of the text.

    Returns
    -------
    float
        The resolution [s].
    """
    tmax = float(np.max(np.abs(t))) if t.size else 0.0
    if stored is not None:
        stored = np.dtype(stored)
        if stored.kind in "biu":
            return 0.0
        return float(np.spacing(np.asarray(tmax, dtype=stored)))
    res = float(np.spacing(np.float32(tmax)))
    if digits and tmax > 0:
        res = max(res, 10.0 ** (np.floor(np.log10(tmax)) - digits + 1))
    return res


def uniform_step(t: np.ndarray, resolution: float) -> float | None:
    """The sampling time of increasing time stamps, or None when they are not uniform.

    Steps equal to within 1e-6 (relative) give their median.  Steps that differ by more,
    but not by more than the stamps' own rounding can make (``resolution``,
    :func:`stamp_resolution`; twice it between a step and the median step), are a uniform
    grid stored coarsely: its sampling time is the least-squares slope of the stamps over
    the sample index, which averages their rounding out (an error of about
    ``resolution / K**1.5``, where one step's is ``resolution``).

    Parameters
    ----------
    t : ndarray
        Increasing time stamps, at least two.
    resolution : float
        The largest step error of the stamps' rounding [s].

    Returns
    -------
    float or None
        The sampling time [s], or None for a grid that is not uniform.
    """
    steps = np.diff(t)
    dt = float(np.median(steps))
    if np.allclose(steps, dt, rtol=1e-6, atol=1e-12):
        return dt
    if np.allclose(steps, dt, rtol=1e-6, atol=2.0 * resolution):
        k = np.arange(t.size) - 0.5 * (t.size - 1)
        return float(k @ (t - t.mean()) / (k @ k))
    return None


def not_uniform(where: str, what: str, steps: np.ndarray, resolution: float, stored: str,
                 override: str = "pass dt = {dt} instead (dt=, --dt on the command line, "
                                 "records.dt in a wing file), which overrides the time "
                                 "channel") -> str:
    """The message for a time channel that is not uniformly sampled; ``override`` says how
    to give the sampling time instead (``{dt}``: the median step)."""
    dt = f"{float(np.median(steps)):.9g}"
    return (f"{where}: time {what} is not uniformly sampled (steps {steps.min():.9g} to "
            f"{steps.max():.9g} s, more than rounding its {stored} time stamps can explain, "
            f"{resolution:.2g} s); resample the record, or, if the samples are uniform and "
            f"only the time stamps are not, {override.format(dt=dt)}")


def time_contradiction(t: np.ndarray, dt: float) -> float | None:
    """The step of a time channel that contradicts a sampling time ``dt`` given instead of
    it, or None where they agree.

    A channel stepping by ``dt`` in seconds, milliseconds or microseconds agrees (to 0.1 %);
    a channel that is not increasing is not a time channel and is not checked.
    """
    if t.size < 2:
        return None
    steps = np.diff(t)
    if not np.all(np.isfinite(steps)) or not np.all(steps > 0):
        return None
    step = float(np.median(steps))
    if any(abs(step / (dt * scale) - 1.0) <= 1e-3 for scale in (1.0, 1e3, 1e6)):
        return None
    return step


def time_contradicts(where: str, given: str, dt: float, channel: str, step: float) -> str:
    """The warning for a time channel that contradicts the sampling time given."""
    return (f"{where}: the sampling time given, {given} = {dt:g} s, contradicts the time "
            f"channel {channel!r}, which steps by {step:g}: {given} is used and {channel!r} "
            f"is not; if {channel!r} is the time in seconds, use it instead of the sampling "
            "time (records.time in a wing file, --time without --dt on the command line)")
