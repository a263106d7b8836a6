"""Orthogonal collocation of one period of ``x' = f(x, V)`` (continuous truths).

Time is scaled by the unknown period, ``x(t) = w(t / T)``, so that ``w' = T f(w, V)`` on
``tau in [0, 1]``.  The period is cut into ``n_intervals`` equal mesh intervals; on each,
``w`` is the polynomial of degree ``m`` through its value at the interval start and at the
``m`` Gauss--Legendre points, and the differential equation holds at the Gauss points
(collocation; superconvergent of order ``2m`` at the mesh points).  Continuity joins the
intervals and the last one wraps onto the first (periodicity).  The unknowns are

    X = [w at every node (interval-major, state fastest), T, V],

and the equations are the collocation and continuity conditions, the integral phase
condition ``int_0^1 <w(tau), w_ref'(tau)> dtau = 0`` against a reference orbit (it fixes the
time origin), and one linear condition ``<c, X> = s`` (the pseudo-arclength hyperplane, or
the amplitude of the first orbit next to the Hopf point).  The square system is solved by
CasADi's Newton rootfinder through :func:`casflutter._nlp.make_rootfinder`.

Floquet multipliers: the linearised collocation equations of each interval are condensed
onto its start value (the interior values eliminated), which gives the interval's transfer
matrix; their product is the monodromy matrix of the discretised orbit, whose eigenvalues
are the multipliers (one of them the trivial multiplier 1, to the accuracy of the mesh).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .._nlp import RootResult, solve_newton

__all__ = ["Collocation"]


class Collocation:
    """The periodic-orbit collocation system of a vector field (module docstring).

    Parameters
    ----------
    f : casadi.Function
        ``f(x, V) -> dx/dt``.
    n_intervals, degree : int
        Mesh intervals and Gauss--Legendre points per interval.
    tol : float
        Newton tolerance on the residual.
    max_newton : int
        Newton iterations per solve.
    """

    def __init__(self, f: ca.Function, n_intervals: int = 40, degree: int = 4, *,
                 tol: float = 1e-9, max_newton: int = 15):
        self.f = f
        n = int(f.size1_in(0))
        N, m = int(n_intervals), int(degree)
        self.n, self.N, self.m = n, N, m
        xg, wg = np.polynomial.legendre.leggauss(m)
        c = 0.5 * (xg + 1.0)
        self.c, self.b = c, 0.5 * wg
        s = np.concatenate([[0.0], c])
        coef = np.linalg.inv(np.vander(s, m + 1, increasing=True))   # l_j(s) = sum_k coef[k, j] s^k
        self._coef = coef
        self.ell1 = (np.vander([1.0], m + 1, increasing=True) @ coef).ravel()   # l_j(1)
        dvand = np.zeros((m, m + 1))
        for k in range(1, m + 1):
            dvand[:, k] = k * c ** (k - 1)
        self.D = dvand @ coef                                               # l_j'(c_k)
        self.npts = N * (m + 1)
        self.nw = n * self.npts
        self.nX = self.nw + 2
        self.iT, self.iV = self.nw, self.nw + 1
        self.colidx = np.array([i * (m + 1) + k for i in range(N) for k in range(1, m + 1)])
        self.quad = np.tile(self.b / N, N)             # quadrature weights at the Gauss points
        self._build(tol, max_newton)

    # ---- symbolic system ---------------------------------------------------------------
    def _build(self, tol: float, max_newton: int) -> None:
        n, N, m = self.n, self.N, self.m
        X = ca.MX.sym("X", self.nX)
        W = ca.reshape(X[:self.nw], n, self.npts)
        T, V = X[self.iT], X[self.iV]
        Wc = W[:, list(self.colidx)]
        fmap = self.f.map(N * m)
        Fc = fmap(Wc, ca.repmat(V, 1, N * m))
        h = 1.0 / N
        # all intervals at once: W @ Dbig gives sum_j D[k, j] w_{i,j} at every Gauss point,
        # W @ Cbig the end value of each interval minus the start of the next (periodic)
        Dbig = np.kron(np.eye(N), self.D.T)
        Cbig = np.kron(np.eye(N), self.ell1[:, None])
        for i in range(N):
            Cbig[((i + 1) % N) * (m + 1), i] -= 1.0
        colloc = ca.mtimes(W, ca.DM(sp.csc_matrix(Dbig))) - h * T * Fc
        cont = ca.mtimes(W, ca.DM(sp.csc_matrix(Cbig)))
        core = ca.vertcat(ca.vec(colloc), ca.vec(cont))
        # the collocation and continuity rows as scalar graphs with their sparse Jacobian;
        # the dense phase and arclength rows are linear and bordered on in numpy
        self._core = ca.Function("colloc_core", [X], [core]).expand()
        Xs = ca.SX.sym("X", self.nX)
        self._core_jac = ca.Function("colloc_core_jacobian", [Xs],
                                     [ca.jacobian(self._core(Xs), Xs)])
        self._tol, self._max_newton = tol, max_newton
        x = ca.MX.sym("x", n)
        Vs = ca.MX.sym("V")
        fx = ca.Function("fx", [x, Vs], [ca.jacobian(self.f(x, Vs), x)])
        self._fx = fx.map(N * m)
        self._fmap = fmap

    # ---- unknowns ---------------------------------------------------------------------
    def pack(self, W: np.ndarray, T: float, V: float) -> np.ndarray:
        """Unknown vector from node values ``W`` (``n x npts``), period and speed."""
        return np.concatenate([np.asarray(W, float).ravel(order="F"), [T, V]])

    def nodes(self, X: np.ndarray) -> np.ndarray:
        """Node values ``(n, npts)`` of an unknown vector."""
        return np.asarray(X[:self.nw]).reshape(self.npts, self.n).T

    def node_times(self) -> np.ndarray:
        """Scaled times ``tau`` of the nodes (interval-major)."""
        s = np.concatenate([[0.0], self.c])
        return np.concatenate([(i + s) / self.N for i in range(self.N)])

    def collocation_times(self) -> np.ndarray:
        """Scaled times ``tau`` of the Gauss points (interval-major)."""
        return np.concatenate([(i + self.c) / self.N for i in range(self.N)])

    def reference_from(self, derivative_fun) -> np.ndarray:
        """A phase reference from ``derivative_fun(tau) -> (n, len(tau))``, the derivative of
        a reference orbit with respect to ``tau``."""
        return np.asarray(derivative_fun(self.collocation_times()), float).ravel(order="F")

    def initial_guess(self, shape_fun, T: float, V: float) -> np.ndarray:
        """Unknowns from ``shape_fun(tau) -> (n, len(tau))``."""
        return self.pack(shape_fun(self.node_times()), T, V)

    def reference(self, X: np.ndarray) -> np.ndarray:
        """``w'(tau) = T f(w, V)`` at the Gauss points: the phase reference of the next solve."""
        W = self.nodes(X)
        F = np.asarray(self._fmap(W[:, self.colidx], np.full((1, self.N * self.m), X[self.iV])))
        return (X[self.iT] * F).ravel(order="F")

    def phase_row(self, ref: np.ndarray) -> np.ndarray:
        """The integral phase condition ``int <w, w_ref'> dtau`` as a row acting on ``X``."""
        row = np.zeros(self.nX)
        R = np.asarray(ref, float).reshape(self.N * self.m, self.n).T * self.quad[None, :]
        cols = (self.colidx[:, None] * self.n + np.arange(self.n)[None, :]).ravel()
        row[cols] = R.T.ravel()
        return row

    def solve(self, X0: np.ndarray, ref: np.ndarray, c: np.ndarray, s: float) -> RootResult:
        """Newton solve of the collocation system with phase reference ``ref`` and the
        linear condition ``<c, X> = s``."""
        prow = self.phase_row(ref)
        border = sp.csr_matrix(np.vstack([prow, c]))

        def residual(X):
            core = np.asarray(self._core(X)).ravel()
            return np.concatenate([core, [prow @ X, c @ X - s]])

        def jacobian(X):
            return sp.vstack([self._core_jac(X).sparse(), border])

        return solve_newton(residual, jacobian, X0, tol=self._tol, max_iter=self._max_newton,
                            name="periodic_orbit")

    def jacobian(self, X: np.ndarray, ref: np.ndarray) -> sp.csc_matrix:
        """Sparse Jacobian of the collocation, continuity and phase rows (no linear row)."""
        return sp.vstack([self._core_jac(X).sparse(),
                          sp.csr_matrix(self.phase_row(ref)[None, :])]).tocsc()

    # ---- evaluation ---------------------------------------------------------------------
    def fine(self, X: np.ndarray, per_interval: int = 16) -> tuple[np.ndarray, np.ndarray]:
        """The orbit on a fine grid: ``(tau, W)`` with ``W`` of shape ``(n, N * per_interval)``."""
        sf = np.arange(per_interval) / per_interval
        Lf = np.vander(sf, self.m + 1, increasing=True) @ self._coef      # (k, m+1)
        W = self.nodes(X)
        out = [W[:, i * (self.m + 1):(i + 1) * (self.m + 1)] @ Lf.T for i in range(self.N)]
        tau = np.concatenate([(i + sf) / self.N for i in range(self.N)])
        return tau, np.hstack(out)

    def monodromy(self, X: np.ndarray) -> np.ndarray:
        """Monodromy matrix of the discretised orbit from ``tau = 0`` (module docstring)."""
        n, N, m = self.n, self.N, self.m
        W = self.nodes(X)
        T, V = X[self.iT], X[self.iV]
        Jall = np.asarray(self._fx(W[:, self.colidx], np.full((1, N * m), V)))   # (n, n N m)
        h = 1.0 / N
        I = np.eye(n)
        # E[i] = sum_j D[k, j] dw_j - h T J_ik dw_k per interval, all intervals stacked
        E = np.broadcast_to(np.kron(self.D, I), (N, m * n, (m + 1) * n)).copy()
        J = Jall.reshape(n, N, m, n).transpose(1, 2, 0, 3)          # (N, m, n, n)
        for k in range(m):
            E[:, k * n:(k + 1) * n, (k + 1) * n:(k + 2) * n] -= h * T * J[:, k]
        S = np.linalg.solve(E[:, :, n:], E[:, :, :n])               # interior from the start
        Lint = np.kron(self.ell1[1:][None, :], I)                   # (n, m n)
        Mi = self.ell1[0] * I - np.matmul(Lint, S)                  # (N, n, n)
        Mtot = np.eye(n)
        for i in range(N):
            Mtot = Mi[i] @ Mtot
        return Mtot
