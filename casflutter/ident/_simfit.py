"""Simulation-error fit of the HWL model: Levenberg--Marquardt with exact forward sensitivities.

The criterion is the free-run (simulation) error of eq. 3 over every record,

    f(theta, y0) = (1 / (2 n N)) sum_records sum_{k >= L} ||y_sim(k; theta, y0) - y(k)||^2
                   + (rho / 2 n_p) ||theta - theta_ref||^2,

with the initial outputs ``y0`` of each record (the ``H = mu + na - 1`` past outputs the
recursion starts from) estimated together with the model parameters.  Its Jacobian is exact:
the sensitivity of ``y_sim`` obeys the same recursion as ``y_sim`` (see :mod:`._kernels`), so
one compiled pass over the record gives residual and Jacobian in ``O(K)`` time and memory.

The step is Levenberg--Marquardt with Moré's diagonal scaling; the damping shrinks by 3 after
a step whose decrease the Gauss--Newton model predicted well (ratio >= 1/4), grows by 2 after
a poorly predicted one, and doubles repeatedly (2, 4, 8, ...) while trial steps are rejected.
A trial step whose free run is not finite (or exceeds a divergence bound) is rejected like any
step that does not decrease the cost: the damping grows and the step shrinks, so iterates stay
in the region where the model runs free.  When the *starting* model already diverges, the fit
first minimises the simulation error over segments restarted from the measured outputs
(``seg`` samples ahead), lengthening the segments geometrically until they span the records:
short segments cannot blow up, and each stage starts the next near its optimum.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError, cho_factor, cho_solve
from .._format import result_repr
from .._threads import single_threaded

from ..data import IOData
from ._kernels import free_run, sensitivities
from ._structure import HWLStructure

__all__ = ["FreeRunProblem", "LMResult", "fit_simulation_error"]

log = logging.getLogger("casflutter.ident")

#: |y| (in the unit-RMS working units) beyond which a free run is declared divergent
DIVERGENCE_BOUND = 1e8
#: the acceptable level: this many consecutive steps each decreasing the cost by less than
#: this fraction (Ipopt's ``acceptable_iter`` idea)
ACCEPTABLE_ITER = 15
ACCEPTABLE_DECREASE = 1e-5
#: converged when this many consecutive steps together decrease the cost by less than tol
STALL_WINDOW = 5


@dataclass(frozen=True)
class LMResult:
    """Outcome of :func:`fit_simulation_error`.

    Attributes
    ----------
    theta : ndarray
        Model parameters at the best iterate.
    initial_outputs : tuple of ndarray
        Estimated initial outputs ``(H, N)`` of each record (chronological).
    cost, cost_initial : float
        Free-run criterion at the best iterate and at the start (start: measured initial
        outputs).  ``inf`` when the free run diverges.
    success : bool
        Converged (``Solve_Succeeded``) or, when allowed by the caller, acceptable.
    return_status : str
        ``Solve_Succeeded`` (relative cost decrease of one step or of the last
        ``STALL_WINDOW`` steps together, step or scaled gradient below ``tol``),
        ``Solved_To_Acceptable_Level`` (``ACCEPTABLE_ITER`` consecutive steps each below
        ``ACCEPTABLE_DECREASE`` relative decrease, or no decreasing step while the scaled
        gradient is small), ``Maximum_Iterations_Exceeded``,
        ``Maximum_WallTime_Exceeded``, ``Unstable_Free_Run`` or
        ``Search_Direction_Becomes_Too_Small`` (Ipopt's names where they exist).
    iterations : int
        Jacobian evaluations (accepted steps plus the final one), all stages.
    n_evaluations : int
        Free runs (residual evaluations), all stages.
    stages : tuple of int
        Segment lengths used (0: whole records).
    wall_time : float
    """

    __repr__ = result_repr

    theta: np.ndarray
    initial_outputs: tuple
    cost: float
    cost_initial: float
    success: bool
    return_status: str
    iterations: int
    n_evaluations: int
    stages: tuple
    wall_time: float


class FreeRunProblem:
    """Residual and exact Jacobian of the free-run criterion on fixed (working-unit) data.

    The decision vector is ``x = [theta, y0_record0, y0_record1, ...]`` with each ``y0`` the
    ``H x N`` initial outputs flattened sample by sample (``x = theta`` with
    ``estimate_initial=False``: every record starts from its measured outputs).
    """

    def __init__(self, structure: HWLStructure, data: IOData, regularization: float = 0.0,
                 theta_ref=None, estimate_initial: bool = True):
        o = structure.orders
        self.structure = structure
        self.N, self.L = structure.n_modes, structure.max_lag
        self.lags = np.asarray(o.ar_lags(), dtype=np.int64)
        self.H = int(self.lags.max()) if o.na else 0
        self.P = structure.n_params
        self.idx = structure.index_map()
        self.regularization = float(regularization)
        self.theta_ref = (np.zeros(self.P) if theta_ref is None
                          else np.asarray(theta_ref, dtype=float).copy())
        in_lags = o.input_lags()
        L, H = self.L, self.H
        self.records = []
        n_rows = 0
        for rec in data.records:
            K = rec.n_samples
            M = K - L
            item = {"M": M, "target": rec.y[L:], "ymeas": np.ascontiguousarray(rec.y[L - H:]),
                    "ic0": rec.y[L - H:L].copy()}
            if structure.has_u:
                U = np.stack([rec.u[L - g:K - g] for g in in_lags], axis=1)   # (M, n_in, N)
                item["Up"] = np.stack([U ** l for l in range(1, o.p + 1)])    # (p, M, n_in, N)
            if structure.has_v:
                V = np.stack([rec.v[L - g:K - g] for g in in_lags], axis=1)   # (M, n_in)
                item["Vp"] = np.stack([V ** l for l in range(1, o.p + 1)])    # (p, M, n_in)
            self.records.append(item)
            n_rows += M
        self.n_rows = n_rows
        self.scale = 0.5 / (n_rows * self.N)
        self.estimate_initial = bool(estimate_initial)
        self.n_ic = H * self.N if self.estimate_initial else 0
        self.n_x = self.P + len(self.records) * self.n_ic

    # -- layout -----------------------------------------------------------------------
    def x0(self, theta) -> np.ndarray:
        """Decision vector from ``theta`` with the measured initial outputs."""
        if not self.estimate_initial:
            return np.asarray(theta, dtype=float).copy()
        return np.concatenate([np.asarray(theta, dtype=float)]
                              + [r["ic0"].ravel() for r in self.records])

    def split(self, x):
        """``(theta, [y0 (H, N) per record])``."""
        if not self.estimate_initial:
            return x[:self.P], [r["ic0"] for r in self.records]
        ics = [x[self.P + r * self.n_ic:self.P + (r + 1) * self.n_ic].reshape(self.H, self.N)
               for r in range(len(self.records))]
        return x[:self.P], ics

    def _coefficients(self, theta):
        c = self.structure.unpack(theta)
        arr = {k: np.array([np.asarray(m, dtype=float) for m in v]) for k, v in c.items()}
        out = {"A": arr["A"].reshape(-1, self.N, self.N), "alpha": arr["alpha"]}
        if self.structure.has_u:
            out["HB"] = np.concatenate([arr["H"], arr["B"]])
            out["gamma"] = arr["gamma"]
        if self.structure.has_v:
            out["hb"] = np.concatenate([arr["h"], arr["b"]]).reshape(-1, self.N)
            out["beta"] = arr["beta"].reshape(-1, self.N)
        if self.structure.constant:
            out["c"] = arr["c"].reshape(self.N)
        na, q = self.structure.orders.na, self.structure.orders.q
        out["W"] = np.ascontiguousarray(out["A"][:, None] * out["alpha"][None]).reshape(
            na, q, self.N, self.N)
        return out

    def _input_part(self, co, rec):
        xin = np.zeros((rec["M"], self.N))
        if self.structure.has_u:
            # sum_d sum_j sum_l HB[d,i,j] gamma[l,i,j] u_j(k - lag_d)^l
            xin += np.einsum("dij,lij,ltdj->ti", co["HB"], co["gamma"], rec["Up"], optimize=True)
        if self.structure.has_v:
            xin += np.einsum("di,li,ltd->ti", co["hb"], co["beta"], rec["Vp"], optimize=True)
        if self.structure.constant:
            xin += co["c"]
        return xin

    # -- evaluation -------------------------------------------------------------------
    def residual(self, x, seg: int = 0):
        """Weighted residual vector (data part), per-record caches, and the cost.

        The cost is ``0.5 ||r||^2`` plus the regularisation; ``inf`` when a free run
        diverges (then ``r`` is None).
        """
        theta, ics = self.split(x)
        co = self._coefficients(theta)
        w = np.sqrt(2 * self.scale)
        parts, caches = [], []
        for rec, ic in zip(self.records, ics):
            xin = self._input_part(co, rec)
            if self.H:
                ybuf, yused, div = free_run(xin, co["W"], self.lags, np.ascontiguousarray(ic),
                                            rec["ymeas"], int(seg), DIVERGENCE_BOUND)
                if div >= 0:
                    return None, None, np.inf
                ysim = ybuf[self.H:]
            else:
                ysim, yused = xin, None
            parts.append((w * (ysim - rec["target"])).ravel())
            caches.append(yused)
        r = np.concatenate(parts)
        cost = 0.5 * float(r @ r) + self._reg_cost(theta)
        if not np.isfinite(cost):
            return None, None, np.inf
        return r, (co, caches), cost

    def _reg_cost(self, theta):
        if not self.regularization:
            return 0.0
        d = theta - self.theta_ref
        return 0.5 * self.regularization / self.P * float(d @ d)

    def _direct(self, co, rec, yused):
        """Direct derivatives ``D (M, N, P)`` of eq. 3 (past outputs held fixed)."""
        M, N, o = rec["M"], self.N, self.structure.orders
        D = np.zeros((M, N, self.P))
        idx = self.idx
        ii = np.arange(N)[:, None] * np.ones((1, N), dtype=int)   # ii[i, j] = i

        def put(name, vals, rows):
            # vals (M, n, N, N) or (M, n, N); rows: output index shaped like idx[name]
            D[:, rows.ravel(), idx[name].ravel()] = vals.reshape(M, -1)

        if o.na:
            Yp = np.stack([yused ** l for l in range(1, o.q + 1)])             # (q, M, na, N)
            put("A", -np.einsum("lij,ltmj->tmij", co["alpha"], Yp),
                np.broadcast_to(ii, idx["A"].shape))
            if o.q > 1:
                put("alpha", -np.einsum("mij,ltmj->tlij", co["A"], Yp[1:]),
                    np.broadcast_to(ii, idx["alpha"].shape))
        if self.structure.has_u:
            Up = rec["Up"]
            dHB = np.einsum("lij,ltdj->tdij", co["gamma"], Up)
            put("H", dHB[:, :o.mu], np.broadcast_to(ii, idx["H"].shape))
            put("B", dHB[:, o.mu:], np.broadcast_to(ii, idx["B"].shape))
            if o.p > 1:
                put("gamma", np.einsum("dij,ltdj->tlij", co["HB"], Up[1:]),
                    np.broadcast_to(ii, idx["gamma"].shape))
        if self.structure.has_v:
            Vp = rec["Vp"]
            dhb = np.einsum("li,ltd->tdi", co["beta"], Vp)
            put("h", dhb[:, :o.mu], np.broadcast_to(np.arange(N), idx["h"].shape))
            put("b", dhb[:, o.mu:], np.broadcast_to(np.arange(N), idx["b"].shape))
            if o.p > 1:
                put("beta", np.einsum("di,ltd->tli", co["hb"], Vp[1:]),
                    np.broadcast_to(np.arange(N), idx["beta"].shape))
        if self.structure.constant:
            D[:, np.arange(N), idx["c"].ravel()] = 1.0
        return D

    def jacobian(self, cache, seg: int = 0) -> np.ndarray:
        """Jacobian of the weighted residual with respect to ``x`` (dense)."""
        co, caches = cache
        w = np.sqrt(2 * self.scale)
        single = len(self.records) == 1
        J = None if single else np.zeros((self.n_rows * self.N, self.n_x))
        row = 0
        for r, (rec, yused) in enumerate(zip(self.records, caches)):
            D = self._direct(co, rec, yused)
            D *= w   # the sensitivity recursion is linear: scale its forcing once
            n = rec["M"] * self.N
            if self.H:
                S = sensitivities(D, co["W"], self.lags, yused, int(seg), self.H)
                if single and self.estimate_initial:
                    # columns [theta, initial outputs] are already the layout of x
                    S[:, :, self.P:] *= w
                    return S.reshape(n, self.n_x)
                if single:
                    return np.ascontiguousarray(S[:, :, :self.P]).reshape(n, self.P)
                J[row:row + n, :self.P] = S[:, :, :self.P].reshape(n, self.P)
                if self.estimate_initial:
                    c0 = self.P + r * self.n_ic
                    J[row:row + n, c0:c0 + self.n_ic] = (
                        w * S[:, :, self.P:].reshape(n, self.n_ic))
            else:
                if single:
                    return D.reshape(n, self.P)
                J[row:row + n, :self.P] = D.reshape(n, self.P)
            row += n
        return J

    def cost(self, x, seg: int = 0) -> float:
        """The criterion at ``x`` (``inf`` when a free run diverges)."""
        return self.residual(x, seg)[2]


def _levenberg_marquardt(problem: FreeRunProblem, x, seg, *, max_iter, tol, deadline):
    """One LM run at segment length ``seg``.  Returns ``(x, cost, status, n_jac, n_fev)``."""
    r, cache, f = problem.residual(x, seg)
    n_fev = 1
    if not np.isfinite(f):
        return x, np.inf, "Unstable_Free_Run", 0, n_fev
    P, reg = problem.P, problem.regularization
    d2 = None
    lam = None
    nu = 2.0
    n_jac = 0
    history = [f]
    n_slow = 0          # consecutive steps with a relative decrease below ACCEPTABLE_DECREASE
    status = "Maximum_Iterations_Exceeded"
    for _ in range(max_iter):
        if time.perf_counter() > deadline:
            status = "Maximum_WallTime_Exceeded"
            break
        J = problem.jacobian(cache, seg)
        n_jac += 1
        g = J.T @ r
        A = J.T @ J
        if reg:
            g[:P] += reg / P * (x[:P] - problem.theta_ref)
            A[np.arange(P), np.arange(P)] += reg / P
        diag = np.diag(A).copy()
        d2 = np.where(diag > 0, diag, 1.0) if d2 is None else np.maximum(d2, diag)
        # scaled gradient test (cosine between the residual and each Jacobian column)
        gscale = np.abs(g) / np.sqrt(d2)
        if gscale.max() <= tol * np.sqrt(2 * f + 1e-300):
            status = "Solve_Succeeded"
            break
        if lam is None:
            lam = 1e-3
        accepted = False
        while True:
            Aa = A + lam * np.diag(d2)
            try:
                step = -cho_solve(cho_factor(Aa, check_finite=False), g, check_finite=False)
            except (LinAlgError, ValueError):
                lam *= nu
                nu *= 2
                if lam > 1e20:
                    break
                continue
            pred = -(g @ step + 0.5 * step @ (A @ step))
            x_new = x + step
            r_new, cache_new, f_new = problem.residual(x_new, seg)
            n_fev += 1
            if np.isfinite(f_new) and pred > 0:
                ratio = (f - f_new) / pred
            else:
                ratio = -1.0
            if ratio > 1e-4:
                accepted = True
                break
            lam *= nu
            nu *= 2
            if lam > 1e20:
                break
            if time.perf_counter() > deadline:
                break
        if not accepted:
            # no step decreases the cost: a minimum to working precision, or a stall
            rel_grad = gscale.max() / np.sqrt(2 * f + 1e-300)
            status = ("Solved_To_Acceptable_Level" if rel_grad < 1e-4
                      else "Search_Direction_Becomes_Too_Small")
            if time.perf_counter() > deadline:
                status = "Maximum_WallTime_Exceeded"
            break
        dx = np.sqrt(d2) * step
        small_step = np.linalg.norm(dx) <= tol * (np.linalg.norm(np.sqrt(d2) * x) + tol)
        small_decrease = (f - f_new) <= tol * f and pred <= tol * f
        history.append(f_new)
        # converged: the last STALL_WINDOW steps together decreased the cost by < tol
        stalled = (len(history) > STALL_WINDOW
                   and history[-1 - STALL_WINDOW] - f_new <= tol * f_new)
        n_slow = n_slow + 1 if (f - f_new) <= ACCEPTABLE_DECREASE * f else 0
        x, r, cache, f = x_new, r_new, cache_new, f_new
        log.debug("LM seg=%d iteration %d: cost %.6e, ratio %.3f, lambda %.2e", seg, n_jac, f,
                  ratio, lam)
        # a good model of the decrease: trust it more; a poor one: damp more
        lam = max(lam / 3.0, 1e-15) if ratio >= 0.25 else lam * 2.0
        nu = 2.0
        if small_step or small_decrease or stalled or f <= 1e-30:
            status = "Solve_Succeeded"
            break
        if n_slow >= ACCEPTABLE_ITER:
            # creeping along an ill-conditioned valley: stop as Ipopt's acceptable level does
            status = "Solved_To_Acceptable_Level"
            break
    return x, f, status, n_jac, n_fev


def fit_simulation_error(problem: FreeRunProblem, theta0, *, max_iter: int = 500,
                         tol: float = 1e-8, max_time: float | None = None,
                         blowup: float = 10.0) -> LMResult:
    """Minimise the free-run criterion from ``theta0`` (module docstring).

    Parameters
    ----------
    problem : FreeRunProblem
    theta0 : ndarray
        Starting parameters (working units).
    max_iter : int
        Jacobian evaluations allowed, all stages together.
    tol : float
        Relative tolerance on the cost decrease, the step and the scaled gradient.
    max_time : float, optional
        Wall-time budget in seconds: the best iterate so far is returned with status
        ``Maximum_WallTime_Exceeded``.
    blowup : float
        A start whose free-run cost exceeds ``blowup`` times the cost of the zero output
        (or diverges) goes through the segment continuation first.

    Returns
    -------
    LMResult
    """
    # single-threaded BLAS inside the fit: the products are too small to gain from threads on
    # a shared machine (where they lose several times over), and the result then does not
    # depend on the thread count
    with single_threaded():
        return _fit(problem, theta0, max_iter=max_iter, tol=tol, max_time=max_time,
                    blowup=blowup)


def _fit(problem, theta0, *, max_iter, tol, max_time, blowup) -> LMResult:
    t0 = time.perf_counter()
    deadline = np.inf if max_time is None else t0 + float(max_time)
    x = problem.x0(theta0)
    cost0 = problem.cost(x)
    ref = sum(0.5 * problem.scale * 2 * float(np.sum(r["target"] ** 2)) for r in problem.records)
    ref = max(ref, 1e-300)
    stages = []
    n_jac = n_fev = 0
    if not (cost0 <= blowup * ref):
        longest = max(r["M"] for r in problem.records)
        seg = max(4 * (problem.L + 1), 32)
        # the shortest segments whose cost is finite (1: mu-step-ahead prediction error)
        while seg > 1 and not np.isfinite(problem.cost(x, seg)):
            seg //= 2
        while seg < longest:
            stages.append(seg)
            x, f, status, nj, nf = _levenberg_marquardt(
                problem, x, seg, max_iter=max(1, min(30, max_iter - n_jac)), tol=1e-6,
                deadline=deadline)
            n_jac, n_fev = n_jac + nj, n_fev + nf
            log.debug("simulation fit: %d-sample segments, cost %.4e (%s)", seg, f, status)
            if status in ("Unstable_Free_Run", "Maximum_WallTime_Exceeded"):
                break
            seg *= 4
    stages.append(0)
    x, f, status, nj, nf = _levenberg_marquardt(problem, x, 0, max_iter=max(1, max_iter - n_jac),
                                                tol=tol, deadline=deadline)
    n_jac, n_fev = n_jac + nj, n_fev + nf
    theta, ics = problem.split(x)
    return LMResult(theta=theta.copy(), initial_outputs=tuple(ic.copy() for ic in ics),
                    cost=float(f), cost_initial=float(cost0),
                    success=status == "Solve_Succeeded", return_status=status,
                    iterations=n_jac, n_evaluations=n_fev, stages=tuple(stages),
                    wall_time=time.perf_counter() - t0)
