"""Scaled plant sets, exact evaluation and the local (cutting-plane) models of a static gain.

Helpers of :mod:`._synthesis` (paper §III.C).  Every plant is balanced (diagonal state
similarity), its inputs/outputs scaled and its time axis scaled so that the closed-loop
frequencies of interest are of order one; the controller is optimised as the static gain
``Kbar`` on the plants augmented with its states (:meth:`Partition.augmented`) and unscaled
at the end.

Local models (Apkarian & Noll 2006; Burke, Lewis & Overton's HIFOO for the spectral
abscissa): a *cut* is one smooth piece of a nonsmooth function with its value and exact
gradient with respect to ``Kbar``,

* ``σ_i(T(jω; K))`` at an active frequency ω: ``dσ = Re(uᴴ F dK~ G v)`` with
  ``F = D12 + Ccl R B2``, ``G = C2 R Bcl + D21``, ``R = (jωI − Acl)⁻¹``;
* ``Re λ(Acl(K))``: ``dλ = yᴴ B2 dK~ C2 x / (yᴴ x)`` with the left/right eigenvectors;
* ``det(I − Kbar D22)`` for the well-posedness of a loop with feed-through;

and ``dK~ = L dKbar R`` carries them to ``Kbar``.  Everything is numpy/scipy on the plant
state dimension; the optimisation itself only sees values and gradients.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Sequence

import control
import numpy as np
import scipy.linalg as sla

from ._norm import _refine_peak, active_frequencies, hinf_norm
from ._plant import Partition, partition, spectral_abscissa

__all__ = ["verify_closed_loop"]


def _balance(P: Partition) -> np.ndarray:
    """Diagonal similarity that balances ``A`` (LAPACK gebal, no permutation)."""
    if P.nx == 0:
        return np.eye(0)
    _, T = sla.matrix_balance(P.A, permute=False)
    return T


def _io_scales(parts: Sequence[Partition]) -> tuple[np.ndarray, np.ndarray]:
    """Input and output scales that make the control-to-measurement gain ``G22`` of order one.

    ``|G22_ij(jω)|`` is sampled on a log grid spanning the plants' pole moduli; its median
    per entry ``M_ij`` (over frequencies and plants) is balanced in the log domain,
    ``r_i M_ij c_j ≈ 1``, giving ``u = su u~`` with ``su = c`` and ``y~ = y / sy`` with
    ``sy = 1 / r``.  A static gain of order one on the scaled plant then has an effect of order
    one on the loop, whatever the physical units of the sensors and actuators.
    """
    nu, ny = parts[0].B2.shape[1], parts[0].C2.shape[0]
    samples = []
    for P in parts:
        if P.nx == 0:
            samples.append(np.abs(P.D22)[None])
            continue
        mags = np.abs(np.linalg.eigvals(P.A))
        big = float(np.max(mags, initial=0.0))
        small = mags[mags > 1e-9 * max(big, 1e-300)]
        lo, hi = (float(np.min(small)), big) if small.size else (1.0, 1.0)
        w = np.geomspace(0.5 * lo, 2.0 * hi, 24)
        n = P.nx
        M = 1j * w[:, None, None] * np.eye(n)[None] - P.A[None]
        try:
            X = np.linalg.solve(M, np.broadcast_to(P.B2.astype(complex), (w.size,) + P.B2.shape))
        except np.linalg.LinAlgError:
            continue
        G = np.abs(P.C2[None] @ X + P.D22[None])
        # an entry with no path from its control to its measurement (from the sparsity, or
        # at the rounding level of the solve at every frequency) is a zero, whatever
        # rounding leaves in it: scaled to one it would make that measurement's gains
        # astronomically large
        samples.append(np.where(_paths(P) & _above_rounding(P, w), G, 0.0))
    if not samples:
        return np.ones(nu), np.ones(ny)
    S = np.concatenate(samples, axis=0)
    S = np.where(np.isfinite(S) & (S > 0), S, np.nan)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)      # entries never reached by u
        Mlog = np.log(np.nanmedian(S, axis=0))
    ok = np.isfinite(Mlog)
    if not np.any(ok):
        return np.ones(nu), np.ones(ny)
    Mlog = np.where(ok, Mlog, np.nan)
    lr, lc = np.zeros(ny), np.zeros(nu)
    for _ in range(50):
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            lr = -np.nan_to_num(np.nanmean(Mlog + lc[None, :], axis=1))
            lc = -np.nan_to_num(np.nanmean(Mlog + lr[:, None], axis=0))
    su = np.exp(np.clip(lc, -200, 200))
    sy = np.exp(np.clip(-lr, -200, 200))
    return su, sy


def _above_rounding(P: Partition, w: np.ndarray) -> np.ndarray:
    """``(ny, nu)``: whether ``|G22_ij(jω)|`` rises above the rounding level of its solve,
    ``1e3 eps |C2_i| |X_j|``, at one frequency of ``w`` at least (computed in the balanced
    realisation, where rounding is even over the states)."""
    t = np.diag(_balance(P))
    Ab = P.A / t[:, None] * t[None, :]
    B2b, C2b = P.B2 / t[:, None], P.C2 * t[None, :]
    M = 1j * w[:, None, None] * np.eye(P.nx)[None] - Ab[None]
    try:
        X = np.linalg.solve(M, np.broadcast_to(B2b.astype(complex), (w.size,) + B2b.shape))
    except np.linalg.LinAlgError:
        return np.ones(P.D22.shape, bool)
    G = np.abs(C2b[None] @ X + P.D22[None])
    floor = 1e3 * np.finfo(float).eps * (
        np.linalg.norm(C2b, axis=1)[None, :, None] * np.linalg.norm(X, axis=1)[:, None, :]
        + np.abs(P.D22)[None])
    return np.any(G > floor, axis=0)


def _paths(P: Partition) -> np.ndarray:
    """``(ny, nu)``: whether measurement ``i`` depends on control ``j`` at all, from the
    sparsity of ``(A, B2, C2, D22)`` (a path through the states' graph, or ``D22_ij != 0``)."""
    step = (P.A != 0).astype(int)
    reached = (P.B2 != 0).astype(int)            # states that control j drives, so far
    for _ in range(P.nx):
        grown = ((reached + step @ reached) > 0).astype(int)
        if np.array_equal(grown, reached):
            break
        reached = grown
    return ((P.C2 != 0).astype(int) @ reached > 0) | (P.D22 != 0)


def _time_scale(parts: Sequence[Partition]) -> float:
    """Geometric mean of the smallest and largest non-zero pole moduli (1 when none)."""
    mags = np.concatenate([np.abs(np.linalg.eigvals(P.A)) for P in parts if P.nx] + [[]])
    big = float(np.max(mags, initial=0.0))
    if big == 0.0:
        return 1.0
    small = mags[mags > 1e-9 * big]
    return float(np.sqrt(np.min(small) * big))


_KAPPA_MAX = 1e8
"""Eigenvalue condition number above which a Re λ cut is not extrapolated linearly."""


@dataclass
class Cut:
    """One smooth piece: value, gradient w.r.t. vec(Kbar) (column-major) and an identity
    used to re-evaluate it at another gain (``("sigma", j, ω, i)`` or ``("eig", j, λ)``)."""

    value: float
    grad: np.ndarray
    key: tuple
    linear: bool = True
    """False for a nearly defective eigenvalue, whose gradient does not predict its motion
    over a finite step: its reach within a trust region is taken as its value alone."""

    def reach(self, delta: float) -> float:
        """Largest value the linear model reaches within the box trust region ``delta``."""
        if not self.linear:
            return self.value
        return self.value + delta * float(np.sum(np.abs(self.grad)))


def _cluster_samples(r: int) -> list[np.ndarray]:
    """Unit vectors of C^r: the axes, then every pair of axes with the phases 1, j, −1, −j."""
    out = [np.eye(r, dtype=complex)[i] for i in range(r)]
    for i in range(r):
        for k in range(i + 1, r):
            for ph in (1, 1j, -1, -1j):
                a = np.zeros(r, complex)
                a[i], a[k] = 1 / np.sqrt(2), ph / np.sqrt(2)
                out.append(a)
    return out


def _abscissa(P: Partition, K: np.ndarray) -> float:
    """Spectral abscissa of ``P`` closed by the static ``K``; ``inf`` when the loop is
    singular (``I − K D22``), has non-finite entries, or its eigenvalues do not converge."""
    try:
        A = P.closed_loop(K)[0]
        return spectral_abscissa(A) if np.all(np.isfinite(A)) else np.inf
    except np.linalg.LinAlgError:
        return np.inf


def _eig_lr(A: np.ndarray):
    w, vl, vr = sla.eig(A, left=True, right=True)
    return w, vl, vr


class Problem:
    """Scaled, augmented plant set with exact evaluation and cuts of a static gain.

    Parameters
    ----------
    parts : sequence of Partition
        The H∞ plants (the objective is the worst-case norm over them).
    stab_parts : sequence of Partition
        Plants that must only be stable with decay rate ``decay`` (e.g. ΣAE at many speeds).
    order : int
        Controller order.
    decay : float
        Required decay rate of the stability plants (rad/s, unscaled).
    min_det : float
        Lower bound on ``det(I − Kbar D22)`` over all plants with a feed-through.
    """

    def __init__(self, parts: Sequence[Partition], stab_parts: Sequence[Partition],
                 order: int, decay: float = 0.0, min_det: float = 0.2):
        self.order = order
        allp = list(parts) + list(stab_parts)
        self.su, self.sy = _io_scales(allp)
        self.w0 = _time_scale(allp)
        tr = [P.transformed(_balance(P), self.su, self.sy, self.w0) for P in allp]
        self.aug = [P.augmented(order) for P in tr[:len(parts)]]
        self.stab = [P.augmented(order) for P in tr[len(parts):]]
        self.nu, self.ny = parts[0].B2.shape[1], parts[0].C2.shape[0]
        self.shape = (self.nu + order, self.ny + order)
        self.n = self.shape[0] * self.shape[1]
        self.decay = float(decay) / self.w0
        self.min_det = float(min_det)
        self.d22 = [P for P in self.aug + self.stab if P.has_d22]

    # ------------------------------------------------------------------ exact evaluation
    def vec(self, K: np.ndarray) -> np.ndarray:
        return K.ravel(order="F")

    def mat(self, x: np.ndarray) -> np.ndarray:
        return x.reshape(self.shape, order="F")

    def dets(self, K: np.ndarray) -> np.ndarray:
        return np.array([P.well_posedness(K) for P in self.d22])

    def well_posed(self, K: np.ndarray) -> bool:
        return bool(np.all(self.dets(K) >= self.min_det * (1.0 - 1e-6)))

    def alphas(self, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Spectral abscissae of the H∞ plants and of the stability plants (scaled time);
        ``inf`` for a loop that cannot be closed or whose entries overflowed."""
        a = np.array([_abscissa(P, K) for P in self.aug])
        b = np.array([_abscissa(P, K) for P in self.stab])
        return a, b

    def stab_objective(self, K: np.ndarray, margin: float) -> float:
        """``max(α_j + margin, α_l + decay, min_det − det_i)``: negative once every
        requirement holds (decay rates and well-posedness with margin)."""
        dets = self.dets(K)
        if np.any(np.abs(dets) < 1e-12):
            return np.inf
        try:
            a, b = self.alphas(K)
        except np.linalg.LinAlgError:
            return np.inf
        return float(max(np.max(a + margin, initial=-np.inf),
                         np.max(b + self.decay, initial=-np.inf),
                         np.max(self.min_det * (1.0 - 1e-6) - dets, initial=-np.inf)))

    def feasible(self, K: np.ndarray) -> bool:
        """Well posed, and the stability plants decay at the required rate."""
        if not self.well_posed(K):
            return False
        return all(_abscissa(P, K) <= -self.decay for P in self.stab)

    def gamma(self, K: np.ndarray) -> tuple[float, list[float], list[float]]:
        """Worst-case exact γ, per-plant γ and peak frequencies (γ = inf if unstable)."""
        gams, peaks = [], []
        for P in self.aug:
            try:
                g, w = hinf_norm(*P.closed_loop(K))
            except np.linalg.LinAlgError:    # a singular loop, or no solver converged on it
                g, w = np.inf, np.nan
            if not np.isfinite(g):
                return np.inf, [], []
            gams.append(g)
            peaks.append(w)
        return max(gams), gams, peaks

    # ------------------------------------------------------------------ cuts
    def sigma_cuts(self, K: np.ndarray, j: int, omegas: Sequence[float], floor: float,
                   rel: float = 0.9) -> list[Cut]:
        """σ_i(T_j(jω)) cuts at the given frequencies (the singular values above
        ``max(floor, rel σ_1)``, at most three per frequency)."""
        P = self.aug[j]
        Kt, L, R = P.loop_gain(K)
        A = P.A + P.B2 @ Kt @ P.C2
        Bc = P.B1 + P.B2 @ Kt @ P.D21
        Cc = P.C1 + P.D12 @ Kt @ P.C2
        Dc = P.D11 + P.D12 @ Kt @ P.D21
        n, nw = A.shape[0], Bc.shape[1]
        out = []
        for w in omegas:
            if not np.isfinite(w):
                X = np.zeros((n, nw + P.B2.shape[1]), complex)
            else:
                X = np.linalg.solve(1j * w * np.eye(n) - A, np.hstack([Bc, P.B2]))
            T = Cc @ X[:, :nw] + Dc
            F = P.D12 + Cc @ X[:, nw:]
            G = P.C2 @ X[:, :nw] + P.D21
            U, s, Vh = np.linalg.svd(T)
            r = 1
            while r < min(3, s.size) and s[r] >= max(floor, rel * s[0]):
                r += 1
            # near-coalescing singular values: σ_max(T + dT) >= Re(uᴴ(T + dT)v) for every unit
            # pair u = U_r a, v = V_r a, exact to first order for the best a; a polyhedral
            # inner model of λ_max over the cluster from the axes and their phased pairs
            for a in _cluster_samples(r):
                u = U[:, :r] @ a
                v = Vh[:r].conj().T @ a
                val = float(np.real(u.conj() @ T @ v))
                ga = u.conj() @ F
                gb = G @ v
                g = L.T @ np.real(np.outer(ga, gb)) @ R.T
                out.append(Cut(val, g.ravel(order="F"), ("sigma", j, float(w), a.tobytes())))
        return out

    def _eig_cuts_of(self, P: Partition, K: np.ndarray, tag: tuple, offset: float,
                     threshold: float, delta: float) -> list[Cut]:
        Kt, L, R = P.loop_gain(K)
        A = P.A + P.B2 @ Kt @ P.C2
        w, vl, vr = _eig_lr(A)
        sel = np.flatnonzero(w.imag >= -1e-12 * (1 + np.abs(w)))
        Y, X = vl[:, sel], vr[:, sel]
        yx = np.einsum("ij,ij->j", Y.conj(), X)
        keep = np.abs(yx) >= 1e-300
        sel, Y, X, yx = sel[keep], Y[:, keep], X[:, keep], yx[keep]
        # dλ = (yᴴ B2 dKt C2 x) / (yᴴ x), dKt = L dK R: the gradient is Re((Lᵀa)(R b)ᵀ) with
        # a = B2ᵀ ȳ / (yᴴx) and b = C2 x, for every eigenvalue at once
        La = ((Y.conj().T @ P.B2) / yx[:, None]) @ L
        Rb = (P.C2 @ X).T @ R.T
        G = np.real(La[:, :, None] * Rb[:, None, :])
        G = G.transpose(0, 2, 1).reshape(sel.size, -1)       # column-major vec per eigenvalue
        vals = w[sel].real + offset
        # condition number of the eigenvalue: beyond _KAPPA_MAX it sits in a (nearly)
        # defective cluster, moves like a fractional power of the step and its first-order
        # gradient (up to 1e60 on BDT2's Jordan blocks) would swamp the QP
        kappa = np.linalg.norm(Y, axis=0) * np.linalg.norm(X, axis=0) / np.abs(yx)
        linear = kappa <= _KAPPA_MAX
        with np.errstate(over="ignore", invalid="ignore"):
            reach = np.where(linear, vals + delta * np.sum(np.abs(G), axis=1), vals)
        return [Cut(float(vals[i]), G[i], tag + (complex(w[sel[i]]),), linear=bool(linear[i]))
                for i in np.flatnonzero(reach >= threshold)]

    def eig_cuts(self, K: np.ndarray, margin: float, threshold: float, delta: float,
                 which: str = "all") -> list[Cut]:
        """``Re λ + offset`` cuts of every eigenvalue that may exceed ``threshold`` within the
        trust region ``delta`` (offset: ``margin`` for the H∞ plants, ``decay`` for the
        stability plants); ``which`` in {"all", "stab"}."""
        out: list[Cut] = []
        if which == "all":
            for j, P in enumerate(self.aug):
                out += self._eig_cuts_of(P, K, ("eig", "h", j), margin, threshold, delta)
        for j, P in enumerate(self.stab):
            out += self._eig_cuts_of(P, K, ("eig", "s", j), self.decay, threshold, delta)
        return out

    def det_cuts(self, K: np.ndarray) -> list[Cut]:
        """``min_det − det(I − Kbar D22)`` cuts (feasible when <= 0)."""
        out = []
        m = K.shape[0]
        for j, P in enumerate(self.d22):
            M = np.eye(m) - K @ P.D22
            dt = np.linalg.det(M)
            # d det = det tr(M⁻¹ dM), dM = −dK D22  ->  grad = −det (D22 M⁻¹)ᵀ
            g = -dt * (P.D22 @ np.linalg.inv(M)).T
            out.append(Cut(self.min_det - dt, -g.ravel(order="F"), ("det", j)))
        return out

    def reevaluate(self, K: np.ndarray, cut: Cut, margin: float) -> Cut | None:
        """The same piece at another gain (for the quasi-Newton update)."""
        kind = cut.key[0]
        if kind == "sigma":
            _, j, w, a = cut.key
            if np.isfinite(w) and w > 0:
                # follow the local peak: the gradient of the peak function max_ω σ (envelope)
                # carries the curvature that the peak's motion adds
                A, B, C, D = self.aug[j].closed_loop(K)
                w = _refine_peak(A, B, C, D, w / 1.2, w * 1.2, w, xatol=1e-4)[0]
            cs = self.sigma_cuts(K, j, [w], floor=0.0, rel=0.0)
            same = [c for c in cs if c.key[3] == a]
            return same[0] if same else cs[0]
        if kind == "det":
            return self.det_cuts(K)[cut.key[1]]
        if kind == "eig":
            _, grp, j, lam = cut.key
            P = self.aug[j] if grp == "h" else self.stab[j]
            off = margin if grp == "h" else self.decay
            cs = self._eig_cuts_of(P, K, ("eig", grp, j), off, -np.inf, 0.0)
            if not cs:
                return None
            return min(cs, key=lambda c: abs(c.key[-1] - lam))
        return None

    def peaks(self, K: np.ndarray, j: int, gamma_j: float, omega_j: float,
              ratio: float) -> list[float]:
        """Active frequencies of plant ``j``: local maxima of σ_max above ``ratio γ_j``."""
        A, B, C, D = self.aug[j].closed_loop(K)
        return [w for w, _ in active_frequencies(A, B, C, D, gamma_j, omega_j, ratio=ratio)]

    # ------------------------------------------------------------------ controllers
    def to_controller(self, K: np.ndarray) -> tuple[np.ndarray, ...]:
        """Unscaled ``(Ak, Bk, Ck, Dk)`` from the scaled static gain."""
        nu, ny = self.nu, self.ny
        Dt, Ct, Bt, Ak = K[:nu, :ny], K[:nu, ny:], K[nu:, :ny], K[nu:, ny:]
        Dk = self.su[:, None] * Dt / self.sy[None, :]
        Ck = self.su[:, None] * Ct
        Bk = self.w0 * Bt / self.sy[None, :]
        return self.w0 * Ak, Bk, Ck, Dk

    def from_controller(self, Ak, Bk, Ck, Dk) -> np.ndarray:
        """Scaled static gain from an unscaled controller."""
        nu, ny, k = self.nu, self.ny, self.order
        K = np.zeros((nu + k, ny + k))
        K[:nu, :ny] = Dk * self.sy[None, :] / self.su[:, None]
        K[:nu, ny:] = Ck / self.su[:, None]
        K[nu:, :ny] = Bk * self.sy[None, :] / self.w0
        K[nu:, ny:] = Ak / self.w0
        return K


def verify_closed_loop(P: control.StateSpace, K: control.StateSpace, nmeas: int,
                       ncon: int) -> tuple[float, float, float]:
    """Exact check of one plant/controller pair with the synthesis' own arithmetic.

    Closes ``u = K y`` on the partitioned plant (including a ``D22`` feed-through) and returns
    ``(gamma, omega_peak, spectral_abscissa)`` with the exact norm (Hamiltonian iteration);
    ``gamma`` is ``inf`` for an unstable loop.  The independent check of a design is
    :func:`casflutter.verify.verify_controller`, which shares no code with this one.
    """
    part = partition(P, nmeas, ncon)
    k = K.nstates
    Kbar = np.block([[np.asarray(K.D, float).reshape(ncon, nmeas),
                      np.asarray(K.C, float).reshape(ncon, k)],
                     [np.asarray(K.B, float).reshape(k, nmeas),
                      np.asarray(K.A, float).reshape(k, k)]])
    A, B, C, D = part.augmented(k).closed_loop(Kbar)
    alpha = spectral_abscissa(A)
    if alpha >= 0:
        return np.inf, np.nan, alpha
    g, w = hinf_norm(A, B, C, D)
    return g, w, alpha


def realize(Ak, Bk, Ck, Dk) -> control.StateSpace:
    """Real-Schur form of ``Ak`` with a diagonal scaling that balances ``Bk`` rows and ``Ck``
    columns (orthogonal + diagonal similarity: well conditioned)."""
    k = Ak.shape[0]
    if k == 0:
        return control.ss([], [], [], Dk) if Dk.size else control.ss(Dk)
    Tk, Z = sla.schur(Ak, output="real")
    Bz, Cz = Z.T @ Bk, Ck @ Z
    rb, cc = np.linalg.norm(Bz, axis=1), np.linalg.norm(Cz, axis=0)
    ok = (rb > 0) & (cc > 0)
    d = np.ones(k)
    d[ok] = np.sqrt(rb[ok] / cc[ok])
    d = np.clip(d, 1e-6, 1e6)
    A2 = Tk * d[None, :] / d[:, None]
    return control.ss(A2, Bz / d[:, None], Cz * d[None, :], Dk)
