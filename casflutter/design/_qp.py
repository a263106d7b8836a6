"""The trust-region subproblem of the nonsmooth synthesis, a small QP in the gain step only.

    minimise   t + ½ dᵀ H d
    subject to f_i + g_iᵀ d <= t            (objective cuts: local models of σ or Re λ)
               c_l + h_lᵀ d <= 0            (constraint cuts: decay rate, well-posedness)
               |d| <= Δ                     (box trust region)

Its size is the number of controller parameters plus one, whatever the plant's state
dimension: the plant enters only through the cut values and gradients computed in numpy.
Solved by Ipopt through :mod:`casflutter._nlp`; one solver per (parameters, cut slots)
size is built and reused, unused slots are free constraints.  The solver is built from MX
symbols: the data (``H``, the cuts) are parameters that enter only through products with
the step, which MX keeps as dense matrix products, so a build takes milliseconds (from SX
scalar symbols, half a second at 77 parameters and 160 cut slots, once per slot size: a
third of a goland_4flaps H∞ phase) and a solve costs the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .._nlp import NLPSolver, make_solver

__all__ = ["CutQP", "QPStep"]

_SLOT = 16


@dataclass(frozen=True)
class QPStep:
    """Solution of one subproblem: step ``d``, model value ``t + ½dᵀHd``, the multipliers of
    the objective and constraint cuts, and Ipopt's status."""

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
        Extra Ipopt options (flat CasADi keys).
    """

    def __init__(self, n: int, options: dict | None = None):
        self.n = int(n)
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
        p = np.concatenate([H.ravel(order="F"), Gp.ravel(order="F"), fp,
                            Hcp.ravel(order="F"), cp])
        delta = np.broadcast_to(np.asarray(delta, dtype=float), (n,))
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
                      nu=np.maximum(res.lam_g[mo:mo + nc], 0.0), status=res.return_status,
                      success=res.success)
