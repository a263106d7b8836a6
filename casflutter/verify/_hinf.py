"""Exact H∞ norm and its peak frequency (continuous time).

Two independent implementations of the same Hamiltonian algorithm:

* ``"slycot"``: SLICOT ``AB13DD`` through :func:`slycot.ab13dd` (the routine behind
  :func:`control.linfnorm`);
* ``"scipy"``: the Boyd--Balakrishnan / Bruinsma--Steinbuch iteration written here
  with numpy/scipy only: a lower bound γ_lb is raised to the largest singular value
  at the midpoints between the imaginary-axis eigenvalues of the Hamiltonian H(γ),
  γ = (1 + 2 tol) γ_lb, until H(γ) has none (quadratic convergence).

Used for eq. (16) of Lum et al. (2016), ``‖T_{w̄ zf}‖∞ < γ``.  Shares no code with
:mod:`casflutter.design`.
"""

from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .._format import result_repr
from ..errors import ConfigError, ConvergenceError
from ._common import SystemLike, as_statespace, is_hurwitz, ssdata

__all__ = ["HinfNorm", "hinf_norm", "sigma_max", "slycot_available"]

_METHODS = ("auto", "slycot", "scipy")


@dataclass(frozen=True)
class HinfNorm:
    """The H∞ norm of a continuous-time system.

    Attributes
    ----------
    gamma : float
        ``sup_ω σ_max(G(jω))``; ``inf`` when the system is not internally stable.
    omega_peak : float
        Frequency (rad/s) of the peak; ``inf`` for a peak at infinite frequency
        (``σ_max(D)``), ``nan`` when ``gamma`` is infinite.
    method : str
        ``"slycot"``, ``"scipy"`` or ``"static"`` (0 states), or ``"unstable"``.
    stable : bool
        Whether the state matrix is Hurwitz.
    spectral_abscissa : float
        Largest real part of the poles.
    iterations : int
        Hamiltonian eigenvalue problems solved (scipy branch; 0 otherwise).
    tol : float
        Relative tolerance requested.
    wall_time : float
        Seconds spent.
    """

    __repr__ = result_repr

    gamma: float
    omega_peak: float
    method: str
    stable: bool
    spectral_abscissa: float
    iterations: int = 0
    tol: float = 1e-10
    wall_time: float = 0.0

    def __float__(self) -> float:
        return float(self.gamma)


def slycot_available() -> bool:
    """True when ``slycot.ab13dd`` can be imported now."""
    try:
        module = importlib.import_module("slycot")
    except ImportError:
        return False
    return hasattr(module, "ab13dd")


def sigma_max(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
              omega: float | np.ndarray) -> float | np.ndarray:
    """Largest singular value of ``G(jω) = C (jωI - A)^-1 B + D``.

    ``omega`` may be a scalar or a 1-D array (``inf`` gives ``σ_max(D)``).
    """
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.empty(w.shape)
    n = A.shape[0]
    eye = np.eye(n)
    for i, wi in enumerate(w):
        if np.isinf(wi) or n == 0:
            G = D
        else:
            G = C @ np.linalg.solve(1j * wi * eye - A, B) + D
        out[i] = sla.svdvals(G)[0] if G.size else 0.0
    return out if np.ndim(omega) else float(out[0])


def _hamiltonian(A, B, C, D, gamma):
    """H(γ) of Bruinsma & Steinbuch (1990): jω is an eigenvalue iff γ is a singular
    value of G(jω)."""
    m, p = B.shape[1], C.shape[0]
    R = D.T @ D - gamma**2 * np.eye(m)
    S = D @ D.T - gamma**2 * np.eye(p)
    RinvDtC = np.linalg.solve(R, D.T @ C)
    RinvBt = np.linalg.solve(R, B.T)
    return np.block([
        [A - B @ RinvDtC, -gamma * B @ RinvBt],
        [gamma * C.T @ np.linalg.solve(S, C), -A.T + C.T @ D @ RinvBt],
    ])


def _hinf_scipy(A, B, C, D, tol, max_iter=200, im_tol=1e-5):
    """Bruinsma--Steinbuch iteration; returns (gamma, omega_peak, iterations)."""
    poles = np.linalg.eigvals(A)
    # Starting frequencies: 0, infinity, and every pole's modulus / imaginary part.
    cands = np.unique(np.concatenate([[0.0], np.abs(poles), np.abs(poles.imag)]))
    sig = sigma_max(A, B, C, D, cands)
    k = int(np.argmax(sig))
    gamma_lb, omega_peak = float(sig[k]), float(cands[k])
    sig_inf = sigma_max(A, B, C, D, np.inf)
    if sig_inf > gamma_lb:
        gamma_lb, omega_peak = sig_inf, math.inf
    if gamma_lb == 0.0:
        # G(jω) vanishes at all start points: zero system unless B or C has content.
        if not (np.any(B) and np.any(C)):
            return 0.0, 0.0, 0
        w = np.logspace(-3, 3, 61) * max(1.0, float(np.max(np.abs(poles))))
        sig = sigma_max(A, B, C, D, w)
        k = int(np.argmax(sig))
        gamma_lb, omega_peak = float(sig[k]), float(w[k])
    for it in range(1, max_iter + 1):
        gamma = (1.0 + 2.0 * tol) * gamma_lb
        ev = np.linalg.eigvals(_hamiltonian(A, B, C, D, gamma))
        scale = np.maximum(1.0, np.abs(ev))
        on_axis = np.abs(ev.real) <= im_tol * scale
        omegas = np.unique(np.abs(ev[on_axis].imag))
        if omegas.size == 0:
            return gamma_lb, omega_peak, it
        grid = np.concatenate([[0.0], omegas])
        mids = 0.5 * (grid[:-1] + grid[1:])
        sig = sigma_max(A, B, C, D, mids)
        k = int(np.argmax(sig))
        if sig[k] <= gamma_lb:
            # Only near-axis (spurious) eigenvalues left: no frequency beats γ_lb.
            return gamma_lb, omega_peak, it
        gamma_lb, omega_peak = float(sig[k]), float(mids[k])
    raise ConvergenceError(
        f"H∞ norm (scipy Hamiltonian iteration) did not converge in {max_iter} "
        f"iterations (last lower bound {gamma_lb:.6g}); loosen tol or use method='slycot'",
        result=(gamma_lb, omega_peak))


def _hinf_slycot(A, B, C, D, tol):
    slycot = importlib.import_module("slycot")
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    jobd = "Z" if not np.any(D) else "D"
    try:
        gpeak, fpeak = slycot.ab13dd("C", "I", "S", jobd, n, m, p, A.copy(), np.eye(n),
                                     B.copy(), C.copy(), D.copy(), tol)
    except Exception as exc:  # slycot raises its own SlycotError hierarchy
        raise ConvergenceError(f"slycot ab13dd failed ({exc}); try method='scipy'",
                               result=exc) from exc
    return float(gpeak), float(fpeak)


def hinf_norm(sys: SystemLike, *, method: str = "auto", tol: float = 1e-10) -> HinfNorm:
    """Exact H∞ norm of a continuous-time system and the frequency of its peak.

    Parameters
    ----------
    sys : control.StateSpace, TransferFunction or array_like
        Continuous-time system (a matrix is a static gain).
    method : {"auto", "slycot", "scipy"}
        ``"auto"`` uses slycot when it can be imported, the scipy implementation
        otherwise.
    tol : float
        Relative tolerance on γ (both branches).

    Returns
    -------
    HinfNorm
        ``gamma = inf`` (and ``stable=False``) when the state matrix is not Hurwitz:
        the H∞ norm of an unstable system is infinite, this is reported, not hidden.

    Raises
    ------
    ConfigError
        Unknown ``method``, ``method="slycot"`` without slycot, or a discrete-time system.
    ConvergenceError
        If the scipy iteration does not converge.
    """
    if method not in _METHODS:
        raise ConfigError(f"method={method!r} is not allowed; use one of {_METHODS}")
    if not tol > 0:
        raise ConfigError(f"tol must be positive, got {tol!r}")
    t0 = time.perf_counter()
    sys = as_statespace(sys)
    A, B, C, D = ssdata(sys)
    if A.shape[0] == 0:
        g = float(sla.svdvals(D)[0]) if D.size else 0.0
        return HinfNorm(g, 0.0, "static", True, -math.inf, 0, tol, time.perf_counter() - t0)
    stable, alpha = is_hurwitz(A)
    if not stable:
        return HinfNorm(math.inf, math.nan, "unstable", False, alpha, 0, tol,
                        time.perf_counter() - t0)
    if method == "auto":
        method = "slycot" if slycot_available() else "scipy"
    if method == "slycot":
        if not slycot_available():
            raise ConfigError("method='slycot' but slycot is not installed; "
                              "`pip install slycot` or use method='scipy'")
        g, w = _hinf_slycot(A, B, C, D, tol)
        it = 0
    else:
        g, w, it = _hinf_scipy(A, B, C, D, tol)
    return HinfNorm(g, w, method, True, alpha, it, tol, time.perf_counter() - t0)
