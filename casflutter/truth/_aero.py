"""Unsteady thin-airfoil aerodynamics shared by the truth simulators.

Theodorsen's strip coefficients (pitch, plunge, trailing-edge flap), with the circulatory
part written as a Wagner convolution in R. T. Jones' two-lag approximation

    phi(s) = 1 - A1 exp(-b1 s) - A2 exp(-b2 s),   s = U t / b,

so that ``C(k) ~= 1 - sum_j A_j i k / (i k + b_j)``.  In state-space form, for a downwash
signal ``g(t)`` (Theodorsen's ``Q``, the 3/4-chord normal velocity) the effective downwash is

    g_eff = (1 - A1 - A2) g + sum_j A_j lam_j z_j,    dz_j/dt = -lam_j z_j + g,

with ``lam_j = b_j U / b`` [1/time] and ``z_j(t0) = 0`` (flow at rest before ``t0``).

Also the accurate sample-based tools used by ``aero_forces``: derivatives of sampled
signals from a quintic interpolating spline, and the exact integration of the lag states
for an input that is a cubic Hermite interpolant of its samples and sampled derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.linalg import expm
from scipy.signal import lfilter

from ..errors import DataError

__all__ = ["JONES_A", "JONES_B", "jones_C", "theodorsen_T", "StripCoefficients",
           "strip_coefficients", "sample_derivatives", "integrate_lags"]

#: Jones' Wagner-function amplitudes A_j.
JONES_A = (0.165, 0.335)
#: Jones' Wagner-function exponents b_j (per semichord travelled).
JONES_B = (0.0455, 0.3)


def jones_C(k: np.ndarray | complex) -> np.ndarray:
    """Jones' rational approximation of Theodorsen's function, ``C(k)``.

    Parameters
    ----------
    k : array_like
        Reduced frequency ``omega b / U`` (may be complex: ``i k`` is replaced by
        ``s b / U`` for a Laplace variable ``s``).

    Returns
    -------
    numpy.ndarray
        ``1 - sum_j A_j i k / (i k + b_j)``.
    """
    ik = 1j * np.asarray(k, dtype=complex)
    return 1.0 - sum(A * ik / (ik + bj) for A, bj in zip(JONES_A, JONES_B))


def theodorsen_T(c: float) -> dict[str, float]:
    """Theodorsen's flap geometry functions ``T1, T4, T7, T8, T10, T11``.

    Parameters
    ----------
    c : float
        Flap hinge position in semichords aft of mid-chord (``-1 < c < 1``).

    Returns
    -------
    dict
        ``{"T1": ..., "T4": ..., "T7": ..., "T8": ..., "T10": ..., "T11": ...}``
        (Theodorsen, NACA Report 496, 1935).
    """
    s = np.sqrt(1.0 - c * c)
    ac = np.arccos(c)
    return {
        "T1": -s * (2.0 + c * c) / 3.0 + c * ac,
        "T4": -ac + c * s,
        "T7": -(0.125 + c * c) * ac + 0.125 * c * s * (7.0 + 2.0 * c * c),
        "T8": -s * (2.0 * c * c + 1.0) / 3.0 + c * ac,
        "T10": s + ac,
        "T11": ac * (1.0 - 2.0 * c) + s * (2.0 - c),
    }


@dataclass(frozen=True)
class StripCoefficients:
    """Coefficients of Theodorsen's strip lift and moment (per unit span).

    With plunge ``h`` (positive down), pitch ``alpha`` (nose up) about the elastic axis and
    flap ``beta`` (trailing edge down), the lift (up) and the moment about the elastic
    axis (nose up) are

        L = Lh2 h'' + La1 alpha' + La2 alpha'' + Lb1 beta' + Lb2 beta'' + Lc Q_eff
        M = Mh2 h'' + Ma1 alpha' + Ma2 alpha'' + Mb0 beta + Mb1 beta' + Mb2 beta''
            + Mc Q_eff
        Q = Qh1 h' + Qa0 alpha + Qa1 alpha' + Qb0 beta + Qb1 beta'

    where ``Q_eff`` is ``Q`` passed through the Wagner (Jones) lag.
    """

    Lh2: float
    La1: float
    La2: float
    Lb1: float
    Lb2: float
    Lc: float
    Mh2: float
    Ma1: float
    Ma2: float
    Mb0: float
    Mb1: float
    Mb2: float
    Mc: float
    Qh1: float
    Qa0: float
    Qa1: float
    Qb0: float
    Qb1: float


def strip_coefficients(rho: float, b: float, U: float, a: float, c: float,
                       lift_slope: float = 2.0 * np.pi) -> StripCoefficients:
    """Theodorsen's strip coefficients (Theodorsen 1935, flap terms included).

    Parameters
    ----------
    rho : float
        Air density.
    b : float
        Semichord.
    U : float
        Airspeed.
    a : float
        Elastic axis, semichords aft of mid-chord.
    c : float
        Flap hinge, semichords aft of mid-chord.
    lift_slope : float, optional
        Lift-curve slope of the circulatory part (``2 pi`` in thin-airfoil theory); the
        circulatory lift and moment are scaled by ``lift_slope / (2 pi)``.

    Returns
    -------
    StripCoefficients
    """
    T = theodorsen_T(c)
    kap = lift_slope / (2.0 * np.pi)
    rb2 = rho * b * b
    pi = np.pi
    return StripCoefficients(
        Lh2=rb2 * pi, La1=rb2 * pi * U, La2=-rb2 * pi * b * a,
        Lb1=-rb2 * U * T["T4"], Lb2=-rb2 * b * T["T1"],
        Lc=2.0 * pi * kap * rho * U * b,
        Mh2=rb2 * pi * a * b,
        Ma1=-rb2 * pi * b * (0.5 - a) * U,
        Ma2=-rb2 * pi * b * b * (0.125 + a * a),
        Mb0=-rb2 * (T["T4"] + T["T10"]) * U * U,
        Mb1=-rb2 * (T["T1"] - T["T8"] - (c - a) * T["T4"] + 0.5 * T["T11"]) * U * b,
        Mb2=rb2 * (T["T7"] + (c - a) * T["T1"]) * b * b,
        Mc=2.0 * pi * kap * rho * U * b * b * (a + 0.5),
        Qh1=1.0, Qa0=U, Qa1=b * (0.5 - a),
        Qb0=U * T["T10"] / pi, Qb1=b * T["T11"] / (2.0 * pi),
    )


def check_timepts(timepts: np.ndarray, rtol: float = 1e-6) -> float:
    """Return the sample time of uniformly spaced, increasing ``timepts``.

    Raises
    ------
    DataError
        If there are fewer than 6 samples, non-finite values, or the spacing is not uniform.
    """
    t = np.asarray(timepts, dtype=float)
    if t.ndim != 1 or t.size < 6:
        raise DataError(f"timepts must be a 1-D array of at least 6 samples, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise DataError("timepts contains NaN or inf")
    d = np.diff(t)
    dt = float(np.mean(d))
    if dt <= 0 or np.max(np.abs(d - dt)) > rtol * max(dt, abs(t[-1])):
        raise DataError("timepts must be increasing and uniformly spaced (resample the record "
                        "onto a uniform grid first)")
    return dt


def sample_derivatives(timepts: np.ndarray, x: np.ndarray, order: int = 2) -> list[np.ndarray]:
    """First ``order`` time derivatives of sampled signals, from a quintic spline.

    The samples are interpolated by a not-a-knot quintic B-spline (``scipy``'s
    ``make_interp_spline(k=5)``), whose derivatives are exact for the interpolant:
    errors are ``O(dt^5)`` (first) and ``O(dt^4)`` (second) for smooth signals away from
    the record ends.

    Parameters
    ----------
    timepts : numpy.ndarray
        Sample times, shape ``(K,)``.
    x : numpy.ndarray
        Samples, shape ``(K,)`` or ``(K, n)``.
    order : int
        Number of derivatives.

    Returns
    -------
    list of numpy.ndarray
        ``[x', x'', ...]`` at ``timepts``, each shaped like ``x``.
    """
    spl = make_interp_spline(np.asarray(timepts, float), np.asarray(x, float), k=5, axis=0)
    return [spl.derivative(m)(timepts) for m in range(1, order + 1)]


def _hermite_weights(lam: float, h: float) -> np.ndarray:
    """Weights of the exact one-step update of ``z' = -lam z + p(t)`` for cubic Hermite ``p``.

    ``z_{k+1} = e z_k + w0 p_k + w1 h p'_k + w2 p_{k+1} + w3 h p'_{k+1}``; returns
    ``[e, w0, w1, w2, w3]``.
    """
    # augmented system: states [z, 1, s, s^2, s^3] with s = t/h, z' = -lam z + sum c_m s^m
    # the integrals I_m = int_0^h exp(-lam (h - t)) s^m dt come from one matrix exponential.
    A = np.zeros((5, 5))
    A[0, 0] = -lam
    A[0, 1:] = 0.0
    for m in range(1, 4):
        A[m + 1, m] = m / h  # d(s^m)/dt = m s^{m-1} / h
    # z row picks up the polynomial states through separate columns, one per monomial
    integrals = np.empty(4)
    for m in range(4):
        Am = A.copy()
        Am[0, 1 + m] = 1.0
        E = expm(Am * h)
        integrals[m] = E[0, 1]  # response to initial state [0, 1, 0, 0, 0]
    I0, I1, I2, I3 = integrals
    e = np.exp(-lam * h)
    # Hermite basis on s in [0, 1]: h00 = 1-3s^2+2s^3, h10 = s-2s^2+s^3, h01 = 3s^2-2s^3,
    # h11 = -s^2+s^3
    return np.array([e, I0 - 3 * I2 + 2 * I3, I1 - 2 * I2 + I3, 3 * I2 - 2 * I3, -I2 + I3])


def integrate_lags(g: np.ndarray, gdot: np.ndarray, dt: float,
                   lams: tuple[float, ...]) -> list[np.ndarray]:
    """Integrate the lag states ``z_j' = -lam_j z_j + g`` from rest, exactly for Hermite ``g``.

    Parameters
    ----------
    g, gdot : numpy.ndarray
        The lag input and its time derivative at uniformly spaced samples, shape ``(K, n)``.
    dt : float
        Sample time.
    lams : tuple of float
        Lag rates ``lam_j > 0`` [1/time].

    Returns
    -------
    list of numpy.ndarray
        ``z_j`` at the samples, each ``(K, n)``, with ``z_j(t0) = 0``.
    """
    out = []
    for lam in lams:
        e, w0, w1, w2, w3 = _hermite_weights(lam, dt)
        drive = np.zeros_like(g)
        drive[1:] = w0 * g[:-1] + w1 * dt * gdot[:-1] + w2 * g[1:] + w3 * dt * gdot[1:]
        out.append(lfilter([1.0], [1.0, -e], drive, axis=0))
    return out
