"""Derivatives of the flutter speed with respect to problem parameters.

At the flutter crossing the critical eigenvalue λ(V, p) of ``A(V, p)`` has ``Re λ = 0``
(Hopf point, paper Sec. III-B).  Holding it there while ``p`` moves gives the implicit
derivative ::

    d Re λ/dp + d Re λ/dV · dVf/dp = 0   =>   dVf/dp = -Re(∂λ/∂p) / Re(∂λ/∂V)

with the first-order eigenvalue perturbation ``∂λ/∂s = wᴴ (∂A/∂s) v / (wᴴ v)`` (``v`` right,
``w`` left eigenvector of the simple eigenvalue λ), and likewise for the flutter frequency
``dωf/dp = Im(∂λ/∂p) + Im(∂λ/∂V) · dVf/dp``.  ``∂A/∂p`` and ``∂A/∂V`` are central
differences of ``truth.state_matrix`` (one-sided second order at a domain bound such as
``zeta = 0``); the eigenvalue formula makes them one matrix pair per parameter, with no
flutter search at the perturbed values.  :func:`flutter_speed_fd` is the independent check
(finite differences of the refined flutter speed itself).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np
from scipy.linalg import eig

from .._format import result_repr
from ..aeroelastic import find_flutter
from ..errors import ConfigError, ConvergenceError
from ..truth import load_problem, problem_definition, problem_names

__all__ = ["ParameterSensitivity", "FlutterSensitivity", "flutter_sensitivity",
           "flutter_speed_fd"]


@dataclass(frozen=True)
class ParameterSensitivity:
    """Sensitivity of the flutter point to one parameter.

    Attributes
    ----------
    name : str
        Parameter name.
    value : float
        Its value at the nominal point.
    dVf_dp : float
        Derivative of the flutter speed index.
    domega_dp : float
        Derivative of the flutter frequency [rad per time unit].
    dlambda_dp : complex
        Partial derivative of the critical eigenvalue at fixed V.
    normalized : float
        ``(p / Vf) dVf/dp`` (relative change of Vf per relative change of p); when
        ``p == 0`` it is ``dVf/dp / Vf`` (per unit change of p), see ``normalized_by``.
    normalized_by : str
        ``"value"`` or ``"unit"``.
    difference : str
        ``"central"`` or ``"forward"`` (``∂A/∂p`` at a domain bound).
    """

    __repr__ = result_repr

    name: str
    value: float
    dVf_dp: float
    domega_dp: float
    dlambda_dp: complex
    normalized: float
    normalized_by: str
    difference: str


@dataclass(frozen=True)
class FlutterSensitivity:
    """Outcome of :func:`flutter_sensitivity`.

    Attributes
    ----------
    problem : str
        Truth problem name.
    params : dict
        The nominal parameter values.
    Vf, omega_f : float
        Flutter speed index and frequency at the nominal point.
    eigenvalue : complex
        Critical eigenvalue at the crossing (``Re ≈ 0``).
    dlambda_dV : complex
        ``∂λ/∂V`` at the crossing (``Re > 0`` for a destabilising crossing).
    sensitivities : tuple of ParameterSensitivity
        In the order of the requested parameters.
    rel_step : float
        Relative step of the matrix differences.
    method : str
        ``"eigenvalue perturbation"``.
    """

    __repr__ = result_repr

    problem: str
    params: Mapping[str, float]
    Vf: float
    omega_f: float
    eigenvalue: complex
    dlambda_dV: complex
    sensitivities: tuple
    rel_step: float
    method: str = "eigenvalue perturbation"
    flutter_message: str = field(default="", repr=False)

    def __getitem__(self, name: str) -> ParameterSensitivity:
        for s in self.sensitivities:
            if s.name == name:
                return s
        raise KeyError(name)

    def ranked(self) -> list[ParameterSensitivity]:
        """Sensitivities sorted by ``|normalized|``, largest first."""
        return sorted(self.sensitivities, key=lambda s: -abs(s.normalized))

    def table(self) -> str:
        """Plain-text ranked table."""
        lines = [f"{self.problem}: Vf = {self.Vf:.6g}, omega_f = {self.omega_f:.6g} "
                 f"({self.method})",
                 f"{'rank':>4}  {'parameter':<12} {'value':>11} {'dVf/dp':>13} "
                 f"{'normalised':>11}  {'domega/dp':>11}"]
        for i, s in enumerate(self.ranked(), 1):
            norm = f"{s.normalized:+.5f}" + ("*" if s.normalized_by == "unit" else " ")
            lines.append(f"{i:>4}  {s.name:<12} {s.value:>11.5g} {s.dVf_dp:>+13.6g} "
                         f"{norm:>12} {s.domega_dp:>+11.5g}")
        if any(s.normalized_by == "unit" for s in self.sensitivities):
            lines.append("* parameter is 0: normalised per unit change, (dVf/dp)/Vf")
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {"problem": self.problem, "params": dict(self.params), "Vf": self.Vf,
                "omega_f": self.omega_f, "method": self.method, "rel_step": self.rel_step,
                "sensitivities": [
                    {"name": s.name, "value": s.value, "dVf_dp": s.dVf_dp,
                     "domega_dp": s.domega_dp, "normalized": s.normalized,
                     "normalized_by": s.normalized_by, "difference": s.difference}
                    for s in self.ranked()]}


#: ``kind`` of a problem file without simulator parameters -> (what it is, the values to edit
#: instead, the command that gives its flutter speed)
_NO_PARAMETERS = {
    "wing": ("a wing file with records (kind = \"wing\")",
             "values (e.g. modes.frequencies_hz, modes.damping)",
             "`casflutter run RUN.toml` gives (its [problem] name the file, stages = [])"),
    "gaf": ("a wing file with a Q(ik) table (kind = \"gaf\")",
            "values (e.g. modes.frequencies_hz, modes.damping)",
            "`casflutter flutter FILE` gives"),
    "plant_family": ("a gridded plant family (kind = \"plant_family\")", "models",
                     "`casflutter flutter FILE` gives"),
}


def _parametric_truth(problem: str, params: Mapping[str, float] | None = None):
    """The truth of ``problem`` at ``params``, refused where it has no parameters.

    A wing or GAF file, or a gridded plant family, holds data (modes, records, ``Q(ik)``,
    state-space models), not a simulator whose parameters can be moved: the derivatives of
    its flutter speed are not defined.  The file's ``kind`` is read before anything else
    (no record or table is loaded for the refusal).

    Parameters
    ----------
    problem : str
        Truth problem name or problem file (:func:`casflutter.truth.load_problem`).
    params : mapping, optional
        Parameter changes of the nominal point.

    Returns
    -------
    AeroelasticTruth
        The truth, whose ``params.parameter_names()`` are the parameters to differentiate.

    Raises
    ------
    ConfigError
        A problem file without simulator parameters (what it is, and what to do instead),
        an unknown problem or parameter.
    """
    try:
        kind = problem_definition(problem).get("kind")
    except ConfigError:   # a built-in problem without problems/ or an unknown name:
        kind = None       # load_problem below says which
    if kind in _NO_PARAMETERS:
        what, values, command = _NO_PARAMETERS[kind]
        raise ConfigError(
            f"problem {problem!r} is {what}: it has no simulator parameters to differentiate, "
            "so flutter-speed sensitivities are not defined for it. Use a truth problem with "
            f"parameters ({', '.join(problem_names())}, or a problem file of kind = "
            "\"pitch_plunge\"; `casflutter problems` lists them), or edit the file's "
            f"{values} and compare the flutter speeds {command} for each version")
    model = load_problem(problem, dict(params or {}))
    if not callable(getattr(getattr(model, "params", None), "parameter_names", None)):
        raise ConfigError(f"problem {problem!r} ({type(model).__name__}) has no simulator "
                          "parameters to differentiate; use a truth problem with parameters "
                          f"({', '.join(problem_names())}, or a problem file of kind = "
                          "\"pitch_plunge\")")
    return model


def _step(value: float, rel_step: float) -> float:
    return rel_step * max(abs(value), 1.0)


def _matrix_derivative(problem: str, params: Mapping[str, float], name: str, V: float,
                       rel_step: float, A0: np.ndarray) -> tuple[np.ndarray, str]:
    """∂A/∂p at ``V``: central difference, or one-sided second order at a domain bound."""
    p0 = float(params[name])
    h = _step(p0, rel_step)

    def A_at(p):
        return load_problem(problem, {**params, name: p}).state_matrix(V)

    try:
        Ap, Am = A_at(p0 + h), A_at(p0 - h)
        dA, kind = (Ap - Am) / (2 * h), "central"
    except ConfigError:
        try:
            A1, A2 = A_at(p0 + h), A_at(p0 + 2 * h)
            dA, kind = (-3 * A0 + 4 * A1 - A2) / (2 * h), "forward"
        except ConfigError:
            A1, A2 = A_at(p0 - h), A_at(p0 - 2 * h)
            dA, kind = (3 * A0 - 4 * A1 + A2) / (2 * h), "backward"
    # the modal basis must move smoothly with p (no mode-shape sign flip or reordering)
    if np.linalg.norm(dA * h) > 1e-2 * max(np.linalg.norm(A0), 1.0):
        raise ConvergenceError(f"state matrix jumps when {name} moves by {h:g} (mode shapes "
                               "reordered or sign-flipped); use a smaller rel_step or a "
                               "value away from the modal crossing")
    return dA, kind


def flutter_sensitivity(problem: str = "typical_section",
                        parameters: Sequence[str] | None = None, *,
                        params: Mapping[str, float] | None = None,
                        V_range: tuple[float, float] = (0.02, 4.0), n_grid: int = 81,
                        rel_step: float = 1e-6) -> FlutterSensitivity:
    """Flutter-speed sensitivities of a truth problem by eigenvalue perturbation.

    Parameters
    ----------
    problem : str
        Truth problem name (``casflutter problems``).
    parameters : sequence of str, optional
        Parameters to differentiate (default: every parameter of the problem).
    params : mapping, optional
        Nominal parameter changes from the published case.
    V_range, n_grid :
        Flutter search (:func:`casflutter.aeroelastic.find_flutter`).
    rel_step : float
        Relative step of the differences of ``A`` (``h = rel_step · max(|p|, 1)``).

    Returns
    -------
    FlutterSensitivity

    Raises
    ------
    ConvergenceError
        No flutter speed in ``V_range`` (widen it), or a matrix that jumps with ``p``.
    ConfigError
        Unknown problem or parameter names, or a problem file without simulator parameters
        (a wing or GAF file, a gridded plant family: the message says what to do instead).
    """

    params = dict(params or {})
    model = _parametric_truth(problem, params)
    # the numbers are differentiated; lists (a rig's spring polynomials), words and tables
    # stay as the problem has them
    valid = [n for n in model.params.parameter_names()
             if isinstance(getattr(model.params, n), (int, float))
             and not isinstance(getattr(model.params, n), bool)]
    names = list(parameters) if parameters else valid
    bad = [n for n in names if n not in valid]
    if bad:
        others = [n for n in bad if n in model.params.parameter_names()]
        why = (f" ({', '.join(others)}: not a single number; change it with --set and compare "
               "the flutter speeds)" if others else "")
        raise ConfigError(f"unknown parameter(s) {bad} of {problem!r}{why}; valid: "
                          f"{', '.join(valid)}")
    nominal = {n: getattr(model.params, n) for n in valid}
    res = find_flutter(model.state_matrix, V_range, n_grid=n_grid,
                       omega=model.modal_structure().omega)
    if res.Vf is None:
        raise ConvergenceError(f"no flutter speed in V = {V_range}: {res.message}", res)
    Vf = float(res.Vf)
    A0 = model.state_matrix(Vf)
    lam, W, R = eig(A0, left=True, right=True)
    i = int(np.argmin(np.abs(lam - complex(res.flutter.eigenvalue))))
    lam_c, w, v = lam[i], W[:, i], R[:, i]
    wv = np.vdot(w, v)
    if abs(wv) < 1e-10 * np.linalg.norm(w) * np.linalg.norm(v):
        raise ConvergenceError("critical eigenvalue is defective (w^H v ≈ 0): the "
                               "perturbation formula does not apply")

    def dlam(dA):
        return complex(np.vdot(w, dA @ v) / wv)

    hV = _step(Vf, rel_step)
    dAdV = (model.state_matrix(Vf + hV) - model.state_matrix(Vf - hV)) / (2 * hV)
    dl_dV = dlam(dAdV)
    if dl_dV.real <= 0:
        raise ConvergenceError(f"Re dλ/dV = {dl_dV.real:.3g} is not positive at the crossing "
                               "(tangential crossing): Vf is not differentiable here")
    sens = []
    for n in names:
        dA, kind = _matrix_derivative(problem, nominal, n, Vf, rel_step, A0)
        dl_dp = dlam(dA)
        dVf = -dl_dp.real / dl_dV.real + 0.0  # no "-0" in the tables
        dom = float(np.sign(lam_c.imag) * (dl_dp.imag + dl_dV.imag * dVf)) + 0.0
        p0 = float(nominal[n])
        norm, by = ((p0 / Vf) * dVf, "value") if p0 != 0 else (dVf / Vf, "unit")
        sens.append(ParameterSensitivity(name=n, value=p0, dVf_dp=float(dVf),
                                         domega_dp=float(dom), dlambda_dp=dl_dp,
                                         normalized=float(norm), normalized_by=by,
                                         difference=kind))
    return FlutterSensitivity(problem=problem, params=nominal, Vf=Vf,
                              omega_f=float(abs(lam_c.imag)), eigenvalue=complex(lam_c),
                              dlambda_dV=dl_dV, sensitivities=tuple(sens), rel_step=rel_step,
                              flutter_message=res.message)


def flutter_speed_fd(problem: str, name: str, *, params: Mapping[str, float] | None = None,
                     step: float | None = None, V_range: tuple[float, float] = (0.02, 4.0),
                     n_grid: int = 81) -> float:
    """dVf/dp by central (or, at a domain bound, forward second-order) differences of the
    refined flutter speed itself -- the independent check of :func:`flutter_sensitivity`.

    ``step`` defaults to ``1e-4 · max(|p|, 1)``.
    """

    params = dict(params or {})
    p0 = float(getattr(_parametric_truth(problem, params).params, name))
    h = step if step is not None else 1e-4 * max(abs(p0), 1.0)

    def Vf(p):
        m = load_problem(problem, {**params, name: p})
        r = find_flutter(m.state_matrix, V_range, n_grid=n_grid, omega=m.modal_structure().omega)
        if r.Vf is None:
            raise ConvergenceError(f"no flutter speed at {name} = {p}: {r.message}", r)
        return float(r.Vf)

    try:
        return (Vf(p0 + h) - Vf(p0 - h)) / (2 * h)
    except ConfigError:
        return (-3 * Vf(p0) + 4 * Vf(p0 + h) - Vf(p0 + 2 * h)) / (2 * h)
