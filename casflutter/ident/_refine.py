"""Stage 2: refinement of all HWL parameters by a CasADi NLP solved with Ipopt.

Two criteria:

``"prediction"``
    Sum of squared mu-step-ahead prediction errors (eq. 3 with measured past outputs),
    the criterion Bai's two-stage method approximates.  The prediction is linear in the
    over-parameterised products, ``yhat = Phi w(theta)``, so with ``Phi = Q R`` the cost
    equals ``||Q'Y - R w(theta)||^2`` plus a constant: the NLP never touches the long
    record, only an ``n_columns x N`` reduced residual.  Exact Hessian.
``"simulation"``
    Sum of squared free-run simulation errors, by multiple shooting: each record is cut
    into intervals of ``shooting_interval`` samples; the output history at the start of
    each interval is a decision variable tied to the end of the previous interval by an
    equality constraint.  The recursion is a ``mapaccum`` over a one-step function, so the
    graph stays small on long records; short intervals keep an unstable initial guess from
    blowing up.  Exact Hessian of the sparse NLP.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .._format import result_repr
from .._nlp import NLPResult, make_solver
from ..data import IOData
from ..errors import ConfigError
from ._structure import HWLStructure, _input_part
from ._twins import ar_weights, recursion_step
from ._regression import regressor_matrix, weights_matrix
from ._simfit import FreeRunProblem

__all__ = ["prediction_problem", "simulation_problem", "refine", "RefinementResult"]

PREDICTION_TOL = 1e-12
"""Ipopt's ``tol`` for the prediction criterion unless the options give one.  That NLP is
a small dense least squares with the exact Hessian, so Ipopt ends quadratically and the last
four decades cost a few iterations; what they buy is a ROM that is a function of the data,
not of where Ipopt stopped.  With Ipopt's usual 1e-8, records perturbed at 1e-12 moved the
seed wing's flutter speed by 2e-8, and the nonconvex controller synthesis downstream
amplified that into a stable speed interval 1e-2 shorter; at 1e-12 the same perturbation
moves the flutter speed by 7e-12 and the interval by 2e-6."""


@dataclass(frozen=True)
class RefinementResult:
    """Outcome of the stage-2 Ipopt NLP (:func:`refine`).

    Attributes
    ----------
    theta : numpy.ndarray
        Refined parameters (the last iterate when the solve failed: check ``nlp.success``).
    nlp : NLPResult
        The solver's outcome (status, iterations, time).
    cost_initial, cost : float
        Criterion at the start ``theta0`` and at ``theta``.  For the simulation criterion
        both are free runs evaluated outside the NLP (from the measured initial outputs of
        every record), so they compare like with like.
    """

    __repr__ = result_repr

    theta: np.ndarray
    nlp: NLPResult
    cost_initial: float
    cost: float


def prediction_problem(structure: HWLStructure, data: IOData, regularization: float = 0.0,
                       theta_ref=None):
    """Stage-2 NLP for the prediction-error criterion.

    Returns ``(nlp, cost_function)``, ``cost_function(theta)`` evaluating the same
    objective in numpy (used for reporting and by the SciPy reference).
    """
    Phi, Y = regressor_matrix(structure, data)
    n_rows = Y.shape[0]
    col_norm = np.linalg.norm(Phi, axis=0)
    col_norm[col_norm == 0] = 1.0
    Q, R = np.linalg.qr(Phi / col_norm)
    C = Q.T @ Y
    const = max(float(np.sum(Y ** 2) - np.sum(C ** 2)), 0.0)
    RD = R * col_norm[None, :]
    scale = 0.5 / (n_rows * structure.n_modes)
    theta = ca.MX.sym("theta", structure.n_params)
    Wm = ca.vertcat(*weights_matrix(structure, structure.weights(theta)))
    res = ca.DM(C) - ca.mtimes(ca.DM(RD), Wm)
    f = scale * (ca.sumsqr(res) + const)
    if regularization:
        ref = np.zeros(structure.n_params) if theta_ref is None else np.asarray(theta_ref)
        f = f + 0.5 * regularization * ca.sumsqr(theta - ref) / structure.n_params
    cost = ca.Function("prediction_cost", [theta], [f])
    return {"x": theta, "f": f}, lambda th: float(cost(th))


def simulation_problem(structure: HWLStructure, data: IOData, shooting_interval: int = 50,
                       regularization: float = 0.0, theta_ref=None):
    """Stage-2 NLP for the free-run simulation criterion (multiple shooting).

    Returns ``(nlp, residual, x0_nodes, unpack)``: the NLP dict, the residual vector (for a
    Gauss--Newton Hessian), the initial values of the shooting nodes (measured output
    histories) and a function splitting the solution vector into ``(theta, nodes)``.  Each
    record starts from its measured outputs.
    """
    N, L = structure.n_modes, structure.max_lag
    lags = structure.orders.ar_lags()
    theta = ca.MX.sym("theta", structure.n_params)
    W = structure.weights(theta)
    n_rows = sum(r.n_samples - L for r in data.records)
    scale = 0.5 / (n_rows * N)
    H = max(lags) if lags else 0
    step = recursion_step(structure) if lags else None
    w_ar = ar_weights(structure, W) if lags else None
    accs: dict[int, ca.Function] = {}
    nodes, node_init, g, residuals = [], [], [], []
    for rec in data.records:
        K = rec.n_samples
        u = None if rec.u is None else ca.DM(rec.u)
        v = None if rec.v is None else ca.DM(rec.v.reshape(-1, 1))
        xin = _input_part(structure, W, u, v, K)  # (K-L) x N, MX
        target = rec.y[L:]
        if not lags:
            residuals.append(ca.vec(xin - ca.DM(target)))
            continue
        # the measured initial output history (the Gauss--Newton solver estimates it)
        hist = ca.DM(np.concatenate([rec.y[L - 1 - d] for d in range(H)]))
        for start in range(0, K - L, shooting_interval):
            stop = min(start + shooting_interval, K - L)
            n = stop - start
            if start > 0:
                z = ca.MX.sym(f"z_{len(nodes)}", H * N)
                k = L + start
                node_init.append(np.concatenate([rec.y[k - 1 - d] for d in range(H)]))
                nodes.append(z)
                g.append(z - hist)
                hist = z
            if n not in accs:
                accs[n] = step.mapaccum(f"hwl_seg_{n}", n)
            traj = accs[n](hist, xin[start:stop, :].T, ca.repmat(w_ar, 1, n))
            residuals.append(ca.vec(traj[:N, :].T - ca.DM(target[start:stop])))
            hist = traj[:, -1]
    residual = ca.vertcat(*residuals)
    f = scale * ca.sumsqr(residual)
    if regularization:
        ref = np.zeros(structure.n_params) if theta_ref is None else np.asarray(theta_ref)
        f = f + 0.5 * regularization * ca.sumsqr(theta - ref) / structure.n_params
    x = ca.vertcat(theta, *nodes)
    nlp = {"x": x, "f": f, "g": ca.vertcat(*g) if g else ca.MX(0, 1)}
    x_nodes = np.concatenate(node_init) if node_init else np.zeros(0)
    n_par = structure.n_params
    return nlp, residual, x_nodes, lambda xx: (np.asarray(xx)[:n_par], np.asarray(xx)[n_par:])


def _gauss_newton_hessian(nlp, residual, structure, data, regularization) -> ca.Function:
    """Gauss--Newton Hessian of the Lagrangian, ``lam_f * 2 scale J'J`` (constraint
    curvature ignored), in the ``hess_lag`` form CasADi's Ipopt interface accepts."""
    x = nlp["x"]
    N, L = structure.n_modes, structure.max_lag
    n_rows = sum(r.n_samples - L for r in data.records)
    scale = 0.5 / (n_rows * N)
    J = ca.jacobian(residual, x)
    H = 2 * scale * ca.mtimes(J.T, J)
    if regularization:
        n = structure.n_params
        reg = ca.diag(ca.vertcat(ca.DM.ones(n), ca.DM.zeros(x.numel() - n)))
        H = H + regularization / n * reg
    sigma = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", nlp["g"].numel())
    p = ca.MX.sym("p", 0)
    return ca.Function("hwl_gn_hessian", [x, p, sigma, lam_g], [sigma * ca.triu(H)],
                       ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])


def refine(structure: HWLStructure, data: IOData, theta0, *, criterion: str = "prediction",
           shooting_interval: int = 50, regularization: float = 0.0,
           options: dict | None = None, hessian: str = "gauss-newton") -> RefinementResult:
    """Solve the stage-2 NLP from ``theta0`` with Ipopt.

    Options not given take the package defaults (``casflutter._nlp.DEFAULT_IPOPT_OPTIONS``).
    The NLP starts every record from its measured outputs.

    Returns
    -------
    RefinementResult
        The refined parameters, the solver's outcome and the criterion before and after.

    Raises
    ------
    ConfigError
        ``criterion`` is neither ``"prediction"`` nor ``"simulation"``.
    """
    theta0 = np.asarray(theta0, dtype=float)
    opts = dict(options or {})
    if criterion == "prediction":
        opts.setdefault("ipopt.tol", PREDICTION_TOL)
        nlp, cost = prediction_problem(structure, data, regularization, theta0)
        solver = make_solver(nlp, opts, name="hwl_prediction")
        cost0 = cost(theta0)
        res = solver(theta0)
        return RefinementResult(res.x, res, cost0, res.f)
    if criterion == "simulation":
        nlp, residual, nodes0, split = simulation_problem(structure, data, shooting_interval,
                                                          regularization, theta0)
        x0 = np.concatenate([theta0, nodes0])
        free = FreeRunProblem(structure, data, regularization, theta0)
        cost0 = free.cost(free.x0(theta0))
        if hessian == "gauss-newton":
            opts.setdefault("hess_lag", _gauss_newton_hessian(nlp, residual, structure,
                                                              data, regularization))
        opts.setdefault("show_eval_warnings", False)
        solver = make_solver(nlp, opts, name="hwl_simulation")
        res = solver(x0, lbg=0.0, ubg=0.0)
        theta = split(res.x)[0]
        cost = free.cost(free.x0(theta)) if np.all(np.isfinite(theta)) else float("nan")
        return RefinementResult(theta, res, cost0, cost)
    raise ConfigError(f"criterion={criterion!r} is not known: use 'prediction' or 'simulation'")
