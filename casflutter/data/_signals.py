"""Excitation signals (band-limited chirps, paper §IV.A) and backward-difference derivatives.

Three chirp shapes serve three kinds of experiment, with one check of their band:

- :func:`chirp_excitation` — several mutually decorrelated channels at once (triangle sweeps at
  seeded rates and phases), for records in which every input moves together;
- :func:`chirp_motion` — one tapered linear sweep with its exact first and second
  derivatives, for a prescribed motion that starts and ends at rest (one channel per record);
- :func:`stepped_chirp_motion` — the same sweep repeated at several amplitudes one after the
  other, each repetition starting and ending at rest: a record that covers the amplitude
  range of a nonlinear response (the amplitude-dependent terms of a nonlinear model are
  fitted where they act).

:func:`backward_derivatives` gives the grid velocity and acceleration a second-order implicit
CFD time step computes from the displacement samples (BDF2): a causal function of the samples.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError, DataError

__all__ = ["chirp_excitation", "chirp_motion", "stepped_chirp_motion", "backward_derivatives",
           "check_band"]


def check_band(band, dt: float | None = None) -> tuple[float, float]:
    """The chirp band ``(f_low, f_high)`` [Hz] checked against ``0 <= f_low < f_high`` and,
    with a sampling time, against the Nyquist frequency ``1 / (2 dt)``.

    Parameters
    ----------
    band : (float, float)
        Lowest and highest frequency [cycles per time unit of the problem].
    dt : float, optional
        Sampling time.

    Returns
    -------
    (float, float)

    Raises
    ------
    ConfigError
        A band that is not two increasing non-negative numbers, or whose top is not below the
        Nyquist frequency of ``dt``.
    """
    try:
        f0, f1 = (float(x) for x in band)
    except (TypeError, ValueError):
        raise ConfigError(f"band = {band!r}: give [f_low, f_high] in Hz") from None
    if not 0.0 <= f0 < f1:
        raise ConfigError(f"band = {band!r}: must satisfy 0 <= f_low < f_high [Hz]")
    if dt is not None and f1 >= 0.5 / dt:
        raise ConfigError(f"band upper edge {f1:g} Hz is above the Nyquist frequency "
                          f"{0.5 / dt:g} Hz of dt = {dt:g}; lower it or sample faster")
    return f0, f1


def chirp_excitation(n_samples: int, dt: float, n_channels: int = 1, *,
                     band: tuple[float, float] = (0.1, 10.0), amplitude=1.0,
                     taper: float = 0.05, seed: int | None = 0) -> np.ndarray:
    """Band-limited linear chirps, one per channel, mutually decorrelated.

    Each channel sweeps ``band`` (Hz) up and down with a continuous instantaneous frequency
    (no phase jumps), at a channel-specific, seeded rate and phase, alternately starting at
    the low and the high edge, so that the channels are not collinear; a cosine taper of
    relative length ``taper`` at both ends keeps the spectrum inside the band.

    Parameters
    ----------
    n_samples : int
        Samples per channel (at least 4).
    dt : float
        Sampling time [s]; ``band[1]`` must lie below the Nyquist frequency ``1/(2 dt)``.
    n_channels : int
        Number of channels.
    band : (float, float)
        Lowest and highest frequency [Hz].
    amplitude : float or array of length n_channels
        Peak amplitude of each channel.
    taper : float
        Fraction of the record tapered at each end.
    seed : int
        Seed of the random shifts and phases.

    Returns
    -------
    ndarray, shape (n_samples, n_channels)

    Raises
    ------
    ConfigError
        A band that is not increasing or reaches the Nyquist frequency (:func:`check_band`).
    DataError
        Fewer than 4 samples.

    See Also
    --------
    chirp_motion : one chirp with its exact derivatives.
    stepped_chirp_motion : chirps at several amplitude levels, one after the other.
    truth_records : chirp records of a truth simulator.

    Examples
    --------
    >>> import casflutter as cf
    >>> u = cf.chirp_excitation(2000, 0.01, n_channels=2, band=(1.0, 20.0), seed=0)
    >>> u.shape, bool(abs(u).max() <= 1.0)
    ((2000, 2), True)
    """
    f0, f1 = check_band(band, dt)
    if n_samples < 4:
        raise DataError("a chirp needs at least 4 samples")
    rng = np.random.default_rng(seed)
    T = n_samples * dt
    t = np.arange(n_samples) * dt
    amp = np.broadcast_to(np.asarray(amplitude, dtype=float), (n_channels,))
    out = np.empty((n_samples, n_channels))
    for c in range(n_channels):
        # channel c sweeps up (even c) or down (odd c), with its own seeded sweep rate
        # (a fraction of the band covered twice or more) and phase: smooth, no jumps
        cycles = 1 + c // 2 + rng.random()
        Tc = T / cycles
        tau = t % (2 * Tc)
        tri = np.where(tau < Tc, tau, 2 * Tc - tau)  # triangle sweep: continuous frequency
        if c % 2:
            tri = Tc - tri
        freq = f0 + (f1 - f0) * tri / Tc
        phase = 2 * np.pi * np.cumsum(freq) * dt
        out[:, c] = amp[c] * np.sin(phase + 2 * np.pi * rng.random())
    n_tap = int(round(taper * n_samples))
    if n_tap > 0:
        w = 0.5 * (1 - np.cos(np.pi * np.arange(n_tap) / n_tap))
        out[:n_tap] *= w[:, None]
        out[n_samples - n_tap:] *= w[::-1, None]
    return out


def chirp_motion(timepts, band: tuple[float, float], amplitude: float = 1.0,
                 taper: float = 0.1, phase: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A tapered linear chirp and its exact first and second derivatives.

    ``s(t) = amplitude w(t) sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)) + phase)`` with a
    raised-cosine taper ``w`` over the first and last ``taper`` fraction of the record
    (so the motion starts and ends at rest, smoothly).

    Parameters
    ----------
    timepts : array_like, shape (K,)
        Increasing, uniformly spaced sample times (the record starts at ``timepts[0]``).
    band : (float, float)
        Start and end frequency [Hz, i.e. cycles per time unit of the problem].
    amplitude : float
        Peak amplitude.
    taper : float
        Fraction of the record tapered at each end, in (0, 0.5].
    phase : float
        Phase offset [rad].

    Returns
    -------
    s, sdot, sddot : ndarray, shape (K,)

    Raises
    ------
    DataError
        Fewer than 4 samples or times that do not increase.
    ConfigError
        A taper outside (0, 0.5] or a band that is not increasing or reaches the Nyquist
        frequency of the sampling (:func:`check_band`).

    See Also
    --------
    chirp_excitation : decorrelated chirps for several channels.
    truth_records : records of a truth driven by such motions.

    Examples
    --------
    >>> import numpy as np
    >>> import casflutter as cf
    >>> t = np.linspace(0.0, 10.0, 2001)
    >>> x, xdot, xddot = cf.chirp_motion(t, band=(0.1, 2.0), amplitude=0.01)
    >>> x.shape == xdot.shape == xddot.shape == t.shape
    True
    """
    t = np.asarray(timepts, dtype=float).ravel()
    if t.size < 4 or np.any(np.diff(t) <= 0):
        raise DataError("timepts must hold at least 4 increasing samples")
    if not 0.0 < taper <= 0.5:
        raise ConfigError(f"taper = {taper}: must lie in (0, 0.5]")
    f0, f1 = check_band(band, (t[-1] - t[0]) / (t.size - 1))
    t = t - t[0]
    Tr = t[-1]
    k = (f1 - f0) / Tr
    ph = 2 * np.pi * (f0 * t + 0.5 * k * t * t) + phase
    d1 = 2 * np.pi * (f0 + k * t)
    d2 = 2 * np.pi * k
    Tt = taper * Tr
    w, w1, w2 = np.ones_like(t), np.zeros_like(t), np.zeros_like(t)
    for mask, x, sgn in ((t < Tt, t, 1.0), (t > Tr - Tt, Tr - t, -1.0)):
        xx = np.pi * x[mask] / Tt
        w[mask] = 0.5 * (1.0 - np.cos(xx))
        w1[mask] = sgn * 0.5 * np.pi / Tt * np.sin(xx)
        w2[mask] = 0.5 * (np.pi / Tt) ** 2 * np.cos(xx)
    s, c = np.sin(ph), np.cos(ph)
    u = w * s
    ud = w1 * s + w * d1 * c
    udd = w2 * s + 2 * w1 * d1 * c + w * d2 * c - w * d1 * d1 * s
    return amplitude * u, amplitude * ud, amplitude * udd


def stepped_chirp_motion(timepts, band: tuple[float, float], levels, taper: float = 0.1,
                         phase: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Amplitude-stepped chirps: :func:`chirp_motion` once per level, one after the other.

    The samples are split into ``len(levels)`` consecutive segments of (nearly) equal length;
    segment ``k`` is a tapered chirp over the whole ``band`` with peak amplitude
    ``levels[k]``.  Every segment starts and ends at rest (value and both derivatives zero),
    so the concatenation is twice continuously differentiable and its derivatives are exact.

    Parameters
    ----------
    timepts : array_like, shape (K,)
        Increasing, uniformly spaced sample times.
    band : (float, float)
        Start and end frequency of every segment [cycles per time unit of the problem].
    levels : sequence of float
        Peak amplitude of each segment, in the order they are applied (at least one; every
        segment keeps at least 4 samples).
    taper : float
        Fraction of each segment tapered at each end, in (0, 0.5].
    phase : float
        Phase offset of every segment [rad].

    Returns
    -------
    s, sdot, sddot : ndarray, shape (K,)

    Raises
    ------
    ConfigError
        No level, a level that is not a finite number, or a bad taper or band
        (:func:`chirp_motion`).
    DataError
        Times that do not increase, or fewer than 4 samples per segment.
    """
    t = np.asarray(timepts, dtype=float).ravel()
    try:
        amps = [float(a) for a in levels]
    except (TypeError, ValueError):
        raise ConfigError(f"levels = {levels!r}: give a list of amplitudes") from None
    if not amps or not all(np.isfinite(amps)):
        raise ConfigError(f"levels = {levels!r}: give at least one finite amplitude")
    n = len(amps)
    if t.size < 4 * n:
        raise DataError(f"{t.size} samples cannot hold {n} chirps of at least 4 samples")
    edges = np.linspace(0, t.size, n + 1).round().astype(int)
    out = [np.empty(t.size) for _ in range(3)]
    for k, a in enumerate(amps):
        seg = slice(edges[k], edges[k + 1])
        for o, x in zip(out, chirp_motion(t[seg], band, a, taper, phase)):
            o[seg] = x
    return out[0], out[1], out[2]


def backward_derivatives(x, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Second-order backward differences (BDF2) of samples, at rest before the record.

    ``xdot(k) = (3 x_k - 4 x_{k-1} + x_{k-2}) / (2 dt)``,
    ``xddot(k) = (2 x_k - 5 x_{k-1} + 4 x_{k-2} - x_{k-3}) / dt^2``, with ``x_{k<0} = 0``:
    the grid velocity and acceleration of a second-order implicit CFD time step.

    Parameters
    ----------
    x : array_like, shape (K, ...)
        Samples along the first axis.
    dt : float
        Sampling time.

    Returns
    -------
    xdot, xddot : ndarray, shape of ``x``
    """
    x = np.asarray(x, dtype=float)
    xp = np.concatenate([np.zeros((3,) + x.shape[1:]), x], axis=0)
    d1 = (3 * xp[3:] - 4 * xp[2:-1] + xp[1:-2]) / (2 * dt)
    d2 = (2 * xp[3:] - 5 * xp[2:-1] + 4 * xp[1:-2] - xp[:-3]) / dt ** 2
    return d1, d2
