"""The two CasADi NLPs of the fixed-order synthesis (built once, solved many times).

Both act on the static gain ``Kbar`` of the augmented plants (see :mod:`._plant`),
written ``Kbar = Kc + S ∘ d`` with the current gain ``Kc`` and the element scales ``S`` as
parameters and the scaled step ``d`` as decision variable; a trust region is a simple
bound ``|d| <= Δ``.

*Stabilisation* (smoothed spectral abscissa, Vanbiervliet et al. 2009): maximise ``β``
subject to, for every plant, ``(Acl + βI)ᵀP + P(Acl + βI) + I = 0`` with ``P = RRᵀ`` and
``tr P <= c``.  A positive definite ``P`` exists iff ``α(Acl) < -β``; bounding ``tr P``
turns ``-β`` into the smoothed spectral abscissa, a smooth upper bound of ``α``.

*H∞ phase* (epigraph minimax, paper §III.C, a local model in the spirit of Apkarian & Noll
2006): minimise ``t`` subject to, for every plant ``j`` and slot ``(ω_i, v_i)``,

* ``‖T_j(jω_i; K) v_i‖² <= t²`` where ``T`` is the *exact* closed-loop frequency response as
  a function of ``K`` (the complex solve written in its real 2n×2n form inside the CasADi
  graph) and ``v_i`` the top right singular vector at the current controller (``‖Tᴴu‖``
  with the left vector when ``nz < nw``).  By the envelope theorem this is a first-order
  exact, smooth model of ``σ_max(T(jω_i; K))``; near-multiple ``σ_max`` are covered by
  sampling the top-2 singular subspace;
* ``Aclᵀ P + P Acl + 2βP + WWᵀ = 0``, ``P = RRᵀ``, ``tr P = n`` — a Lyapunov certificate
  of ``α(Acl) <= -β``: every feasible point is stable;
* a trust region ``|d| <= Δ`` and a floor on ``t`` (the model is trusted locally only).

The driver (:mod:`._synthesis`) accepts a step only after the exact H∞ norm (Hamiltonian
method) has decreased and the loop is verified stable by eigenvalues; it then re-selects the
slots around the exact peak frequencies (adaptive grid).

An earlier formulation with lifted responses ``X`` and Cholesky slacks ``t²I - TᴴT = LLᴴ``
(exact at every slot) was measured to stall Ipopt near the optimum (rank-deficient ``L`` at
active slots: restoration phases, 10–20 s per solve on AC15/HE4), hence this design.
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


def _tril_mx(v: ca.MX, n: int, strict: bool = False) -> ca.MX:
    """Lower-triangular MX matrix filled column by column from ``v``."""
    idx = [(i, j) for j in range(n) for i in range(n) if (i > j if strict else i >= j)]
    if not idx:
        return ca.MX.zeros(n, n)
    sp = ca.Sparsity.triplet(n, n, [i for i, _ in idx], [j for _, j in idx])
    return ca.densify(ca.MX(sp, v))


def _psd_conditions(t2, Yr, Yi) -> ca.MX:
    """Smooth, exact conditions for ``t² I - YᴴY ⪰ 0`` with ``Y = Yr + jYi`` (``r <= 3``
    columns): the coefficients of the characteristic polynomial of the Hermitian
    ``H = t² I - YᴴY`` (sums of principal minors) are all ``>= 0`` iff its (real) eigenvalues
    are ``>= 0`` (Descartes).  Uses the real symmetric 2r×2r embedding ``[[Hr, -Hi], [Hi, Hr]]``
    whose eigenvalues are those of ``H`` twice; computed on ``H`` directly for r <= 3."""
    r = Yr.shape[1]
    Gr = Yr.T @ Yr + Yi.T @ Yi
    Gi = Yr.T @ Yi - Yi.T @ Yr
    Hr = t2 * ca.DM.eye(r) - Gr
    Hi = -Gi
    if r == 1:
        return Hr[0, 0]
    c1 = ca.trace(Hr)
    # 2x2 principal minors of a Hermitian matrix: h_aa h_bb - |h_ab|²
    pairs = [(a, b) for a in range(r) for b in range(a + 1, r)]
    m2 = [Hr[a, a] * Hr[b, b] - Hr[a, b] ** 2 - Hi[a, b] ** 2 for a, b in pairs]
    c2 = m2[0]
    for v in m2[1:]:
        c2 = c2 + v
    if r == 2:
        return ca.vertcat(c1, c2)
    # r == 3: det of the Hermitian 3x3 (real form of the complex determinant)
    h11, h22, h33 = Hr[0, 0], Hr[1, 1], Hr[2, 2]
    a12r, a12i = Hr[0, 1], Hi[0, 1]
    a13r, a13i = Hr[0, 2], Hi[0, 2]
    a23r, a23i = Hr[1, 2], Hi[1, 2]
    # det = h11 h22 h33 + 2 Re(h12 h23 conj(h13)) - h11|h23|² - h22|h13|² - h33|h12|²
    re_prod = (a12r * a23r - a12i * a23i) * a13r + (a12r * a23i + a12i * a23r) * a13i
    c3 = (h11 * h22 * h33 + 2 * re_prod - h11 * (a23r ** 2 + a23i ** 2)
          - h22 * (a13r ** 2 + a13i ** 2) - h33 * (a12r ** 2 + a12i ** 2))
    return ca.vertcat(c1, c2, c3)


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
    rank : int
        Singular directions modelled per frequency (1–3): ``t²I - YᴴY ⪰ 0`` with
        ``Y = T(jω; K) V_r`` through the characteristic-polynomial conditions.
    """

    plants: Sequence[Partition]
    nslots: int
    options: dict
    rank: int = 1

    def __post_init__(self):
        P0 = self.plants[0]
        nw, nz, m, p = P0.dims
        self.m, self.p, self.nw, self.nz = m, p, nw, nz
        self.fix_input = nw <= nz   # fix the direction of the smaller side
        self.rank = min(self.rank, nw, nz)
        d = ca.MX.sym("d", m * p)
        Kc = ca.MX.sym("Kc", m * p)
        S = ca.MX.sym("S", m * p)
        K = ca.reshape(Kc + S * d, m, p)
        t = ca.MX.sym("t")
        gref = ca.MX.sym("gref")
        beta = ca.MX.sym("beta")
        rho = ca.MX.sym("rho")
        xs, gs, ps = [d, t], [], []
        for j, P in enumerate(self.plants):
            n = P.nx
            Acl = P.A + ca.mtimes([ca.DM(P.B2), K, ca.DM(P.C2)])
            Bcl = P.B1 + ca.mtimes([ca.DM(P.B2), K, ca.DM(P.D21)])
            Ccl = (P.C1 + ca.mtimes([ca.DM(P.D12), K, ca.DM(P.C2)])) / gref
            Dcl = (P.D11 + ca.mtimes([ca.DM(P.D12), K, ca.DM(P.D21)])) / gref
            om = ca.MX.sym(f"om{j}", self.nslots)
            # [vec Re V; vec Im V] per slot (top-r singular vectors, zero-padded)
            U = ca.MX.sym(f"U{j}", 2 * nz * self.rank, self.nslots)
            V = ca.MX.sym(f"V{j}", 2 * nw * self.rank, self.nslots)
            ps += [om, ca.vec(U), ca.vec(V)]
            In = ca.DM.eye(n)
            r = self.rank
            for i in range(self.nslots):
                # real form of (jωI - Acl)
                M = ca.blockcat([[-Acl, -om[i] * In], [om[i] * In, -Acl]])
                if self.fix_input:
                    # Y = T(jω) V with V the top right singular vectors at the current K
                    Vr = ca.reshape(V[:nw * r, i], nw, r)
                    Vi = ca.reshape(V[nw * r:, i], nw, r)
                    Xs = ca.solve(M, ca.vertcat(Bcl @ Vr, Bcl @ Vi))
                    Yr = Ccl @ Xs[:n, :] + Dcl @ Vr
                    Yi = Ccl @ Xs[n:, :] + Dcl @ Vi
                else:
                    # Y = T(jω)ᴴ U with U the top left singular vectors
                    Ur = ca.reshape(U[:nz * r, i], nz, r)
                    Ui = ca.reshape(U[nz * r:, i], nz, r)
                    Xs = ca.solve(M.T, ca.vertcat(Ccl.T @ Ur, Ccl.T @ Ui))
                    Yr = Bcl.T @ Xs[:n, :] + Dcl.T @ Ur
                    Yi = Bcl.T @ Xs[n:, :] + Dcl.T @ Ui
                gs.append(_psd_conditions(t ** 2, Yr, Yi))
            rv = ca.MX.sym(f"R{j}", n * (n + 1) // 2)
            wv = ca.MX.sym(f"W{j}", n * (n + 1) // 2)
            R, W = _tril_mx(rv, n), _tril_mx(wv, n)
            Pm = R @ R.T
            E = Acl.T @ Pm + Pm @ Acl + 2 * beta * Pm + W @ W.T
            xs += [rv, wv]
            gs += [_sym_lower(E), ca.trace(Pm) - n]
        x = ca.vertcat(*xs)
        f = t + 0.5 * rho * ca.sumsqr(d)
        pvec = ca.vertcat(Kc, S, gref, beta, rho, *ps)
        self.nd = m * p
        self.nx_nlp = x.numel()
        g = ca.vertcat(*gs)
        self.ng_nlp = g.numel()
        # which constraints are the frequency inequalities (g >= 0), the rest are equalities
        self.ineq = np.zeros(self.ng_nlp, dtype=bool)
        k = 0
        for P in self.plants:
            self.ineq[k:k + self.nslots * self.rank] = True
            k += self.nslots * self.rank + P.nx * (P.nx + 1) // 2 + 1
        self.solver: NLPSolver = make_solver({"x": x, "f": f, "g": g, "p": pvec},
                                             self.options, name="hinf_minimax")

    def slots(self, Kc: np.ndarray, omegas: Sequence[np.ndarray], rel: float = 0.8):
        """Frequency slots ``(ω, U, V)``: at each frequency the (at most ``rank``) singular
        vectors with ``σ_i >= rel σ_1``, zero-padded (the local model of the peak)."""
        out = []
        for j, P in enumerate(self.plants):
            A, B, C, D = P.closed_loop(Kc)
            n = P.nx
            items = []
            for w in omegas[j]:
                T = C @ np.linalg.solve(1j * w * np.eye(n) - A, B) + D
                Us, sv, Vh = np.linalg.svd(T)
                Vs = Vh.conj().T
                r = max(1, min(self.rank, int(np.sum(sv >= rel * sv[0]))))
                Ur = np.zeros((self.nz, self.rank), complex)
                Vr = np.zeros((self.nw, self.rank), complex)
                Ur[:, :r], Vr[:, :r] = Us[:, :r], Vs[:, :r]
                items.append((w, Ur, Vr, sv[0]))
            items = items[:self.nslots]
            while len(items) < self.nslots:
                items.append(items[-1])
            out.append(items)
        return out

    def initial_point(self, Kc: np.ndarray, slots, gref: float, beta: float):
        """A feasible starting point at ``Kc`` (the Lyapunov pair) and the parameters."""
        tmax = max(it[3] for sl in slots for it in sl) / gref
        t0 = 1.001 * tmax + 1e-6
        blocks, pars = [], []
        for j, P in enumerate(self.plants):
            A = P.closed_loop(Kc)[0]
            n = P.nx
            Pm = _lyap(A + beta * np.eye(n), np.eye(n))
            Pm = 0.5 * (Pm + Pm.T)
            scale = n / np.trace(Pm)
            R = np.linalg.cholesky(Pm * scale)
            W = np.sqrt(scale) * np.eye(n)
            blocks += [_tril_vals(R), _tril_vals(W)]
            om = np.array([it[0] for it in slots[j]])
            U = np.array([np.concatenate([it[1].real.ravel(order="F"),
                                          it[1].imag.ravel(order="F")]) for it in slots[j]]).T
            V = np.array([np.concatenate([it[2].real.ravel(order="F"),
                                          it[2].imag.ravel(order="F")]) for it in slots[j]]).T
            pars += [om, U.ravel(order="F"), V.ravel(order="F")]
        x0 = np.concatenate([np.zeros(self.nd), [t0]] + blocks)
        return x0, pars

    def solve(self, Kc: np.ndarray, S: np.ndarray, delta: float, omegas: Sequence[np.ndarray],
              gref: float, beta: float, rho: float = 1e-4, t_floor: float = 0.7):
        """One minimax solve in the trust region ``|d| <= delta`` around ``Kc``.

        Returns ``(Kbar_new, t_grid * gref, NLPResult)``; ``t_grid * gref`` is the *gridded*
        bound, never reported as the norm.
        """
        slots = self.slots(Kc, omegas)
        x0, pars = self.initial_point(Kc, slots, gref, beta)
        lbx = np.full(x0.size, -np.inf)
        ubx = np.full(x0.size, np.inf)
        lbx[:self.nd], ubx[:self.nd] = -delta, delta
        lbx[self.nd] = t_floor   # the model bound may fall by at most 1 - t_floor per solve
        p = np.concatenate([Kc.ravel(order="F"), S.ravel(order="F"), [gref, beta, rho]] + pars)
        ubg = np.where(self.ineq, np.inf, 0.0)
        res = self.solver(x0, lbx=lbx, ubx=ubx, lbg=0.0, ubg=ubg, p=p, accept_acceptable=True)
        d = res.x[:self.nd].reshape((self.m, self.p), order="F")
        return Kc + S * d, float(res.x[self.nd]) * gref, res
