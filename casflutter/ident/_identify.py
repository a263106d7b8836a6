"""Two-stage identification of the HWL ROM: the public entry point :func:`identify`."""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from .._format import result_repr
from .._threads import single_threaded

from .._nlp import DEFAULT_IPOPT_OPTIONS, NLPResult
from ..data import IOData, Record
from ..errors import ConfigError, ConvergenceError, DataError, OrderError
from ._model import HWLModel, HWLStructure, UnstableModelWarning
from ._orders import HWLOrders
from ._refine import refine
from ._regression import stage1
from ._simfit import FreeRunProblem, fit_simulation_error

__all__ = ["IdentificationSettings", "IdentificationResult", "IdentificationWarning",
           "FitReport", "identify", "fit_report"]

_CRITERIA = ("prediction", "simulation")
log = logging.getLogger("casflutter.ident")


_SOLVERS = ("auto", "gauss-newton", "ipopt")
#: statuses returned as converged
_CONVERGED = {"Solve_Succeeded", "not run"}
_ACCEPTABLE = {"Solved_To_Acceptable_Level"}
_TIMEOUT = {"Maximum_WallTime_Exceeded"}
#: a simulation fit whose cost from the measured initial outputs exceeds this many times its
#: cost from the estimated ones is refitted with the initial outputs fixed
HIDDEN_MODE_FACTOR = 10.0


class IdentificationWarning(UserWarning):
    """An identification returned a result that is not fully converged (acceptable level,
    time limit); the result's ``return_status`` says which."""


def _is_bool(x) -> bool:
    return isinstance(x, (bool, np.bool_))


def _is_real(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not _is_bool(x)


@dataclass(frozen=True)
class IdentificationSettings:
    """Choices of the two-stage identification (every field checked on construction).

    Attributes
    ----------
    criterion : {"prediction", "simulation"}
        Stage-2 criterion: mu-step-ahead prediction error (default; the criterion of the
        paper's two-stage method, fast) or free-run simulation error (the criterion to use
        when the model will run free: flutter loop, LCO, suppression).
    solver : {"auto", "gauss-newton", "ipopt"}
        Stage-2 solver for the simulation criterion: Levenberg--Marquardt with exact forward
        sensitivities (``"gauss-newton"``, what ``"auto"`` picks) or Ipopt on a
        multiple-shooting NLP (``"ipopt"``).  The prediction criterion always uses Ipopt.
    refine : bool
        Run stage 2.  ``False`` returns the stage-1 model.
    shooting_interval : int
        Samples per shooting interval of the Ipopt simulation NLP.
    regularization : float
        Weight of ``||theta - theta_start||^2 / n_params`` added to the stage-2 cost
        (0: none; finite and >= 0).
    scale_data : bool
        Identify on unit-RMS channels and transform the model back (exact: the HWL class
        is closed under scaling); improves conditioning of both stages.
    offset : bool
        Give the model a constant term and identify on centred data (the means of every
        channel removed, then put back into the model exactly: :meth:`HWLModel.shifted`).
        Use it for data with offsets (raw sensor records); the paper's model has none.
    max_condition : float
        Largest condition number of the stage-1 regression accepted before the input is
        declared non-exciting.
    accept_acceptable : bool
        Return a stage 2 that stopped at the *acceptable* level
        (``Solved_To_Acceptable_Level``) with an :class:`IdentificationWarning` (default);
        ``False`` raises :class:`~casflutter.errors.ConvergenceError` instead.
    max_iter : int or None
        Stage-2 iterations (Ipopt iterations or Jacobian evaluations); ``None`` takes the
        package default ``casflutter._nlp.DEFAULT_IPOPT_OPTIONS["ipopt.max_iter"]`` for both
        solvers.  An ``"ipopt.max_iter"`` in ``ipopt_options`` wins for Ipopt.
    max_time : float or None
        Wall-time budget of stage 2 in seconds: the best iterate so far is returned with
        status ``Maximum_WallTime_Exceeded`` and an :class:`IdentificationWarning`.
    tol : float
        Relative tolerance of the Gauss--Newton solver (cost decrease, step, gradient).
    estimate_initial : bool
        Estimate the initial outputs of each record with the parameters (Gauss--Newton
        solver); ``False`` starts every record from its measured outputs.
    ipopt_options : dict
        Flat CasADi/Ipopt options, e.g. ``{"ipopt.tol": 1e-10}`` (defaults in
        ``casflutter._nlp.DEFAULT_IPOPT_OPTIONS``, the one place they are set).
    """

    criterion: str = "prediction"
    solver: str = "auto"
    refine: bool = True
    shooting_interval: int = 50
    regularization: float = 0.0
    scale_data: bool = True
    offset: bool = False
    max_condition: float = 1e10
    accept_acceptable: bool = True
    max_iter: int | None = None
    max_time: float | None = None
    tol: float = 1e-8
    estimate_initial: bool = True
    ipopt_options: dict = field(default_factory=dict)

    def __post_init__(self):
        def bad(name, allowed):
            raise ConfigError(f"identification setting {name}={getattr(self, name)!r} is not "
                              f"allowed: {allowed}")

        if self.criterion not in _CRITERIA:
            bad("criterion", f"use one of {_CRITERIA}")
        if self.solver not in _SOLVERS:
            bad("solver", f"use one of {_SOLVERS}")
        for name in ("refine", "scale_data", "offset", "accept_acceptable", "estimate_initial"):
            if not _is_bool(getattr(self, name)):
                bad(name, "give True or False")
        if not (isinstance(self.shooting_interval, (int, np.integer))
                and not _is_bool(self.shooting_interval) and self.shooting_interval >= 1):
            bad("shooting_interval", "give an integer >= 1")
        if not (_is_real(self.regularization) and np.isfinite(self.regularization)
                and self.regularization >= 0):
            bad("regularization", "give a finite number >= 0 (0: no regularisation)")
        if not (_is_real(self.max_condition) and self.max_condition > 1):
            bad("max_condition", "give a number > 1")
        if self.max_iter is not None and not (isinstance(self.max_iter, (int, np.integer))
                                              and not _is_bool(self.max_iter)
                                              and self.max_iter >= 0):
            bad("max_iter", "give an integer >= 0 or None (package default)")
        if self.max_time is not None and not (_is_real(self.max_time)
                                              and np.isfinite(self.max_time)
                                              and self.max_time > 0):
            bad("max_time", "give a positive number of seconds or None (no limit)")
        if not (_is_real(self.tol) and 0 < self.tol < 1):
            bad("tol", "give a number in (0, 1)")
        if not (isinstance(self.ipopt_options, dict)
                and all(isinstance(k, str) for k in self.ipopt_options)):
            bad("ipopt_options", "give a dict of option names (str) to values, e.g. "
                "{'ipopt.tol': 1e-10}")

    @property
    def iteration_limit(self) -> int:
        """``max_iter`` or the package default."""
        return int(DEFAULT_IPOPT_OPTIONS["ipopt.max_iter"] if self.max_iter is None
                   else self.max_iter)

    @classmethod
    def build(cls, settings=None, **kwargs) -> "IdentificationSettings":
        """Settings from an instance and/or keyword overrides; unknown keys are a
        :class:`~casflutter.errors.ConfigError` listing the known ones.

        Parameters
        ----------
        settings : IdentificationSettings, optional
            Settings to start from (default: the defaults).
        **kwargs
            Fields to replace, by name.

        Returns
        -------
        IdentificationSettings
        """
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(kwargs) - set(names))
        if unknown:
            raise ConfigError(f"unknown identification setting(s) {unknown}: the settings are "
                              f"{names}")
        if settings is None:
            return cls(**kwargs)
        if not isinstance(settings, cls):
            raise ConfigError(f"settings must be an IdentificationSettings, got "
                              f"{type(settings).__name__}")
        return replace(settings, **kwargs) if kwargs else settings


@dataclass(frozen=True)
class FitReport:
    """Per-output goodness of fit.

    Attributes
    ----------
    mode : str
        ``"simulation"`` (free run) or ``"prediction"`` (mu steps ahead).
    error_percent : ndarray (N,)
        ``100 ||y - yhat|| / ||y||`` per output, as the error of the paper's Fig. 7.
    nrmse : ndarray (N,)
        ``RMS(y - yhat) / std(y)`` per output (1 is no better than the mean).
    rms_error : ndarray (N,)
        ``RMS(y - yhat)`` per output, in the output's units.
    skip : int
        Leading samples of each record excluded from the scores.
    """

    __repr__ = result_repr

    mode: str
    error_percent: np.ndarray
    nrmse: np.ndarray
    rms_error: np.ndarray
    skip: int

    def table(self, names=None) -> str:
        """A small text table."""
        names = names or [f"y{i + 1}" for i in range(len(self.error_percent))]
        lines = [f"{'output':>10} {'error %':>10} {'NRMSE':>10} {'RMS error':>12}"]
        for n, e, r, s in zip(names, self.error_percent, self.nrmse, self.rms_error):
            lines.append(f"{n:>10} {e:10.4f} {r:10.5f} {s:12.4e}")
        return "\n".join(lines)


def fit_report(model: HWLModel, data: IOData, mode: str = "simulation",
               skip: int | None = None) -> FitReport:
    """Score ``model`` on ``data`` by free-run simulation or mu-step prediction.

    Simulation (eq. 3 with the model's own past outputs fed back) starts from the measured
    first ``max_lag`` outputs of each record; prediction feeds the measured outputs back
    (the mu-step predictor of eq. 4).

    Parameters
    ----------
    model : HWLModel
        The identified model.
    data : IOData
        Records to score it on (the same channels as the model).
    mode : {"simulation", "prediction"}
        Free run or mu-step prediction.
    skip : int, optional
        Samples excluded at the start of each record (default and minimum ``max_lag``).

    Returns
    -------
    FitReport
        Per-output error percentage (the paper's Fig. 7), NRMSE and RMS error.

    Raises
    ------
    ConfigError
        ``mode`` is neither ``"simulation"`` nor ``"prediction"``.

    See Also
    --------
    identify : the identification whose result carries this report.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> data = cf.truth_records(truth, V0=1.8, dt=0.1, duration=60.0, band=(0.002, 1.0))
    >>> rom = cf.identify_common_denominator(data).model
    >>> fit = cf.fit_report(rom, data)
    >>> bool(fit.error_percent.max() < 1.0)
    True
    """
    if mode not in ("simulation", "prediction"):
        raise ConfigError(f"fit_report mode={mode!r} is not allowed: use 'simulation' or "
                          "'prediction'")
    skip = model.max_lag if skip is None else max(int(skip), model.max_lag)
    err, ref = [], []
    for rec in data.records:
        if mode == "simulation":
            yhat = model.simulate(rec.u, rec.v, y0=rec.y[:model.max_lag])
        else:
            yhat = model.predict(rec.y, rec.u, rec.v)
        err.append(rec.y[skip:] - yhat[skip:])
        ref.append(rec.y[skip:])
    e = np.vstack(err)
    y = np.vstack(ref)
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = 100 * np.linalg.norm(e, axis=0) / np.linalg.norm(y, axis=0)
        nrmse = np.sqrt(np.mean(e ** 2, axis=0)) / np.std(y, axis=0)
    return FitReport(mode, pct, nrmse, np.sqrt(np.mean(e ** 2, axis=0)), skip)


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
    theta_p, res, *_ = refine(structure, work, theta0, criterion="prediction",
                              regularization=settings.regularization, options=opts)
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
    if settings.offset:
        my, mu, mv = _means(data)
        centred = _shifted_data(data, my, mu, mv)
    else:
        _warn_offsets(data)
        centred = data
    if settings.scale_data:
        sy, su, sv = centred.scales()
    else:
        N = data.n_modes
        sy, su, sv = np.ones(N), (np.ones(N) if data.has_u else None), (1.0 if data.has_v else None)
    work = centred.scaled(sy, su, sv)
    names = dict(output_names=data.output_names, u_names=data.u_names, v_name=data.v_name)
    inv = lambda s: None if s is None else 1.0 / np.asarray(s)  # noqa: E731

    def to_physical(theta) -> HWLModel:
        phys = HWLModel(structure, theta, data.dt).rescaled(inv(sy), inv(su), inv(sv))
        if settings.offset:
            phys = phys.shifted(-my, None if mu is None else -mu, None if mv is None else -mv)
        return HWLModel(structure, phys.theta, data.dt, **names)

    def to_work(model: HWLModel) -> np.ndarray:
        if settings.offset:
            model = model.shifted(my, mu, mv)
        return model.rescaled(sy, su, sv).theta

    t0 = time.perf_counter()
    if start_model is None:
        try:
            s1 = stage1(structure, work, max_condition=settings.max_condition)
        except np.linalg.LinAlgError as exc:
            raise DataError(f"the stage-1 regression could not be solved ({exc}); check that "
                            "the data are finite, scaled and exciting") from None
        theta0, cond = s1.model.theta, s1.condition_number
        initial_model = to_physical(theta0)
    else:
        theta0, cond = to_work(start_model), float("nan")
        initial_model = HWLModel(structure, start_model.theta, data.dt, **names)
    t_stage1 = time.perf_counter() - t0
    nlp_result, ics, solver = None, (), "none"
    t0 = time.perf_counter()
    if not settings.refine:
        theta, success, status, iters = theta0, True, "not run", 0
        cost0 = cost = float("nan")
    elif settings.criterion == "simulation" and settings.solver in ("auto", "gauss-newton"):
        solver = "gauss-newton"
        problem = FreeRunProblem(structure, work, settings.regularization, theta0,
                                 estimate_initial=settings.estimate_initial)
        start = (theta0 if start_model is not None
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
        lm = replace(lm, cost_initial=problem.cost(problem.x0(theta0)))
        theta, success, status, iters = lm.theta, lm.success, lm.return_status, lm.iterations
        cost0, cost = lm.cost_initial, lm.cost
        ics = tuple(ic * sy + (my if settings.offset else 0.0) for ic in lm.initial_outputs)
    else:
        solver = "ipopt"
        opts = dict(settings.ipopt_options)
        if settings.max_iter is not None:
            opts.setdefault("ipopt.max_iter", int(settings.max_iter))
        if settings.max_time is not None:
            opts.setdefault("ipopt.max_wall_time", float(settings.max_time))
        theta, nlp_result, cost0, cost, ic_work = refine(
            structure, work, theta0, criterion=settings.criterion,
            shooting_interval=settings.shooting_interval,
            regularization=settings.regularization, options=opts)
        success, status, iters = (nlp_result.success, nlp_result.return_status,
                                  nlp_result.iterations)
        ics = tuple(ic * sy + (my if settings.offset else 0.0) for ic in ic_work)
    t_stage2 = time.perf_counter() - t0
    if np.all(np.isfinite(theta)):
        model = to_physical(theta)
    else:
        model, success, status = initial_model, False, "Invalid_Number_Detected"
    where = _free_run_failure(model, data)
    if where is not None:
        success, status = False, "Unstable_Free_Run"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)
        fit = fit_report(model, data, "simulation")
    pfit = fit_report(model, data, "prediction")
    non_finite = [name for name, e, r in zip(model.output_names, fit.error_percent, fit.nrmse)
                  if not (np.isfinite(e) and np.isfinite(r))]
    if non_finite and where is None:  # a fit that cannot be scored is never a success
        success, status = False, "Non_Finite_Fit"
    result = IdentificationResult(
        model=model, initial_model=initial_model, fit=fit, prediction_fit=pfit, success=success,
        return_status=status, iterations=iters, cost=float(cost), cost_initial=float(cost0),
        t_stage1=t_stage1, t_stage2=t_stage2, wall_time=time.perf_counter() - t_start,
        condition_number=cond, settings=settings, nlp=nlp_result, initial_outputs=ics,
        solver=solver)
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
            f"{', '.join(f'{e:.4g}' for e in fit.error_percent)}; stage 2: "
            f"{settings.criterion} criterion, {iters} iterations); lower the orders, add "
            "regularization or check that every output varies", result)
    if status in _ACCEPTABLE and settings.accept_acceptable:
        warnings.warn(f"stage 2 stopped at the acceptable level ({status}, {iters} iterations, "
                      f"cost {cost0:.3e} -> {cost:.3e}); the result is returned",
                      IdentificationWarning, stacklevel=3)
        return result
    if status in _TIMEOUT:
        warnings.warn(f"stage 2 reached max_time={settings.max_time} s after {iters} "
                      f"iterations (cost {cost0:.3e} -> {cost:.3e}); the best iterate is "
                      "returned", IdentificationWarning, stacklevel=3)
        return result
    raise ConvergenceError(
        f"stage 2 ({settings.criterion} criterion, {solver}) did not converge: status "
        f"{status!r} after {iters} iterations (cost {cost0:.3e} -> {cost:.3e}); raise "
        "max_iter, add regularization, or check the excitation", result)
