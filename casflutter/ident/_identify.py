"""Two-stage identification of the HWL ROM: the public entry point :func:`identify`.

The work is done in the identification's own coordinates (:class:`_Coordinates`: channels
centred when an offset is fitted, scaled to unit RMS), where stage 1 gives the start and
stage 2 (:func:`_stage2`) refines it; the model is then mapped back to physical units, scored
on the records (:func:`_score`) and its status turned into a return, a warning or an error
(:func:`_checked`).
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .._format import result_repr
from .._nlp import NLPResult
from .._threads import single_threaded
from ..data import IOData, Record
from ..errors import ConfigError, ConvergenceError, DataError, OrderError
from ._fit import FitReport, fit_report
from ._model import HWLModel, UnstableModelWarning
from ._orders import HWLOrders
from ._refine import refine
from ._regression import stage1
from ._settings import IdentificationSettings, IdentificationWarning
from ._simfit import FreeRunProblem, fit_simulation_error
from ._structure import HWLStructure

__all__ = ["IdentificationSettings", "IdentificationResult", "IdentificationWarning",
           "FitReport", "identify", "fit_report"]

log = logging.getLogger("casflutter.ident")

#: statuses returned as converged
_CONVERGED = {"Solve_Succeeded", "not run"}
_ACCEPTABLE = {"Solved_To_Acceptable_Level"}
_TIMEOUT = {"Maximum_WallTime_Exceeded"}
#: a simulation fit whose cost from the measured initial outputs exceeds this many times its
#: cost from the estimated ones is refitted with the initial outputs fixed
HIDDEN_MODE_FACTOR = 10.0


@dataclass(frozen=True)
class IdentificationResult:
    """Outcome of :func:`identify`.

    Attributes
    ----------
    model : HWLModel
        The identified ROM (physical units).
    initial_model : HWLModel
        The starting model: stage 1 (linear regression + rank-one SVD) or the ``initial=``
        model.
    fit : FitReport
        Free-run simulation fit on the estimation data (from the measured initial outputs).
    prediction_fit : FitReport
        mu-step-ahead prediction fit on the estimation data.
    success : bool
        Stage 2 converged (``Solve_Succeeded``; True when stage 2 was skipped).  False for
        an acceptable-level or time-limited result, which :func:`identify` returns with an
        :class:`IdentificationWarning`.
    return_status : str
        The solver's status verbatim (Ipopt's, or the same names from the Gauss--Newton
        solver; ``"Unstable_Free_Run"`` when the model's free run diverges on the estimation
        data; ``"not run"`` without stage 2).
    iterations : int
    cost, cost_initial : float
        Stage-2 criterion at the solution and at the starting model (``initial_model``),
        both evaluated the same way (scaled units: half the mean squared error of the
        unit-RMS outputs, plus the regularisation).  For the simulation criterion both are
        free runs (the starting model's from the measured initial outputs; the solver itself
        may start from the prediction-error optimum when that runs free better); ``inf`` when
        the free run diverges.
    t_stage1, t_stage2, wall_time : float
        Seconds.
    condition_number : float
        Of the (column-normalised) stage-1 regression (NaN when stage 1 was skipped).
    settings : IdentificationSettings
    nlp : NLPResult or None
        The Ipopt result, when Ipopt ran.
    initial_outputs : tuple of ndarray
        Estimated initial outputs of each record (physical units; simulation criterion).
    solver : str
        ``"ipopt"``, ``"gauss-newton"`` or ``"none"``.
    """

    __repr__ = result_repr

    model: HWLModel
    initial_model: HWLModel
    fit: FitReport
    prediction_fit: FitReport
    success: bool
    return_status: str
    iterations: int
    cost: float
    cost_initial: float
    t_stage1: float
    t_stage2: float
    wall_time: float
    condition_number: float
    settings: IdentificationSettings
    nlp: NLPResult | None = field(default=None, repr=False)
    initial_outputs: tuple = field(default=(), repr=False)
    solver: str = "none"

    @property
    def n_params(self) -> int:
        return self.model.n_params

    def summary(self) -> str:
        """Human-readable report with the fit table.

        Returns
        -------
        str
            Orders, solver status, costs, times and the fit error per output.
        """
        m = self.model
        stage2 = (f"{self.settings.criterion}, {self.solver}" if self.settings.refine
                  else "skipped")
        lines = [
            f"{m}",
            f"stage 1: {self.t_stage1:.3f} s (regression condition number "
            f"{self.condition_number:.3g})",
            f"stage 2 ({stage2}): {self.t_stage2:.3f} s, {self.iterations} iterations, status "
            f"{self.return_status}, cost {self.cost_initial:.4e} -> {self.cost:.4e}",
            "free-run fit on the estimation data:",
            self.fit.table(list(m.output_names)),
        ]
        return "\n".join(lines)


def _check_compatible(data: IOData, structure: HWLStructure) -> None:
    short = min(r.n_samples for r in data.records)
    if short <= structure.max_lag + 1:
        raise OrderError(f"orders {structure.orders} are inconsistent with the data: the largest "
                         f"lag {structure.max_lag} needs records longer than "
                         f"{structure.max_lag + 1} samples, the shortest has {short}")


def _means(data: IOData):
    cat = lambda arrs: np.concatenate(arrs, axis=0).mean(axis=0)  # noqa: E731
    my = cat([r.y for r in data.records])
    mu = cat([r.u for r in data.records]) if data.has_u else None
    mv = float(cat([r.v for r in data.records])) if data.has_v else None
    return my, mu, mv


def _shifted_data(data: IOData, my, mu, mv) -> IOData:
    recs = tuple(Record(r.y - my, None if r.u is None else r.u - mu,
                        None if r.v is None else r.v - mv, r.name) for r in data.records)
    return IOData(recs, data.dt, data.output_names, data.u_names, data.v_name, data.meta)


def _warn_offsets(data: IOData) -> None:
    """Warn when a channel's mean exceeds its standard deviation and no offset is fitted
    (a nonlinear response has a mean of its own: only a dominant one is flagged)."""
    for name, arrs in (("y", [r.y for r in data.records]),
                       ("u", [r.u for r in data.records] if data.has_u else []),
                       ("v", [r.v[:, None] for r in data.records] if data.has_v else [])):
        if not arrs:
            continue
        a = np.concatenate(arrs, axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            mean, std = np.abs(a.mean(axis=0)), a.std(axis=0)
        if np.any(mean > np.maximum(std, 1e-300)):
            warnings.warn(f"signal {name} has a mean of {float(mean.max()):.3g} against a "
                          f"standard deviation of {float(std[np.argmax(mean)]):.3g}; the HWL "
                          "model has no constant term: pass offset=True to identify it with one",
                          IdentificationWarning, stacklevel=4)
            return


def _initial_theta(initial, structure: HWLStructure, data: IOData):
    """Validate ``initial=`` and return it as an HWLModel in physical units."""
    if isinstance(initial, HWLModel):
        s = initial.structure
        want = (structure.orders, structure.n_modes, structure.has_u, structure.has_v)
        if (s.orders, s.n_modes, s.has_u, s.has_v) != want:
            raise OrderError(f"initial model {initial} does not match the identification: orders "
                             f"{structure.orders}, N={structure.n_modes}, inputs "
                             f"u={structure.has_u} v={structure.has_v}; give a model of that "
                             "structure or drop initial=")
        if s.constant and not structure.constant:
            raise ConfigError("the initial model has a constant term: pass offset=True")
        if structure.constant and not s.constant:
            initial = initial.shifted(np.zeros(structure.n_modes))
        if not np.isclose(initial.dt, data.dt, rtol=1e-9):
            raise ConfigError(f"the initial model has dt={initial.dt} but the data dt={data.dt}")
        return initial
    try:
        theta = np.asarray(initial, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ConfigError(f"initial must be an HWLModel or a parameter vector, got "
                          f"{type(initial).__name__}") from None
    if theta.size != structure.n_params or not np.all(np.isfinite(theta)):
        raise ConfigError(f"initial parameter vector has {theta.size} entries (finite: "
                          f"{bool(np.all(np.isfinite(theta)))}); the structure {structure.orders}"
                          f" with N={structure.n_modes} needs {structure.n_params} finite values")
    return HWLModel(structure, theta, data.dt)


def _free_run_failure(model: HWLModel, data: IOData) -> str | None:
    """Where the model's free run diverges on ``data`` (None when it does not)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)
        for rec in data.records:
            y = model.simulate(rec.u, rec.v, y0=rec.y[:model.max_lag])
            bad = ~np.all(np.isfinite(y), axis=1)
            if bad.any():
                return f"sample {int(np.argmax(bad))} of record {rec.name!r}"
    return None


def _simulation_start(problem: FreeRunProblem, structure, work, theta0, settings):
    """The start of the simulation-error fit: the better free run of ``theta0`` (stage 1)
    and of the prediction-error optimum reached from it (the paper's two-stage estimate,
    a cheap Ipopt solve), so that the free-run fit refines the two-stage method's result
    and rarely needs the segment continuation."""
    cost0 = problem.cost(problem.x0(theta0))
    opts = {"ipopt.max_iter": settings.iteration_limit}
    if settings.max_time is not None:
        opts["ipopt.max_wall_time"] = float(settings.max_time) / 4
    pred = refine(structure, work, theta0, criterion="prediction",
                  regularization=settings.regularization, options=opts)
    theta_p, res = pred.theta, pred.nlp
    if not np.all(np.isfinite(theta_p)):
        return theta0
    cost_p = problem.cost(problem.x0(theta_p))
    log.info("simulation fit: free-run cost %.4e from stage 1, %.4e from the prediction-error "
             "optimum (%s)", cost0, cost_p, res.return_status)
    return theta_p if cost_p < cost0 else theta0


def identify(data: IOData, orders=(3, 1, 1, 1, 2, 2), *,
             settings: IdentificationSettings | None = None, initial=None, **kwargs: Any
             ) -> IdentificationResult:
    """Identify an HWL ROM (eq. 3--4) from input--output records in two stages.

    Stage 1: linear least squares on the over-parameterised regression and rank-one SVD
    factorisation (Bai 1998, extended to MIMO), unless ``initial`` gives the start.
    Stage 2 refines all parameters: by the mu-step prediction error (Ipopt, exact Hessian of
    a QR-reduced problem) or by the free-run simulation error (Levenberg--Marquardt with exact
    sensitivities through the recursion of eq. 3, the initial outputs of each record
    estimated too; or Ipopt on a multiple-shooting NLP).

    Parameters
    ----------
    data : IOData
        Records with outputs y (N channels) and inputs u (N channels) and/or v.
    orders : tuple, str or HWLOrders
        ``(mu, na, nb, r, p, q)``; the paper uses ``(3, 1, 1, 1, 2, 2)``.
    settings : IdentificationSettings, optional
        Stage settings (criterion, regularisation, solver, budgets); ``**kwargs`` override
        its fields.
    initial : HWLModel or array, optional
        Starting model (physical units) of the same structure; skips stage 1.
    **kwargs
        Fields of :class:`IdentificationSettings` (``criterion="simulation"``, ...).

    Returns
    -------
    IdentificationResult
        Converged, or returned with an :class:`IdentificationWarning` and its status when
        stage 2 stopped at the acceptable level or at ``max_time``.

    Raises
    ------
    ConfigError
        An unknown or invalid setting, or an unusable ``initial`` (before any work).
    DataError
        ``data`` not an IOData, too few samples, non-exciting input (with the condition number).
    OrderError
        Orders missing, not integers, out of range or inconsistent with the data.
    ConvergenceError
        Stage 2 did not converge, or the identified model's free run diverges on the
        estimation data (status ``Unstable_Free_Run``), or its free-run fit is not a finite
        number for some output (status ``Non_Finite_Fit``); the result is attached as
        ``.result``.

    See Also
    --------
    identify_common_denominator : the linear ROM with one scalar denominator.
    fit_report : the free-run or prediction fit of a model on records.
    realize : the continuous linear ROM Σf of the identified model.

    Examples
    --------
    A known two-mode HWL model with the paper's orders, recovered from its chirp records:

    >>> from casflutter.ident import random_hwl_model, synthetic_data
    >>> import casflutter as cf
    >>> known = random_hwl_model(2, (3, 1, 1, 1, 2, 2), seed=1)
    >>> data = synthetic_data(known, 2000, seed=2)
    >>> result = cf.identify(data, (3, 1, 1, 1, 2, 2))
    >>> result.success, bool(max(result.fit.error_percent) < 0.1)
    (True, True)
    """
    settings = IdentificationSettings.build(settings, **kwargs)
    # single-threaded BLAS: the factorisations here are too small to gain from threads on a
    # shared machine, and the result then does not depend on the thread count
    with single_threaded():
        return _identify(data, orders, settings, initial)

@dataclass(frozen=True)
class _Coordinates:
    """The identification's working coordinates and the maps between them and physical units.

    The records are centred when an offset is fitted (``means``) and scaled to unit RMS
    (``sy, su, sv``, ones without ``scale_data``); the HWL class is closed under both, so a
    model maps exactly between the two (:meth:`HWLModel.rescaled`, :meth:`HWLModel.shifted`).
    """

    structure: HWLStructure
    dt: float
    names: dict
    sy: np.ndarray
    su: np.ndarray | None
    sv: float | None
    means: tuple | None    # (my, mu, mv) when an offset is fitted

    @classmethod
    def of(cls, data: IOData, structure: HWLStructure, settings: IdentificationSettings):
        """The coordinates of ``data`` and the records in them."""
        means = _means(data) if settings.offset else None
        centred = data if means is None else _shifted_data(data, *means)
        if settings.scale_data:
            sy, su, sv = centred.scales()
        else:
            N = data.n_modes
            sy, su, sv = (np.ones(N), (np.ones(N) if data.has_u else None),
                          (1.0 if data.has_v else None))
        names = dict(output_names=data.output_names, u_names=data.u_names, v_name=data.v_name)
        return cls(structure, data.dt, names, sy, su, sv, means), centred.scaled(sy, su, sv)

    def to_physical(self, theta) -> HWLModel:
        """The model of working parameters ``theta`` in physical units."""
        inv = lambda s: None if s is None else 1.0 / np.asarray(s)  # noqa: E731
        phys = HWLModel(self.structure, theta, self.dt).rescaled(inv(self.sy), inv(self.su),
                                                                 inv(self.sv))
        if self.means is not None:
            my, mu, mv = self.means
            phys = phys.shifted(-my, None if mu is None else -mu, None if mv is None else -mv)
        return HWLModel(self.structure, phys.theta, self.dt, **self.names)

    def to_work(self, model: HWLModel) -> np.ndarray:
        """The working parameters of a model in physical units."""
        if self.means is not None:
            model = model.shifted(*self.means)
        return model.rescaled(self.sy, self.su, self.sv).theta

    def outputs(self, initial_outputs) -> tuple:
        """Initial outputs of the records in physical units."""
        shift = self.means[0] if self.means is not None else 0.0
        return tuple(ic * self.sy + shift for ic in initial_outputs)


@dataclass(frozen=True)
class _Stage2:
    """Outcome of stage 2 in working coordinates (see :class:`IdentificationResult`)."""

    theta: np.ndarray
    success: bool
    status: str
    iterations: int
    cost_initial: float
    cost: float
    solver: str = "none"
    initial_outputs: tuple = ()
    nlp: NLPResult | None = None


def _start(structure, work, coords: _Coordinates, start_model, settings):
    """Stage 1 (or the given start): working parameters, regression condition number and the
    starting model in physical units."""
    if start_model is not None:
        initial = HWLModel(structure, start_model.theta, coords.dt, **coords.names)
        return coords.to_work(start_model), float("nan"), initial
    try:
        s1 = stage1(structure, work, max_condition=settings.max_condition)
    except np.linalg.LinAlgError as exc:
        raise DataError(f"the stage-1 regression could not be solved ({exc}); check that "
                        "the data are finite, scaled and exciting") from None
    return s1.model.theta, s1.condition_number, coords.to_physical(s1.model.theta)


def _stage2_gauss_newton(structure, work, theta0, settings, given_start: bool) -> _Stage2:
    """Free-run fit by Levenberg--Marquardt (initial outputs estimated unless told not to),
    refitted with the measured initial outputs when the estimated ones hide a mode."""
    problem = FreeRunProblem(structure, work, settings.regularization, theta0,
                             estimate_initial=settings.estimate_initial)
    start = (theta0 if given_start
             else _simulation_start(problem, structure, work, theta0, settings))
    lm = fit_simulation_error(problem, start, max_iter=settings.iteration_limit,
                              tol=settings.tol, max_time=settings.max_time)
    if settings.estimate_initial and (lm.success or lm.return_status in _ACCEPTABLE):
        # estimated initial outputs can hide an unstable or badly damped mode that the
        # input does not excite: from the measured outputs such a model runs far worse
        measured = problem.cost(problem.x0(lm.theta))
        if not measured <= HIDDEN_MODE_FACTOR * lm.cost + 1e-300:
            log.info("simulation fit: from the measured initial outputs the cost is %.4e "
                     "(estimated: %.4e); refitting with them fixed", measured, lm.cost)
            fixed = FreeRunProblem(structure, work, settings.regularization, theta0,
                                   estimate_initial=False)
            lm2 = fit_simulation_error(fixed, lm.theta, max_iter=settings.iteration_limit,
                                       tol=settings.tol, max_time=settings.max_time)
            lm = replace(lm2, iterations=lm.iterations + lm2.iterations)
    cost0 = problem.cost(problem.x0(theta0))
    return _Stage2(lm.theta, lm.success, lm.return_status, lm.iterations, cost0, lm.cost,
                   "gauss-newton", tuple(lm.initial_outputs))


def _stage2_ipopt(structure, work, theta0, settings) -> _Stage2:
    """Ipopt on the prediction-error NLP or the multiple-shooting simulation NLP."""
    opts = dict(settings.ipopt_options)
    if settings.max_iter is not None:
        opts.setdefault("ipopt.max_iter", int(settings.max_iter))
    if settings.max_time is not None:
        opts.setdefault("ipopt.max_wall_time", float(settings.max_time))
    r = refine(structure, work, theta0, criterion=settings.criterion,
               shooting_interval=settings.shooting_interval,
               regularization=settings.regularization, options=opts)
    return _Stage2(r.theta, r.nlp.success, r.nlp.return_status, r.nlp.iterations,
                   r.cost_initial, r.cost, "ipopt", nlp=r.nlp)


def _stage2(structure, work, theta0, settings, given_start: bool) -> _Stage2:
    """Stage 2 by the solver the settings choose (none when ``refine`` is off)."""
    if not settings.refine:
        return _Stage2(theta0, True, "not run", 0, float("nan"), float("nan"))
    if settings.criterion == "simulation" and settings.solver in ("auto", "gauss-newton"):
        return _stage2_gauss_newton(structure, work, theta0, settings, given_start)
    return _stage2_ipopt(structure, work, theta0, settings)


def _score(model: HWLModel, data: IOData):
    """Free-run and prediction fits of the identified model, where its free run diverges
    (``None`` when it does not) and the outputs whose fit is not a finite number."""
    where = _free_run_failure(model, data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)
        fit = fit_report(model, data, "simulation")
    pfit = fit_report(model, data, "prediction")
    non_finite = [name for name, e, r in zip(model.output_names, fit.error_percent, fit.nrmse)
                  if not (np.isfinite(e) and np.isfinite(r))]
    return fit, pfit, where, non_finite


def _identify(data, orders, settings: IdentificationSettings, initial) -> IdentificationResult:
    if not isinstance(data, IOData):
        raise DataError(f"data must be an IOData, got {type(data).__name__}; build one with "
                        "IOData.from_arrays(y=..., u=..., v=..., dt=...)")
    t_start = time.perf_counter()
    o = HWLOrders.from_tuple(orders)
    constant = settings.offset or (isinstance(initial, HWLModel) and initial.structure.constant)
    structure = HWLStructure(o, data.n_modes, data.has_u, data.has_v, constant)
    _check_compatible(data, structure)
    start_model = None if initial is None else _initial_theta(initial, structure, data)
    if not settings.offset:
        _warn_offsets(data)
    coords, work = _Coordinates.of(data, structure, settings)
    t0 = time.perf_counter()
    theta0, cond, initial_model = _start(structure, work, coords, start_model, settings)
    t_stage1 = time.perf_counter() - t0
    t0 = time.perf_counter()
    s2 = _stage2(structure, work, theta0, settings, given_start=start_model is not None)
    t_stage2 = time.perf_counter() - t0
    success, status = s2.success, s2.status
    if np.all(np.isfinite(s2.theta)):
        model = coords.to_physical(s2.theta)
    else:
        model, success, status = initial_model, False, "Invalid_Number_Detected"
    fit, pfit, where, non_finite = _score(model, data)
    if where is not None:
        success, status = False, "Unstable_Free_Run"
    elif non_finite:  # a fit that cannot be scored is never a success
        success, status = False, "Non_Finite_Fit"
    result = IdentificationResult(
        model=model, initial_model=initial_model, fit=fit, prediction_fit=pfit, success=success,
        return_status=status, iterations=s2.iterations, cost=float(s2.cost),
        cost_initial=float(s2.cost_initial), t_stage1=t_stage1, t_stage2=t_stage2,
        wall_time=time.perf_counter() - t_start, condition_number=cond, settings=settings,
        nlp=s2.nlp, initial_outputs=coords.outputs(s2.initial_outputs), solver=s2.solver)
    return _checked(result, where, non_finite)


def _checked(result: IdentificationResult, where, non_finite) -> IdentificationResult:
    """The result when converged; with an :class:`IdentificationWarning` when stopped at the
    acceptable level or the time limit; otherwise a :class:`ConvergenceError` carrying it."""
    settings, status, iters = result.settings, result.return_status, result.iterations
    cost0, cost = result.cost_initial, result.cost
    if status in _CONVERGED:
        return result
    if where is not None:
        raise ConvergenceError(
            f"the identified model is unstable in free run on the estimation data: its "
            f"simulation diverges at {where} (stage 2: {settings.criterion} criterion, "
            f"{iters} iterations); "
            + ("use criterion='simulation', " if settings.criterion == "prediction" else "")
            + "lower the orders or add regularization", result)
    if non_finite:
        raise ConvergenceError(
            f"the identified model's free-run fit is not a finite number for output(s) "
            f"{', '.join(map(str, non_finite))} (error % "
            f"{', '.join(f'{e:.4g}' for e in result.fit.error_percent)}; stage 2: "
            f"{settings.criterion} criterion, {iters} iterations); lower the orders, add "
            "regularization or check that every output varies", result)
    if status in _ACCEPTABLE and settings.accept_acceptable:
        warnings.warn(f"stage 2 stopped at the acceptable level ({status}, {iters} iterations, "
                      f"cost {cost0:.3e} -> {cost:.3e}); the result is returned",
                      IdentificationWarning, stacklevel=4)
        return result
    if status in _TIMEOUT:
        warnings.warn(f"stage 2 reached max_time={settings.max_time} s after {iters} "
                      f"iterations (cost {cost0:.3e} -> {cost:.3e}); the best iterate is "
                      "returned", IdentificationWarning, stacklevel=4)
        return result
    raise ConvergenceError(
        f"stage 2 ({settings.criterion} criterion, {result.solver}) did not converge: status "
        f"{status!r} after {iters} iterations (cost {cost0:.3e} -> {cost:.3e}); raise "
        "max_iter, add regularization, or check the excitation", result)
