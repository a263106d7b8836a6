"""Shared helpers of the LCO tests: measure a simulated record independently of the
continuation (zero crossings for the frequency, extremes for the amplitude)."""

from __future__ import annotations

import numpy as np


def measure(t, y, periods: int = 8):
    """Amplitude (half peak-to-peak) and frequency of the last ``periods`` cycles of a
    record, from the upward zero crossings of ``y - mean`` (linear interpolation)."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    z = y - np.mean(y[len(y) // 2:])
    idx = np.nonzero((z[:-1] < 0) & (z[1:] >= 0))[0]
    tc = t[idx] - z[idx] * (t[idx + 1] - t[idx]) / (z[idx + 1] - z[idx])
    assert tc.size > periods + 1, "record too short for the requested number of cycles"
    tc = tc[-(periods + 1):]
    freq = periods / (tc[-1] - tc[0])
    sel = t >= tc[0]
    return 0.5 * (y[sel].max() - y[sel].min()), freq
