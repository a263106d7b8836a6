"""The synthesis' own H∞ norm, its peak and the local maxima of σ_max(T(jω)).

Bruinsma & Steinbuch (1990) / Boyd & Balakrishnan (1990): for ``γ > σ_max(D)``, ``γ`` is a
singular value of ``T(jω) = C (jωI − A)⁻¹ B + D`` iff ``jω`` is an eigenvalue of the
Hamiltonian ``H(γ)`` (here the extended pencil of :func:`_level_pencil`).  Starting from a
lower bound taken at the poles' frequencies, the level is raised to the local maximum of
σ_max in the band between imaginary eigenvalues where σ_max is largest, until the pencil at
``(1 + 2 tol) γ`` has none: quadratic convergence to the norm, with the peak frequency.  From
30 states on, the band's maximum is found by a bounded 1-D search on the modal form (a few
``O(n (m + p))`` evaluations), which saves most of the eigenvalue problems of the
``2n``-dimensional Hamiltonian, the cost of the whole iteration: usually one, to confirm the
bound, instead of two or three with the band's best midpoint (which smaller systems keep).  The same level-set eigenvalues give every frequency
band in which ``σ_max > level``; a bounded 1-D maximisation in each band gives the *active
frequencies* of the nonsmooth local model (Apkarian & Noll 2006).

This is deliberately a different algorithm from the verification layer's (SLICOT AB13DD):
the optimiser's accept test and the independent check share no code.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.optimize import minimize_scalar

__all__ = ["hinf_norm", "sigma_max", "level_crossings", "active_frequencies"]

#: states from which the level iteration refines its best point to the band's local maximum
#: (measured: the eigenvalues of a 2n Hamiltonian cost as much as the search at n ≈ 30)
_REFINE_FROM = 30


def _tf(A, B, C, D, omega: np.ndarray) -> np.ndarray:
    """``T(jω)`` for every ω (batched solve)."""
    n = A.shape[0]
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if n == 0:
        return np.broadcast_to(D.astype(complex), (omega.size,) + D.shape).copy()
    M = 1j * omega[:, None, None] * np.eye(n)[None] - A[None]
    X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (omega.size,) + B.shape))
    return C[None] @ X + D[None]


class _Evaluator:
    """σ_max(T(jω)) of one system at many frequencies.

    With a well-conditioned eigenvector matrix ``A = V Λ V⁻¹`` each frequency costs
    ``O(n (m + p))`` (``T = (CV) diag(1/(jω − λ)) (V⁻¹B) + D``); otherwise one LU solve per
    frequency.  The modal form is used only to *locate* peaks; values that decide anything
    are recomputed by :func:`sigma_max` (solves)."""

    def __init__(self, A, B, C, D):
        self.sys = (A, B, C, D)
        self.modal = None
        self.poles = None           # the eigenvalues of A (None where the solver failed)
        n = A.shape[0]
        if n:
            try:
                lam, V = np.linalg.eig(A)
            except np.linalg.LinAlgError:
                return
            self.poles = lam
            if np.linalg.cond(V) < 1e6:
                self.modal = (lam, C @ V, np.linalg.solve(V, B))

    def __call__(self, omega) -> np.ndarray:
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        if self.modal is None:
            return sigma_max(*self.sys, omega)
        lam, CV, VB = self.modal
        D = self.sys[3]
        T = (CV[None] * (1.0 / (1j * omega[:, None] - lam[None, :]))[:, None, :]) @ VB + D
        return np.linalg.svd(T, compute_uv=False)[:, 0]


def sigma_max(A, B, C, D, omega) -> np.ndarray:
    """Largest singular value of ``T(jω)`` at each ω (``inf`` where ``jωI − A`` is singular)."""
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    try:
        return np.linalg.svd(_tf(A, B, C, D, omega), compute_uv=False)[:, 0]
    except np.linalg.LinAlgError:
        out = np.empty(omega.size)
        for i, w in enumerate(omega):
            try:
                out[i] = np.linalg.svd(_tf(A, B, C, D, [w])[0], compute_uv=False)[0]
            except np.linalg.LinAlgError:
                out[i] = np.inf
        return out


def _hamiltonian(A, B, C, D, g: float) -> np.ndarray:
    """Hamiltonian ``H(g)`` (Bruinsma & Steinbuch) for ``g > σ_max(D)``."""
    m, p = B.shape[1], C.shape[0]
    R = D.T @ D - g * g * np.eye(m)
    S = D @ D.T - g * g * np.eye(p)
    RiDt = np.linalg.solve(R, D.T)
    RiBt = np.linalg.solve(R, B.T)
    H11 = A - B @ RiDt @ C
    return np.block([[H11, -g * B @ RiBt], [g * C.T @ np.linalg.solve(S, C),
                                             -A.T + C.T @ D @ RiBt]])


def _level_pencil(A, B, C, D, g: float) -> tuple[np.ndarray, np.ndarray]:
    """Extended Hamiltonian pencil ``λN − M`` whose finite eigenvalues ``jω`` are the
    frequencies where ``g`` is a singular value of ``T(jω)``: with ``x = (jωI − A)⁻¹Bu`` and
    ``p = (−jωI − Aᵀ)⁻¹Cᵀy``, ``T u = g y`` and ``Tᴴ y = g u`` read ``M z = λ N z`` for
    ``z = (x, p, u, y)``.  No inverse of ``DᵀD − g²I`` is formed, so the pencil stays well
    conditioned when ``g`` approaches ``σ_max(D)``."""
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    Z = np.zeros
    M = np.block([[A, Z((n, n)), B, Z((n, p))],
                  [Z((n, n)), -A.T, Z((n, m)), -C.T],
                  [C, Z((p, n)), D, -g * np.eye(p)],
                  [Z((m, n)), B.T, -g * np.eye(m), D.T]])
    N = np.zeros_like(M)
    N[:2 * n, :2 * n] = np.eye(2 * n)
    return M, N


def level_crossings(A, B, C, D, level: float, im_tol: float = 1e-2) -> np.ndarray:
    """Frequencies ``ω >= 0`` at which some singular value of ``T(jω)`` may equal ``level``
    (the imaginary eigenvalues of the Hamiltonian pencil), sorted; ``level > σ_max(D)``.

    The test for "imaginary" is loose on purpose (``|Re λ| <= im_tol |λ|``): a spurious
    frequency only costs one more evaluation of σ_max in the callers, whereas a crossing
    missed through rounding would end the level iteration below the norm."""
    sD = float(np.linalg.norm(D, 2)) if D.size else 0.0
    ev = None
    if level > 1.05 * sD:
        try:
            with np.errstate(all="ignore"):
                H = _hamiltonian(A, B, C, D, level)
        except np.linalg.LinAlgError:       # DᵀD − level²I singular in floating point
            H = None
        if H is not None and np.all(np.isfinite(H)):
            ev = np.linalg.eigvals(H)
    if ev is None:
        # close to σ_max(D) the Hamiltonian is ill-conditioned, and with entries far from one
        # its products overflow: the pencil holds the plant's own entries, no inverse
        M, N = _level_pencil(A, B, C, D, level)
        with np.errstate(divide="ignore", invalid="ignore"):
            ev = sla.eigvals(M, N)
        big = 1e8 * max(1.0, float(np.max(np.abs(M))))
        ev = ev[np.isfinite(ev) & (np.abs(ev) < big)]
    scale = max(1.0, float(np.max(np.abs(ev), initial=0.0)))
    imag = ev[np.abs(ev.real) <= im_tol * np.maximum(np.abs(ev), 1e-6 * scale)]
    w = np.abs(imag.imag)
    return np.unique(np.round(w[w >= 0], 14))


def hinf_norm(A, B, C, D, *, tol: float = 1e-9, max_iter: int = 60) -> tuple[float, float]:
    """H∞ norm and peak frequency of a stable ``(A, B, C, D)`` (Hamiltonian level iteration).

    Parameters
    ----------
    A, B, C, D : ndarray
        Continuous-time state-space matrices; ``A`` must be Hurwitz.
    tol : float
        Relative accuracy: the true norm lies in ``[γ, (1 + 2 tol) γ]``.
    max_iter : int
        Maximum number of level iterations.

    Returns
    -------
    gamma : float
        The norm (``inf`` when ``A`` is not Hurwitz or an entry is not finite).
    omega : float
        Peak frequency in rad/s (``inf`` when the peak is the feedthrough ``σ_max(D)``).

    Raises
    ------
    numpy.linalg.LinAlgError
        When no eigenvalue or singular value solver converges on the system (the synthesis
        records such a start as failed).
    """
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    if not all(np.all(np.isfinite(M)) for M in (A, B, C, D)):
        return np.inf, np.nan      # a loop whose entries overflowed has no finite norm
    n = A.shape[0]
    sD = float(np.linalg.norm(D, 2)) if D.size else 0.0
    if n == 0:
        return sD, np.inf
    ev_ = _Evaluator(A, B, C, D)
    poles = np.linalg.eigvals(A) if ev_.poles is None else ev_.poles
    if np.max(poles.real) >= 0:
        return np.inf, np.nan
    # initial lower bound: ω = 0, the pole frequencies and the most resonant pole, the best of
    # them refined to the local maximum between its neighbours
    mags = np.abs(poles)
    lo, hi = float(np.min(mags)), float(np.max(mags))
    grid = np.geomspace(max(0.1 * lo, 1e-9 * hi, 1e-300), 10.0 * hi, 40) if hi > 0 else []
    cand = np.concatenate([[0.0], np.abs(poles.imag), mags, grid])
    cand = np.unique(cand[np.isfinite(cand)])
    lb, wpk = _best_of(A, B, C, D, ev_, cand, cand)
    if sD >= lb:
        lb, wpk = sD, np.inf
    if lb == 0.0:
        return 0.0, 0.0
    if not np.isfinite(lb):
        return np.inf, wpk         # a pole so close to the axis that σ_max overflows
    for _ in range(max_iter):
        g = lb * (1.0 + 2.0 * tol)
        w = level_crossings(A, B, C, D, g)
        if w.size == 0:
            break
        edges = np.concatenate([w, [2.0 * w[-1] + 1.0]]) if w.size == 1 else w
        mids = 0.5 * (edges[:-1] + edges[1:])
        mids = np.concatenate([mids, np.sqrt(edges[:-1] * edges[1:]), w])
        mids = mids[np.isfinite(mids)]
        s, wj = _best_of(A, B, C, D, ev_, mids, edges)
        if not np.isfinite(s):
            return np.inf, wj
        if not s > lb * (1.0 + tol):
            break          # crossings found but no higher value between them: converged
        lb, wpk = s, wj
    return lb, wpk


def _best_of(A, B, C, D, ev: _Evaluator, points: np.ndarray, edges: np.ndarray
             ) -> tuple[float, float]:
    """``(σ_max, ω)`` at the local maximum of σ_max next to the best of ``points``: the
    bounded search between the nearest ``edges`` on either side of it (exact values:
    :func:`sigma_max`); ``inf`` at a point where σ_max overflows.  Below ``_REFINE_FROM``
    states the best point itself: there one more level iteration costs less than the
    search."""
    j = int(np.argmax(ev(points)))
    w0 = float(points[j])
    s0 = float(sigma_max(A, B, C, D, [w0])[0])
    if not np.isfinite(s0):
        return np.inf, w0
    if A.shape[0] < _REFINE_FROM:
        return s0, w0
    below, above = edges[edges < w0], edges[edges > w0]
    a = float(below.max()) if below.size else 0.0
    b = float(above.min()) if above.size else 2.0 * w0 + 1.0
    w, s = _refine_peak(A, B, C, D, a, b, w0, ev=ev)
    return (s, w) if s > s0 else (s0, w0)


def _refine_peak(A, B, C, D, a: float, b: float, w0: float, xatol: float = 1e-6,
                 ev: _Evaluator | None = None) -> tuple[float, float]:
    """Local maximum of σ_max on ``[a, b]`` (bounded scalar search on log ω, on ``ev``: the
    system's :class:`_Evaluator`, made here when not given)."""
    lo, hi = max(a, 1e-12 * max(b, 1.0)), max(b, a * (1 + 1e-12))
    if hi <= lo * (1 + 1e-10):
        s = float(sigma_max(A, B, C, D, [w0])[0])
        return w0, s
    ev = _Evaluator(A, B, C, D) if ev is None else ev
    f = lambda x: -float(ev([np.exp(x)])[0])  # noqa: E731
    r = minimize_scalar(f, bounds=(np.log(lo), np.log(hi)), method="bounded",
                        options={"xatol": xatol})
    w = float(np.exp(r.x))
    s = float(sigma_max(A, B, C, D, [w])[0])
    s0 = float(sigma_max(A, B, C, D, [w0])[0])
    return (w, s) if s >= s0 else (w0, s0)


def active_frequencies(A, B, C, D, gamma: float, omega_peak: float, *, ratio: float = 0.6,
                       max_count: int = 8) -> list[tuple[float, float]]:
    """Local maxima of ``σ_max(T(jω))`` above ``ratio * gamma``: ``[(ω, σ), ...]`` by
    decreasing σ, the exact peak first; ``ω = inf`` stands for the feed-through ``σ_max(D)``
    when the norm is the feed-through (otherwise that piece would have no cut at all).

    The bands where ``σ_max > ratio γ`` are delimited by the imaginary eigenvalues of the
    Hamiltonian at that level; one local maximum is located in each band.
    """
    out: list[tuple[float, float]] = []
    n = A.shape[0]
    sD = float(np.linalg.norm(D, 2)) if D.size else 0.0
    level = ratio * gamma
    if np.isfinite(omega_peak):
        out.append((float(omega_peak), float(gamma)))
    else:
        # the norm is the feed-through: its piece (ω = ∞) is the active one, and the local
        # maxima above the feed-through level are the others
        out.append((np.inf, sD))
        level = max(level, sD * (1 + 1e-6))
        if n == 0 or level >= gamma:
            return out
    if n == 0 or level <= sD * (1 + 1e-9):
        return out
    w = level_crossings(A, B, C, D, level)
    if w.size == 0:
        return out
    edges = np.concatenate([[0.0], w, [max(10.0 * w[-1], 1.0)]])
    mids = 0.5 * (edges[:-1] + edges[1:])
    sv = sigma_max(A, B, C, D, mids)
    bands = [(edges[i], edges[i + 1], mids[i], sv[i]) for i in range(mids.size)
             if sv[i] > level]
    bands.sort(key=lambda b: -b[3])
    ev = _Evaluator(A, B, C, D)
    for a, b, m, _ in bands[:max_count]:
        if np.isfinite(omega_peak) and a <= omega_peak <= b:
            continue
        wl, sl = _refine_peak(A, B, C, D, a, b, m, ev=ev)
        if sl > level:
            out.append((wl, sl))
    out.sort(key=lambda x: -x[1])
    return out[:max_count]
