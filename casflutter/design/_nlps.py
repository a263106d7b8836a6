"""The two CasADi NLPs of the fixed-order synthesis (built once, solved many times).

Both act on the static gain ``Kbar`` of the augmented plants (see :mod:`._plant`),
written ``Kbar = Kc + S ∘ d`` with the current gain ``Kc`` and the element scales ``S`` as
parameters and the scaled step ``d`` as decision variable; a trust region is a simple
bound ``|d| <= Δ``.

*Stabilisation* (smoothed spectral abscissa, Vanbiervliet et al. 2009): maximise ``β``
subject to, for every plant, ``(Acl + βI)ᵀP + P(Acl + βI) + I = 0`` with ``P = RRᵀ`` and
``tr P <= c``.  A positive definite ``P`` exists iff ``α(Acl) < -β``; bounding ``tr P``
turns ``-β`` into the smoothed spectral abscissa, a smooth upper bound of ``α``.

*H∞ phase* (epigraph minimax, paper §III.C): minimise ``t`` subject to, for every plant
``j`` and frequency slot ``ω_i``,

* ``(jω_i I - Acl) X = Bcl`` and ``T = Ccl X + Dcl`` (lifted frequency response, the complex
  numbers in real and imaginary parts),
* ``t² I - TᴴT = LLᴴ`` with ``L`` complex lower triangular (an exact, smooth form of
  ``σ_max(T(jω_i)) <= t``; ``TTᴴ`` when it is the smaller matrix),
* ``Aclᵀ P + P Acl + 2βP + WWᵀ = 0``, ``P = RRᵀ``, ``tr P = n`` — a Lyapunov certificate
  of ``α(Acl) <= -β``: every feasible point is stable, so the phase cannot leave the
  stability region.

Every equation is polynomial (at most cubic) in the variables, so exact Hessians in SX
are cheap and sparse.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np
import scipy.linalg as sla

from .._nlp import NLPSolver, make_solver
from ._plant import Partition

__all__ = ["StabilizationNLP", "HinfNLP"]


def _tril_sx(name: str, n: int, strict: bool = False) -> tuple[ca.SX, ca.SX]:
    """Symbolic lower-triangular matrix and the vector of its free entries."""
    idx = [(i, j) for j in range(n) for i in range(n) if (i > j if strict else i >= j)]
    v = ca.SX.sym(name, len(idx))
    M = ca.SX.zeros(n, n)
    for k, (i, j) in enumerate(idx):
        M[i, j] = v[k]
    return M, v


def _tril_vals(M: np.ndarray, strict: bool = False) -> np.ndarray:
    n = M.shape[0]
    return np.array([M[i, j] for j in range(n) for i in range(n) if (i > j if strict else i >= j)])


def _sym_lower(M: ca.SX, strict: bool = False) -> ca.SX:
    n = M.shape[0]
    return ca.vertcat(*[M[i, j] for j in range(n) for i in range(n) if (i > j if strict else i >= j)])


def _lyap(A: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Solve ``AᵀP + PA + Q = 0``."""
    return sla.solve_continuous_lyapunov(A.T, -Q)


class _Gain:
    """``Kbar = Kc + S ∘ d`` with parameters ``Kc, S``."""

    def __init__(self, m: int, p: int):
        self.m, self.p = m, p
        self.d = ca.SX.sym("d", m * p)
        self.Kc = ca.SX.sym("Kc", m * p)
        self.S = ca.SX.sym("S", m * p)
        self.K = ca.reshape(self.Kc + self.S * self.d, m, p)


def _closed(P: Partition, K: ca.SX):
    A = P.A + P.B2 @ K @ P.C2
    B = P.B1 + P.B2 @ K @ P.D21
    C = P.C1 + P.D12 @ K @ P.C2
    D = P.D11 + P.D12 @ K @ P.D21
    return A, B, C, D


@dataclass
class StabilizationNLP:
    """Smoothed-spectral-abscissa NLP over a set of augmented plants (one solver, reused)."""

    plants: Sequence[Partition]
    options: dict

    def __post_init__(self):
        m, p = self.plants[0].B2.shape[1], self.plants[0].C2.shape[0]
        g = _Gain(m, p)
        beta = ca.SX.sym("beta")
        c = ca.SX.sym("c", len(self.plants))
        rho = ca.SX.sym("rho")
        xs, gs = [g.d, beta], []
        for j, P in enumerate(self.plants):
            n = P.nx
            R, rv = _tril_sx(f"R{j}", n)
            Acl = _closed(P, g.K)[0] + beta * ca.SX.eye(n)
            Pm = R @ R.T
            E = Acl.T @ Pm + Pm @ Acl + ca.SX.eye(n)
            gs += [_sym_lower(E), ca.trace(Pm) / c[j]]
            xs.append(rv)
        self._ng_eq = [P.nx * (P.nx + 1) // 2 for P in self.plants]
        x = ca.vertcat(*xs)
        f = -beta + 0.5 * rho * ca.sumsqr(g.d)
        pvec = ca.vertcat(g.Kc, g.S, c, rho)
        self.nd = m * p
        self.m, self.p = m, p
        self.solver: NLPSolver = make_solver({"x": x, "f": f, "g": ca.vertcat(*gs), "p": pvec},
                                             self.options, name="stabilize")

    def solve(self, Kc: np.ndarray, S: np.ndarray, delta: float, beta0: float,
              tr_factor: float = 2.0, rho: float = 1e-3):
        """One short solve from ``Kc`` with ``β0`` feasible (``α(Acl(Kc)) + β0 < 0``).

        Returns ``(Kbar_new, NLPResult)``.
        """
        x0 = [np.zeros(self.nd), [beta0]]
        lbg, ubg, cs = [], [], []
        for P in self.plants:
            A = P.closed_loop(Kc)[0] + beta0 * np.eye(P.nx)
            Pm = _lyap(A, np.eye(P.nx))
            Pm = 0.5 * (Pm + Pm.T)
            try:
                R = np.linalg.cholesky(Pm)
            except np.linalg.LinAlgError:
                R = np.linalg.cholesky(Pm + 1e-12 * np.trace(Pm) * np.eye(P.nx))
            cs.append(tr_factor * np.trace(Pm))
            x0.append(_tril_vals(R))
            neq = P.nx * (P.nx + 1) // 2
            lbg += [np.zeros(neq), [-np.inf]]
            ubg += [np.zeros(neq), [1.0]]
        nx = sum(len(np.atleast_1d(v)) for v in x0)
        lbx = np.full(nx, -np.inf)
        ubx = np.full(nx, np.inf)
        lbx[:self.nd], ubx[:self.nd] = -delta, delta
        p = np.concatenate([Kc.ravel(order="F"), S.ravel(order="F"), cs, [rho]])
        res = self.solver(np.concatenate([np.atleast_1d(v) for v in x0]), lbx=lbx, ubx=ubx,
                          lbg=np.concatenate(lbg), ubg=np.concatenate(ubg), p=p,
                          accept_acceptable=True)
        d = res.x[:self.nd].reshape((self.m, self.p), order="F")
        return Kc + S * d, res


@dataclass
class HinfNLP:
    """Epigraph minimax NLP over plants × frequency slots (one solver, reused).

    Parameters
    ----------
    plants : sequence of Partition
        Augmented (static-gain form), scaled plants with common ``(nw, nz, nu+k, ny+k)``.
    nslots : int
        Frequency slots per plant; the frequencies are parameters, refilled every outer
        iteration by the adaptive grid.
    options : dict
        Ipopt options for :func:`casflutter._nlp.make_solver`.
    """

    plants: Sequence[Partition]
    nslots: int
    options: dict

    def __post_init__(self):
        P0 = self.plants[0]
        nw, nz, m, p = P0.dims
        self.m, self.p, self.nw, self.nz = m, p, nw, nz
        self.use_right = nw <= nz          # G = TᴴT (nw×nw) else TTᴴ (nz×nz)
        q = nw if self.use_right else nz
        self.q = q
        g = _Gain(m, p)
        t = ca.SX.sym("t")
        gref = ca.SX.sym("gref")
        beta = ca.SX.sym("beta")
        rho = ca.SX.sym("rho")
        xs, gs, ps = [g.d, t], [], []
        I_q = ca.SX.eye(q)
        self.layout = []
        for j, P in enumerate(self.plants):
            n = P.nx
            Acl, Bcl, Ccl, Dcl = _closed(P, g.K)
            om = ca.SX.sym(f"om{j}", self.nslots)
            xsc = ca.SX.sym(f"xs{j}", self.nslots)
            ps += [om, xsc]
            for i in range(self.nslots):
                Xr = ca.SX.sym(f"Xr{j}_{i}", n, nw)
                Xi = ca.SX.sym(f"Xi{j}_{i}", n, nw)
                Tr = ca.SX.sym(f"Tr{j}_{i}", nz, nw)
                Ti = ca.SX.sym(f"Ti{j}_{i}", nz, nw)
                Lr, lrv = _tril_sx(f"Lr{j}_{i}", q)
                Li, liv = _tril_sx(f"Li{j}_{i}", q, strict=True)
                xs += [ca.vec(Xr), ca.vec(Xi), ca.vec(Tr), ca.vec(Ti), lrv, liv]
                e1 = -Acl @ Xr - om[i] * Xi - Bcl / xsc[i]
                e2 = om[i] * Xr - Acl @ Xi
                e3 = Tr - (xsc[i] * (Ccl @ Xr) + Dcl) / gref
                e4 = Ti - xsc[i] * (Ccl @ Xi) / gref
                if self.use_right:
                    Gr = Tr.T @ Tr + Ti.T @ Ti
                    Gi = Tr.T @ Ti - Ti.T @ Tr
                else:
                    Gr = Tr @ Tr.T + Ti @ Ti.T
                    Gi = Ti @ Tr.T - Tr @ Ti.T
                LLr = Lr @ Lr.T + Li @ Li.T
                LLi = Li @ Lr.T - Lr @ Li.T
                e5 = _sym_lower(t ** 2 * I_q - Gr - LLr)
                e6 = _sym_lower(-Gi - LLi, strict=True)
                gs += [ca.vec(e1), ca.vec(e2), ca.vec(e3), ca.vec(e4), e5, e6]
            R, rv = _tril_sx(f"R{j}", n)
            W, wv = _tril_sx(f"W{j}", n)
            Pm = R @ R.T
            E = Acl.T @ Pm + Pm @ Acl + 2 * beta * Pm + W @ W.T
            xs += [rv, wv]
            gs += [_sym_lower(E), ca.trace(Pm) - n]
        x = ca.vertcat(*xs)
        f = t + 0.5 * rho * ca.sumsqr(g.d)
        pvec = ca.vertcat(g.Kc, g.S, gref, beta, rho, *ps)
        self.nd = m * p
        self.nx_nlp = x.numel()
        self.ng_nlp = ca.vertcat(*gs).numel()
        self.solver: NLPSolver = make_solver({"x": x, "f": f, "g": ca.vertcat(*gs), "p": pvec},
                                             self.options, name="hinf_minimax")

    def initial_point(self, Kc: np.ndarray, omegas: Sequence[np.ndarray], gref: float,
                      beta: float):
        """A feasible starting point at ``Kc`` (exact X, T, Cholesky factors, Lyapunov pair)."""
        x0 = [np.zeros(self.nd)]
        xscales = []
        blocks = []
        tmax = 0.0
        Ts_all = []
        for j, P in enumerate(self.plants):
            A, B, C, D = P.closed_loop(Kc)
            n = P.nx
            xsj, Tj, Xj = [], [], []
            for w in omegas[j]:
                X = np.linalg.solve(1j * w * np.eye(n) - A, B)
                s = max(np.max(np.abs(X)), 1e-12)
                T = (C @ X + D) / gref
                xsj.append(s)
                Xj.append(X / s)
                Tj.append(T)
                tmax = max(tmax, np.linalg.norm(T, 2))
            xscales.append(np.array(xsj))
            Ts_all.append((Xj, Tj))
        t0 = 1.02 * tmax + 1e-3
        for j, P in enumerate(self.plants):
            Xj, Tj = Ts_all[j]
            for X, T in zip(Xj, Tj):
                G = T.conj().T @ T if self.use_right else T @ T.conj().T
                M = t0 ** 2 * np.eye(self.q) - G
                L = np.linalg.cholesky(0.5 * (M + M.conj().T))
                blocks += [X.real.ravel(order="F"), X.imag.ravel(order="F"),
                           T.real.ravel(order="F"), T.imag.ravel(order="F"),
                           _tril_vals(L.real), _tril_vals(L.imag, strict=True)]
            A = P.closed_loop(Kc)[0]
            n = P.nx
            Pm = _lyap(A + beta * np.eye(n), np.eye(n))
            Pm = 0.5 * (Pm + Pm.T)
            scale = n / np.trace(Pm)
            R = np.linalg.cholesky(Pm * scale)
            W = np.sqrt(scale) * np.eye(n)
            blocks += [_tril_vals(R), _tril_vals(W)]
        x0 = np.concatenate([np.zeros(self.nd), [t0]] + blocks)
        return x0, xscales

    def solve(self, Kc: np.ndarray, S: np.ndarray, delta: float, omegas: Sequence[np.ndarray],
              gref: float, beta: float, rho: float = 1e-4, t_floor: float = 0.7):
        """One minimax solve in the trust region ``|d| <= delta`` around ``Kc``.

        Returns ``(Kbar_new, t_grid * gref, NLPResult)``; ``t_grid * gref`` is the *gridded*
        bound, never reported as the norm.
        """
        x0, xscales = self.initial_point(Kc, omegas, gref, beta)
        lbx = np.full(x0.size, -np.inf)
        ubx = np.full(x0.size, np.inf)
        lbx[:self.nd], ubx[:self.nd] = -delta, delta
        lbx[self.nd] = t_floor   # the gridded bound may fall by at most 1 - t_floor per solve
        p = np.concatenate([Kc.ravel(order="F"), S.ravel(order="F"), [gref, beta, rho]]
                           + [v for j in range(len(self.plants))
                              for v in (np.asarray(omegas[j], float), xscales[j])])
        res = self.solver(x0, lbx=lbx, ubx=ubx, lbg=0.0, ubg=0.0, p=p, accept_acceptable=True)
        d = res.x[:self.nd].reshape((self.m, self.p), order="F")
        return Kc + S * d, float(res.x[self.nd]) * gref, res
