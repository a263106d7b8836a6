"""Analysis of a response record: decay, limit-cycle oscillation (LCO) or divergence.

From the envelope (half swings maximum → minimum, see :func:`envelope_growth_rate`) of
the last ``window`` fraction of the record the growth rate σ is the slope of log-envelope
against time; with ``r = σ T_window``, ``r < −tol`` is a decay, ``r > tol`` a divergence,
otherwise an LCO.  A non-finite or blown-up record is a divergence; a record that has fallen
below ``floor`` is a decay.  LCO amplitudes are half the peak-to-peak value over the window,
per channel; the fundamental frequency is the FFT peak (Hann window) refined by parabolic
interpolation of the log magnitude (paper Fig. 9).  The same analysis serves the ROM loop
(:func:`casflutter.aeroelastic.simulate_loop`) and the truth simulators.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

from .._format import result_repr
from ..errors import ConfigError

__all__ = ["ResponseAnalysis", "analyze_response", "envelope_growth_rate", "dominant_frequency"]


@dataclass(frozen=True)
class ResponseAnalysis:
    """Decay / LCO / divergence classification of a record (see module docstring).

    Attributes
    ----------
    kind : str
        ``"decay"``, ``"lco"`` or ``"divergence"``.
    growth_rate : float
        Envelope growth rate σ [1/s] of the dominant channel over the window.
    amplitude : ndarray
        Half peak-to-peak amplitude per channel over the window.
    frequency_hz : float
        Fundamental frequency [Hz] of the dominant channel (FFT peak, parabolic
        interpolation); ``nan`` when the window holds too few samples.
    omega : float
        ``2π frequency_hz`` [rad/s].
    dominant : int
        Channel with the largest window amplitude.
    spectrum_freq_hz, spectrum : ndarray
        One-sided amplitude spectrum of the dominant channel over the window.
    window : tuple of float
        Start and end time of the analysed window.
    """

    __repr__ = result_repr

    kind: str
    growth_rate: float
    amplitude: np.ndarray
    frequency_hz: float
    omega: float
    dominant: int
    spectrum_freq_hz: np.ndarray
    spectrum: np.ndarray
    window: tuple


def envelope_growth_rate(timepts, x) -> float:
    """Growth rate σ [1/s] of the envelope of a scalar record.

    The envelope is half the swing from each local maximum to the next local minimum
    (insensitive to a static offset), placed at the mid time; σ is the slope of its
    logarithm.  Falls back on a fit of log|x| when fewer than three swings exist
    (non-oscillatory records).

    Parameters
    ----------
    timepts : array_like, shape (n,)
        Sample times.
    x : array_like, shape (n,)
        The record.

    Returns
    -------
    float
        σ (``-inf`` for a record at rest).
    """
    t, x = np.asarray(timepts, dtype=float), np.asarray(x, dtype=float)
    mx, _ = find_peaks(x)
    mn, _ = find_peaks(-x)
    if mx.size >= 3 and mn.size >= 3:
        j = np.searchsorted(mn, mx)
        ok = j < mn.size
        i_max, i_min = mx[ok], mn[j[ok]]
        half = 0.5 * (x[i_max] - x[i_min])
        keep = half > 0
        if keep.sum() >= 3:
            tt = 0.5 * (t[i_max] + t[i_min])[keep]
            return float(np.polyfit(tt, np.log(half[keep]), 1)[0])
    a = np.abs(x)
    keep = a > 0
    if keep.sum() < 2:
        return -np.inf
    return float(np.polyfit(t[keep], np.log(a[keep]), 1)[0])


def dominant_frequency(timepts, x) -> tuple[float, np.ndarray, np.ndarray]:
    """Fundamental frequency [Hz] of a uniformly sampled record by FFT peak.

    The record is de-meaned and Hann-windowed; the peak bin is refined by parabolic
    interpolation of the log magnitude.

    Parameters
    ----------
    timepts : array_like, shape (n,)
        Uniform sample times.
    x : array_like, shape (n,)
        The record.

    Returns
    -------
    f_hz : float
        The fundamental frequency (``nan`` for fewer than 8 samples).
    freq_hz, amplitude_spectrum : ndarray
        The one-sided amplitude spectrum.
    """
    t, x = np.asarray(timepts, dtype=float), np.asarray(x, dtype=float)
    n = x.size
    if n < 8:
        return float("nan"), np.zeros(0), np.zeros(0)
    dt = (t[-1] - t[0]) / (n - 1)
    win = np.hanning(n)
    X = np.abs(np.fft.rfft((x - x.mean()) * win)) * 2.0 / win.sum()
    f = np.fft.rfftfreq(n, dt)
    k = int(np.argmax(X[1:]) + 1)
    if 1 <= k < X.size - 1 and np.all(X[k - 1:k + 2] > 0):
        a, b, c = np.log(X[k - 1:k + 2])
        den = a - 2 * b + c
        p = 0.5 * (a - c) / den if den != 0 else 0.0
    else:
        p = 0.0
    return float((k + p) * f[1]), f, X


def analyze_response(timepts, X, *, window: float = 0.3, tol: float = 0.05,
                     floor: float = 1e-12, blowup: float = np.inf) -> ResponseAnalysis:
    """Classify a record as decay / LCO / divergence and measure its LCO (module docstring).

    Parameters
    ----------
    timepts : array_like (n,)
        Sample times.
    X : array_like (n,) or (n, channels)
        The record, one column per channel.
    window : float
        Fraction (0, 1] of the record, at its end, that is analysed.
    tol : float
        Allowed relative envelope change ``|σ T_window|`` of an LCO.
    floor : float
        A window amplitude below this is a decay.
    blowup : float
        An amplitude above this (or non-finite) is a divergence.

    Returns
    -------
    ResponseAnalysis

    See Also
    --------
    truth_lco : the truth's own response at a speed, classified by this function.
    simulate_loop : the ROM loop's response.

    Examples
    --------
    >>> import numpy as np
    >>> import casflutter as cf
    >>> t = np.arange(0.0, 60.0, 0.01)
    >>> lco = cf.analyze_response(t, 0.3 * np.sin(2 * np.pi * 1.5 * t)[:, None])
    >>> lco.kind, round(lco.frequency_hz, 2), round(float(lco.amplitude[0]), 2)
    ('lco', 1.5, 0.3)
    """
    t = np.asarray(timepts, dtype=float)
    X = np.asarray(X, dtype=float)
    X = X[:, None] if X.ndim == 1 else X
    if not 0 < window <= 1:
        raise ConfigError(f"window must be a fraction in (0, 1], got {window}")
    finite = np.all(np.isfinite(X), axis=1)
    n_ok = int(np.argmin(finite)) if not finite.all() else t.size
    t, X = t[:n_ok], X[:n_ok]
    i0 = int(np.floor((1 - window) * t.size))
    tw, Xw = t[i0:], X[i0:]
    amp = 0.5 * (Xw.max(axis=0) - Xw.min(axis=0)) if tw.size else np.full(X.shape[1], np.nan)
    dom = int(np.argmax(amp)) if tw.size else 0
    blown = n_ok < finite.size or (tw.size and np.max(np.abs(Xw)) > blowup)
    sigma = envelope_growth_rate(tw, Xw[:, dom]) if tw.size >= 2 else np.nan
    fhz, ff, XX = dominant_frequency(tw, Xw[:, dom]) if tw.size else (np.nan, np.zeros(0), np.zeros(0))
    T = tw[-1] - tw[0] if tw.size >= 2 else 0.0
    if blown:
        kind = "divergence"
    elif not np.isfinite(sigma) or np.max(amp) < floor or sigma * T < -tol:
        kind = "decay"
    elif sigma * T > tol:
        kind = "divergence"
    else:
        kind = "lco"
    return ResponseAnalysis(kind, float(sigma), amp, fhz, 2 * np.pi * fhz, dom, ff, XX,
                            (float(tw[0]) if tw.size else np.nan, float(tw[-1]) if tw.size else np.nan))
