"""Excitation signals: band-limited chirps as used for the CFD runs of paper §IV.A."""

from __future__ import annotations

import numpy as np

from ..errors import DataError

__all__ = ["chirp_excitation"]


def chirp_excitation(n_samples: int, dt: float, n_channels: int = 1, *,
                     band: tuple[float, float] = (0.1, 10.0), amplitude=1.0,
                     taper: float = 0.05, seed: int | None = 0) -> np.ndarray:
    """Band-limited linear chirps, one per channel, mutually decorrelated.

    Each channel sweeps ``band`` (Hz) up and down with a continuous instantaneous frequency
    (no phase jumps), at a channel-specific, seeded rate and phase, alternately starting at
    the low and the high edge, so that the channels are not collinear; a cosine taper of relative length ``taper`` at both ends keeps the
    spectrum inside the band.

    Parameters
    ----------
    n_samples : int
    dt : float
        Sampling time [s]; ``band[1]`` must lie below the Nyquist frequency ``1/(2 dt)``.
    n_channels : int
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
    """
    f0, f1 = map(float, band)
    if not (0 <= f0 < f1):
        raise DataError(f"chirp band {band} must satisfy 0 <= f_low < f_high")
    if f1 >= 0.5 / dt:
        raise DataError(f"chirp band upper edge {f1} Hz is above the Nyquist frequency "
                        f"{0.5 / dt:g} Hz for dt={dt}; lower it or sample faster")
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
