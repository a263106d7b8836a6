"""The flutter (Hopf) point as a parametric CasADi NLP, reused across sweep points.

The truth state matrices are exactly quadratic in the speed index,
``A(V) = A0 + V A1 + V² A2`` (aerodynamic stiffness ∝ V², damping and lag rates ∝ V,
apparent mass constant; :func:`quadratic_coefficients` checks it), so the Hopf point of
paper Sec. III-B is the root of ::

    (A0 + V A1 + V² A2 − iω I) x = 0,     cᴴ x = 1

in ``(V, ω, x)`` (``2n + 2`` real unknowns and equations).  It is posed as a square
feasibility NLP whose numbers ``(A0, A1, A2, c)`` are the NLP parameters ``p``: the solver
depends on ``n`` only, so a sweep builds it once per worker process
(:func:`casflutter.study.cached_solver`) and every point is one warm-started Ipopt
(Newton) solve from a coarse eigenvalue scan.  Differentiating the solution with respect to
``p`` (the parametric NLP sensitivity at the solution, by CasADi's algorithmic
differentiation of the KKT system) gives dVf/dp without any finite difference of the
flutter speed.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import casadi as ca
import numpy as np

from .._format import result_repr
from .._nlp import make_solver
from ..errors import ConfigError, ConvergenceError
from ..truth import load_problem
from ._sensitivity import FlutterSensitivity, ParameterSensitivity, _parametric_truth
from ._solvers import cached_solver, solver_builds
from ._truth_point import load_truth

__all__ = ["quadratic_coefficients", "hopf_point", "HopfPoint", "flutter_sensitivity_nlp",
           "truth_hopf"]

_OPTIONS = {"ipopt.tol": 1e-12, "ipopt.max_iter": 60, "ipopt.hessian_constant": "no"}


def quadratic_coefficients(matrix_fn: Callable[[float], np.ndarray],
                           V_nodes: Sequence[float] = (0.5, 1.0, 1.5), *,
                           check_V: float = 2.5, rtol: float = 1e-9):
    """``(A0, A1, A2)`` with ``A(V) = A0 + V A1 + V² A2``, verified at ``check_V``.

    Parameters
    ----------
    matrix_fn : callable
        ``V -> A(V)``.
    V_nodes : sequence of three floats
        Speeds at which ``A`` is sampled.
    check_V : float
        Speed of the check.
    rtol : float
        Relative tolerance of the check.

    Returns
    -------
    A0, A1, A2 : ndarray

    Raises
    ------
    ConfigError
        If ``A(check_V)`` differs from the quadratic by more than ``rtol`` (relative), i.e.
        the system is not quadratic in V and the Hopf NLP does not apply.
    """
    V = np.asarray(V_nodes, float)
    M = np.stack([np.ones(3), V, V * V], axis=1)
    As = np.array([matrix_fn(v) for v in V])
    C = np.einsum("ij,jkl->ikl", np.linalg.inv(M), As)
    At = matrix_fn(check_V)
    err = np.abs(C[0] + check_V * C[1] + check_V ** 2 * C[2] - At).max() / max(np.abs(At).max(), 1.0)
    if err > rtol:
        raise ConfigError(f"A(V) is not quadratic in V (relative misfit {err:.2e} at "
                          f"V = {check_V}); use find_flutter instead of the Hopf NLP")
    return C[0], C[1], C[2]


def _hopf_expressions(n: int):
    """Symbols ``(w, p)`` and residual ``g(w, p)`` of the Hopf system of size ``n``."""
    w = ca.SX.sym("w", 2 * n + 2)
    V, om, xr, xi = w[0], w[1], w[2:2 + n], w[2 + n:]
    p = ca.SX.sym("p", 3 * n * n + 2 * n)
    A0, A1, A2 = (ca.reshape(p[k * n * n:(k + 1) * n * n], n, n) for k in range(3))
    cr, ci = p[3 * n * n:3 * n * n + n], p[3 * n * n + n:]
    A = A0 + V * A1 + V * V * A2
    g = ca.vertcat(ca.mtimes(A, xr) + om * xi, ca.mtimes(A, xi) - om * xr,
                   ca.dot(cr, xr) + ca.dot(ci, xi) - 1.0, ca.dot(cr, xi) - ca.dot(ci, xr))
    return w, p, g


def _build(n: int):
    """The Hopf-point NLP for state dimension ``n`` (parameters: A0, A1, A2, c)."""
    w, p, g = _hopf_expressions(n)
    return make_solver({"x": w, "p": p, "f": ca.SX(0), "g": g}, _OPTIONS, name=f"hopf_{n}")


def hopf_solver(n: int):
    """The cached Hopf NLP of size ``n`` in this process (built once)."""
    return cached_solver(("hopf", int(n)), lambda: _build(int(n)))


@dataclass(frozen=True)
class HopfPoint:
    """Result of :func:`hopf_point`.

    Attributes
    ----------
    Vf : float
        Flutter speed index.
    omega_f : float
        Flutter frequency ``|Im λ|``.
    eigenvector : ndarray (complex)
        Critical eigenvector, normalised ``cᴴ x = 1``.
    p : ndarray
        The NLP parameter vector ``(A0, A1, A2, c)``.
    w : ndarray
        The NLP solution ``(V, ω, Re x, Im x)``.
    return_status : str
        Ipopt's status, verbatim.
    iterations : int
        Ipopt iterations.
    solve_time : float
        Seconds.
    solver_builds : int
        Builds of this NLP in this process (1 when the solver is reused).
    lam_g, lam_x : ndarray
        Multipliers at the solution.
    """

    __repr__ = result_repr

    Vf: float
    omega_f: float
    eigenvector: np.ndarray
    p: np.ndarray
    w: np.ndarray
    return_status: str
    iterations: int
    solve_time: float
    solver_builds: int
    lam_g: np.ndarray
    lam_x: np.ndarray


def _scan(A0, A1, A2, V_grid):
    """First grid interval where a complex pair's real part turns positive, and the
    interpolated start (V, λ, eigenvector)."""
    prev = None
    for V in V_grid:
        lam, R = np.linalg.eig(A0 + V * A1 + V * V * A2)
        cplx = lam.imag > 1e-9 * max(np.abs(lam).max(), 1.0)
        if not cplx.any():
            prev = None
            continue
        i = int(np.argmax(np.where(cplx, lam.real, -np.inf)))
        if prev is not None and lam[i].real > 0 >= prev[1].real:
            Vp, lp = prev[0], prev[1]
            t = -lp.real / (lam[i].real - lp.real)
            return Vp + t * (V - Vp), lp + t * (lam[i] - lp), R[:, i]
        prev = (V, lam[i])
    return None


def hopf_point(A0: np.ndarray, A1: np.ndarray, A2: np.ndarray, *,
               V_range: tuple[float, float] = (0.02, 4.0), n_scan: int = 41) -> HopfPoint:
    """Flutter speed of ``A0 + V A1 + V² A2`` by a coarse scan and the Hopf NLP.

    Parameters
    ----------
    A0, A1, A2 : ndarray
        ``A(V) = A0 + V A1 + V² A2`` (:func:`quadratic_coefficients`).
    V_range : (float, float)
        Range of the coarse scan.
    n_scan : int
        Points of the coarse scan.

    Returns
    -------
    HopfPoint

    Raises
    ------
    ConvergenceError
        No complex pair crosses in the scan, or Ipopt did not converge.
    """
    n = A0.shape[0]
    start = _scan(A0, A1, A2, np.linspace(V_range[0], V_range[1], int(n_scan)))
    if start is None:
        raise ConvergenceError(f"no complex eigenvalue pair crosses the imaginary axis for V in "
                               f"{V_range} (coarse scan of {n_scan} points)")
    V0, lam0, x0 = start
    c = x0 / np.vdot(x0, x0)  # cᴴ x0 = 1
    p = np.concatenate([A0.ravel(order="F"), A1.ravel(order="F"), A2.ravel(order="F"),
                        c.real, c.imag])
    w0 = np.concatenate([[V0, lam0.imag], x0.real, x0.imag])
    solver = hopf_solver(n)
    res = solver(w0, p=p, lbg=0.0, ubg=0.0)
    if not res.success:
        raise ConvergenceError(f"Hopf NLP did not converge ({res.return_status}, "
                               f"{res.iterations} iterations) from V = {V0:.4g}", res)
    w = res.x
    return HopfPoint(Vf=float(w[0]), omega_f=float(abs(w[1])),
                     eigenvector=w[2:2 + n] + 1j * w[2 + n:], p=p, w=w,
                     return_status=res.return_status, iterations=res.iterations,
                     solve_time=res.wall_time, solver_builds=solver_builds(("hopf", n)),
                     lam_g=res.lam_g, lam_x=res.lam_x)


def _sens_function(n: int) -> ca.Function:
    """``(w*, p) -> dw*/dp`` of the Hopf NLP, cached per ``n``.

    The NLP is square with ``f = 0``, so its KKT conditions reduce to ``g(w, p) = 0`` (the
    multipliers vanish) and the parametric sensitivity at the solution is
    ``dw*/dp = -(∂g/∂w)⁻¹ ∂g/∂p``, both Jacobians by CasADi's algorithmic differentiation.
    (``solver.factory(..., ['jac:x:p'])`` re-solves the NLP inside the derivative and
    Ipopt refuses the square problem there, hence this explicit form.)
    """
    key = ("hopf_sens", n)
    fn = _SENS.get(key)
    if fn is None:
        w, p, g = _hopf_expressions(n)
        dw = -ca.solve(ca.jacobian(g, w), ca.jacobian(g, p))
        fn = _SENS[key] = ca.Function(f"hopf_sens_{n}", [w, p], [dw], ["w", "p"], ["dw_dp"])
    return fn


_SENS: dict = {}


def flutter_sensitivity_nlp(problem: str = "typical_section",
                            parameters: Sequence[str] | None = None, *,
                            params: Mapping[str, float] | None = None,
                            V_range: tuple[float, float] = (0.02, 4.0), n_scan: int = 41,
                            rel_step: float = 1e-6) -> FlutterSensitivity:
    """dVf/dp by CasADi's parametric sensitivity of the Hopf NLP at its solution.

    ``dVf/dθ = (∂w*/∂p)[V] · ∂p/∂θ`` where ``p = (A0, A1, A2, c)`` and ``∂p/∂θ`` is a central
    difference of the quadratic coefficients (``c`` held fixed).  Same result type as
    :func:`flutter_sensitivity` (``method = "parametric NLP"``).

    Parameters
    ----------
    problem : str
        Truth problem name.
    parameters : sequence of str, optional
        Parameters to differentiate by (default: all).
    params : mapping, optional
        Parameter values of the nominal point (default: the published ones).
    V_range : (float, float)
        Range of the coarse scan.
    n_scan : int
        Points of the coarse scan.
    rel_step : float
        Relative step of the difference of the quadratic coefficients.

    Returns
    -------
    FlutterSensitivity
    """
    params = dict(params or {})
    model = _parametric_truth(problem, params)
    valid = model.params.parameter_names()
    names = list(parameters) if parameters else valid
    bad = [nm for nm in names if nm not in valid]
    if bad:
        raise ConfigError(f"unknown parameter(s) {bad} of {problem!r}; valid: {', '.join(valid)}")
    nominal = {nm: getattr(model.params, nm) for nm in valid}
    A0, A1, A2 = quadratic_coefficients(model.state_matrix)
    hp = hopf_point(A0, A1, A2, V_range=V_range, n_scan=n_scan)
    n = A0.shape[0]
    J = np.asarray(_sens_function(n)(hp.w, hp.p))
    cpart = hp.p[3 * n * n:]
    sens = []
    for nm in names:
        p0 = float(nominal[nm])
        h = rel_step * max(abs(p0), 1.0)

        def pvec(val):
            m = load_problem(problem, {**nominal, nm: val})
            Q = quadratic_coefficients(m.state_matrix)
            return np.concatenate([Q[0].ravel(order="F"), Q[1].ravel(order="F"),
                                   Q[2].ravel(order="F"), cpart])

        try:
            dp, kind = (pvec(p0 + h) - pvec(p0 - h)) / (2 * h), "central"
        except ConfigError:
            dp, kind = (-3 * hp.p + 4 * pvec(p0 + h) - pvec(p0 + 2 * h)) / (2 * h), "forward"
        dw = J @ dp
        dVf, dom = float(dw[0]), float(np.sign(hp.w[1]) * dw[1])
        norm, by = ((p0 / hp.Vf) * dVf, "value") if p0 != 0 else (dVf / hp.Vf, "unit")
        sens.append(ParameterSensitivity(name=nm, value=p0, dVf_dp=dVf, domega_dp=dom,
                                         dlambda_dp=complex(np.nan, np.nan), normalized=norm,
                                         normalized_by=by, difference=kind))
    return FlutterSensitivity(problem=problem, params=nominal, Vf=hp.Vf, omega_f=hp.omega_f,
                              eigenvalue=complex(0.0, hp.omega_f),
                              dlambda_dV=complex(np.nan, np.nan), sensitivities=tuple(sens),
                              rel_step=rel_step, method="parametric NLP (CasADi)",
                              flutter_message=hp.return_status)


def truth_hopf(params: Mapping[str, Any], settings: Mapping[str, Any]) -> dict[str, Any]:
    """Sweep evaluator: truth flutter speed by the cached Hopf NLP.

    Parameters
    ----------
    params, settings : mapping
        As for :func:`casflutter.study.truth_flutter_evaluator` (``problem``, any truth
        parameter, ``V_min``, ``V_max``), plus ``n_scan`` (coarse scan points, default 41).

    Returns
    -------
    dict
        ``Vf``, ``omega_f``, ``frequency_hz``, ``return_status`` (Ipopt, verbatim),
        ``iterations``, ``solve_time``, ``solver_builds`` (times this worker process built
        the NLP of this size: 1 when the solver is reused), ``pid``.
    """
    t0 = time.perf_counter()
    model, options = load_truth(params, settings, extra_options=("n_scan",))
    A0, A1, A2 = quadratic_coefficients(model.state_matrix)
    hp = hopf_point(A0, A1, A2, V_range=(float(options.get("V_min", 0.02)),
                                         float(options.get("V_max", 4.0))),
                    n_scan=int(settings.get("n_scan", 41)))
    return {"Vf": hp.Vf, "omega_f": hp.omega_f, "frequency_hz": hp.omega_f / (2 * np.pi),
            "return_status": hp.return_status, "iterations": hp.iterations,
            "solve_time": hp.solve_time, "solver_builds": hp.solver_builds,
            "pid": os.getpid(), "hopf_time": time.perf_counter() - t0}
