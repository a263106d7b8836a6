"""The trust-region subproblem of the nonsmooth synthesis, a small QP in the gain step only.

    minimise   t + ½ dᵀ H d
    subject to f_i + g_iᵀ d <= t            (objective cuts: local models of σ or Re λ)
               c_l + h_lᵀ d <= 0            (constraint cuts: decay rate, well-posedness)
               |d| <= Δ                     (box trust region)

Its size is the number of controller parameters plus one, whatever the plant's state
dimension: the plant enters only through the cut values and gradients computed in numpy.
One solver per (parameters, cut slots) size is built through :mod:`casflutter._nlp` and
reused; unused slots are free constraints.

qpOASES (``solver="qpoases"``, the multi-speed design's) solves it as a dense QP by an
active-set method: exact on the box (an interior point relaxes the bounds by 1e-8) and about ten
times faster than Ipopt where the σ cuts number hundreds (0.02 s against 0.26 s a step on
goland_4flaps).  A QP it does not solve is solved again by Ipopt, whose status then joins
qpOASES's.  With ``solver="ipopt"`` Ipopt solves every QP, built from MX symbols: the data
(``H``, the cuts) are parameters that enter only through products with the step, which
MX keeps as dense matrix products, so a build takes milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .._nlp import NLPSolver, QPSolver, make_qp_solver, make_solver
from ..errors import ConfigError

__all__ = ["CutQP", "QPStep"]

_SLOT = 16


@dataclass(frozen=True)
class QPStep:
    """Solution of one subproblem: step ``d``, model value ``t + ½dᵀHd``, the multipliers of
    the objective and constraint cuts, and the solver's status."""

    d: np.ndarray
    model: float
    t: float
    mu: np.ndarray
    nu: np.ndarray
    status: str
    success: bool


class CutQP:
    """Cached QP solvers for ``n`` parameters.

    Parameters
    ----------
    n : int
        Number of gain parameters.
    options : dict
        Extra Ipopt options (flat CasADi keys), for the QPs Ipopt solves.
    solver : {"qpoases", "ipopt"}
        The QP solver (module docstring).
    """

    SOLVERS = ("qpoases", "ipopt")

    def __init__(self, n: int, options: dict | None = None, solver: str = "qpoases"):
        if solver not in self.SOLVERS:
            raise ConfigError(f"QP solver {solver!r}: give one of {', '.join(self.SOLVERS)}")
        self.n = int(n)
        self.solver = solver
        self._dense: dict[tuple[int, int], QPSolver] = {}
        self.options = {"ipopt.tol": 1e-11, "ipopt.acceptable_tol": 1e-8,
                        "ipopt.max_iter": 300, "ipopt.hessian_constant": "yes",
                        "ipopt.jac_c_constant": "yes", "ipopt.jac_d_constant": "yes",
                        "ipopt.mu_strategy": "adaptive"}
        self.options.update(options or {})
        self._cache: dict[tuple[int, int], NLPSolver] = {}

    def _solver(self, mo: int, mc: int) -> NLPSolver:
        key = (mo, mc)
        if key not in self._cache:
            n = self.n
            d = ca.MX.sym("d", n)
            t = ca.MX.sym("t")
            H = ca.MX.sym("H", n, n)
            G = ca.MX.sym("G", mo, n)
            f = ca.MX.sym("f", mo)
            Hc = ca.MX.sym("Hc", mc, n)
            c = ca.MX.sym("c", mc)
            obj = t + 0.5 * ca.dot(d, ca.mtimes(H, d))
            # t repeated explicitly: in CasADi 3.8.2 the MX Jacobian of ``vector - scalar``
            # has -1 in the first row only once the vector is longer than a few entries
            # (the values are right, the derivative is not), and Ipopt then solves
            # another QP
            g = ca.vertcat(f + ca.mtimes(G, d) - ca.repmat(t, mo, 1), c + ca.mtimes(Hc, d))
            p = ca.vertcat(ca.vec(H), ca.vec(G), f, ca.vec(Hc), c)
            self._cache[key] = make_solver({"x": ca.vertcat(d, t), "f": obj, "g": g, "p": p},
                                           self.options, name="synthesis_qp")
        return self._cache[key]

    def solve(self, H: np.ndarray, f: np.ndarray, G: np.ndarray, c: np.ndarray,
              Hc: np.ndarray, delta: np.ndarray | float) -> QPStep:
        """Solve the subproblem (module docstring); ``d = 0`` must be feasible (``c <= 0``).

        Raises
        ------
        FloatingPointError
            A cut value or gradient that is not finite (a loop whose sensitivities
            overflowed), or no finite step from the solver; the synthesis records the start
            as failed.
        """
        if not all(np.all(np.isfinite(M)) for M in (H, f, G, c, Hc)):
            raise FloatingPointError("the local model has non-finite cut values or gradients")
        n = self.n
        no, nc = f.size, c.size
        mo = _SLOT * max(1, -(-no // _SLOT))
        mc = _SLOT * max(1, -(-nc // _SLOT))
        Gp = np.zeros((mo, n))
        Gp[:no] = G
        fp = np.zeros(mo)
        fp[:no] = f
        Hcp = np.zeros((mc, n))
        Hcp[:nc] = Hc
        cp = np.zeros(mc)
        cp[:nc] = c
        delta = np.broadcast_to(np.asarray(delta, dtype=float), (n,))
        first = ""
        if self.solver == "qpoases":
            step = self._active_set(H, fp, Gp, no, cp, Hcp, nc, delta)
            if step.success:
                return step
            first = step.status
        p = np.concatenate([H.ravel(order="F"), Gp.ravel(order="F"), fp,
                            Hcp.ravel(order="F"), cp])
        lbx = np.concatenate([-delta, [-np.inf]])
        ubx = np.concatenate([delta, [np.inf]])
        ubg = np.concatenate([np.where(np.arange(mo) < no, 0.0, np.inf),
                              np.where(np.arange(mc) < nc, 0.0, np.inf)])
        x0 = np.concatenate([np.zeros(n), [float(np.max(f)) + 1e-9 * (1 + abs(np.max(f)))]])
        res = self._solver(mo, mc)(x0, lbx=lbx, ubx=ubx, lbg=-np.inf, ubg=ubg, p=p,
                                   accept_acceptable=True)
        d = res.x[:n]
        if not np.all(np.isfinite(res.x)):
            raise FloatingPointError(f"the QP returned a non-finite step ({res.return_status})")
        t = float(res.x[n])
        model = float(np.max(f + G @ d)) + 0.5 * float(d @ H @ d)
        return QPStep(d=d, model=model, t=t, mu=np.maximum(res.lam_g[:no], 0.0),
                      nu=np.maximum(res.lam_g[mo:mo + nc], 0.0),
                      status=f"qpoases: {first}; ipopt: {res.return_status}" if first
                      else res.return_status, success=res.success)

    def _active_set(self, H, fp, Gp, no, cp, Hcp, nc, delta) -> QPStep:
        """The subproblem by qpOASES, in the variables ``(d, t)``, the cut slots padded
        as for Ipopt."""
        n = self.n
        mo, mc = fp.size, cp.size
        if (mo, mc) not in self._dense:
            self._dense[(mo, mc)] = make_qp_solver(n + 1, mo + mc, "qpoases",
                                                   name="synthesis_qp")
        Hx = np.zeros((n + 1, n + 1))
        Hx[:n, :n] = 0.5 * (H + H.T)
        g = np.zeros(n + 1)
        g[n] = 1.0
        A = np.zeros((mo + mc, n + 1))
        A[:mo, :n] = Gp
        A[:mo, n] = -1.0
        A[mo:, :n] = Hcp
        uba = np.concatenate([np.where(np.arange(mo) < no, -fp, np.inf),
                              np.where(np.arange(mc) < nc, -cp, np.inf)])
        big = 1e3 * (1.0 + float(np.max(np.abs(fp))) + float(np.sum(np.abs(Gp).max(0)
                                                                       * delta)))
        res = self._dense[(mo, mc)](Hx, g, A, np.full(mo + mc, -np.inf), uba,
                                    np.concatenate([-delta, [-big]]),
                                    np.concatenate([delta, [big]]))
        d = res.x[:n]
        if not (res.success and np.all(np.isfinite(res.x))):
            return QPStep(d=d, model=np.nan, t=np.nan, mu=np.zeros(no), nu=np.zeros(nc),
                          status=res.return_status, success=False)
        model = float(np.max(fp[:no] + Gp[:no] @ d)) + 0.5 * float(d @ H @ d)
        return QPStep(d=d, model=model, t=float(res.x[n]),
                      mu=np.maximum(res.lam_a[:no], 0.0),
                      nu=np.maximum(res.lam_a[mo:mo + nc], 0.0), status=res.return_status,
                      success=True)
