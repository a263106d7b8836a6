"""Two-stage identification of the HWL ROM: the public entry point :func:`identify`."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._nlp import NLPResult
from ..data import IOData
from ..errors import ConvergenceError, DataError, OrderError
from ._model import HWLModel, HWLStructure
from ._orders import HWLOrders
from ._refine import refine
from ._regression import stage1

__all__ = ["IdentificationSettings", "IdentificationResult", "FitReport", "identify",
           "fit_report"]

_CRITERIA = ("prediction", "simulation")


@dataclass(frozen=True)
class IdentificationSettings:
    """Choices of the two-stage identification.

    Attributes
    ----------
    criterion : {"prediction", "simulation"}
        Stage-2 criterion: mu-step-ahead prediction error (default; the criterion of the
        paper's two-stage method) or free-run simulation error (multiple shooting).
    refine : bool
        Run stage 2 (Ipopt).  ``False`` returns the stage-1 model.
    shooting_interval : int
        Samples per shooting interval for the simulation criterion.
    regularization : float
        Weight of ``||theta - theta_stage1||^2 / n_params`` added to the stage-2 cost
        (0: none).  Useful when some polynomial coefficients are poorly excited.
    scale_data : bool
        Identify on unit-RMS channels and transform the model back (exact: the HWL class
        is closed under scaling); improves conditioning of both stages.
    max_condition : float
        Largest condition number of the stage-1 regression accepted before the input is
        declared non-exciting.
    accept_acceptable : bool
        Accept Ipopt's ``Solved_To_Acceptable_Level`` as converged.
    ipopt_options : dict
        Flat CasADi/Ipopt options, e.g. ``{"ipopt.tol": 1e-10}``.
    """

    criterion: str = "prediction"
    refine: bool = True
    shooting_interval: int = 50
    regularization: float = 0.0
    scale_data: bool = True
    max_condition: float = 1e10
    accept_acceptable: bool = False
    ipopt_options: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.criterion not in _CRITERIA:
            raise ValueError(f"criterion={self.criterion!r} is not allowed: use one of "
                             f"{_CRITERIA}")
        if not (isinstance(self.shooting_interval, int) and self.shooting_interval >= 1):
            raise ValueError(f"shooting_interval={self.shooting_interval!r} must be an integer "
                             ">= 1")
        if not (np.isfinite(self.regularization) and self.regularization >= 0):
            raise ValueError(f"regularization={self.regularization!r} must be >= 0")


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

    Simulation starts from the measured first ``max_lag`` outputs of each record; scores
    exclude the first ``skip`` samples (default ``max_lag``).
    """
    if mode not in ("simulation", "prediction"):
        raise ValueError(f"mode={mode!r}: use 'simulation' or 'prediction'")
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
        The stage-1 (linear regression + rank-one SVD) model.
    fit : FitReport
        Free-run simulation fit on the estimation data.
    prediction_fit : FitReport
        mu-step-ahead prediction fit on the estimation data.
    success : bool
        Stage 2 converged (always True when stage 2 was skipped).
    return_status : str
        Ipopt's status verbatim (``"not run"`` without stage 2).
    iterations : int
    cost, cost_initial : float
        Stage-2 objective at the solution and at the stage-1 start (scaled units: half the
        mean squared error of the unit-RMS outputs).
    t_stage1, t_stage2, wall_time : float
        Seconds.
    condition_number : float
        Of the (column-normalised) stage-1 regression.
    settings : IdentificationSettings
    nlp : NLPResult or None
    """

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

    @property
    def n_params(self) -> int:
        return self.model.n_params

    def summary(self) -> str:
        """Human-readable report with the fit table."""
        m = self.model
        lines = [
            f"{m}",
            f"stage 1: {self.t_stage1:.3f} s (regression condition number "
            f"{self.condition_number:.3g})",
            f"stage 2 ({self.settings.criterion if self.settings.refine else 'skipped'}): "
            f"{self.t_stage2:.3f} s, {self.iterations} iterations, status "
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


def identify(data: IOData, orders=(3, 1, 1, 1, 2, 2), *,
             settings: IdentificationSettings | None = None, **kwargs: Any
             ) -> IdentificationResult:
    """Identify an HWL ROM (eq. 3--4) from input--output records in two stages.

    Stage 1: linear least squares on the over-parameterised regression and rank-one SVD
    factorisation (Bai 1998, extended to MIMO).  Stage 2: Ipopt refines all parameters from
    the stage-1 estimate (CasADi NLP, exact derivatives).

    Parameters
    ----------
    data : IOData
        Records with outputs y (N channels) and inputs u (N channels) and/or v.
    orders : tuple or HWLOrders
        ``(mu, na, nb, r, p, q)``; the paper uses ``(3, 1, 1, 1, 2, 2)``.
    settings : IdentificationSettings, optional
    **kwargs
        Shortcuts for fields of :class:`IdentificationSettings` (``criterion=...``).

    Returns
    -------
    IdentificationResult

    Raises
    ------
    DataError
        NaN/inf, too few samples, non-exciting input (with the condition number).
    OrderError
        Orders out of range or inconsistent with the data.
    ConvergenceError
        Stage 2 did not converge; the unconverged result is attached as ``.result``.

    Examples
    --------
    >>> from casflutter.ident import identify            # doctest: +SKIP
    >>> res = identify(data, (3, 1, 1, 1, 2, 2))         # doctest: +SKIP
    >>> print(res.summary())                             # doctest: +SKIP
    """
    if settings is None:
        settings = IdentificationSettings(**kwargs)
    elif kwargs:
        from dataclasses import replace
        settings = replace(settings, **kwargs)
    if not isinstance(data, IOData):
        raise DataError(f"data must be an IOData, got {type(data).__name__}; build one with "
                        "IOData.from_arrays(y=..., u=..., v=..., dt=...)")
    t_start = time.perf_counter()
    structure = HWLStructure(HWLOrders.from_tuple(orders), data.n_modes, data.has_u, data.has_v)
    _check_compatible(data, structure)
    if settings.scale_data:
        sy, su, sv = data.scales()
    else:
        N = data.n_modes
        sy, su, sv = np.ones(N), (np.ones(N) if data.has_u else None), (1.0 if data.has_v else None)
    work = data.scaled(sy, su, sv)
    names = dict(output_names=data.output_names, u_names=data.u_names, v_name=data.v_name)

    def to_physical(theta) -> HWLModel:
        scaled_model = HWLModel(structure, theta, data.dt)
        inv = lambda s: None if s is None else 1.0 / np.asarray(s)  # noqa: E731
        phys = scaled_model.rescaled(inv(sy), inv(su), inv(sv))
        return HWLModel(structure, phys.theta, data.dt, **names)

    t0 = time.perf_counter()
    s1 = stage1(structure, work, max_condition=settings.max_condition)
    t_stage1 = time.perf_counter() - t0
    initial = to_physical(s1.model.theta)
    nlp_result = None
    if settings.refine:
        t0 = time.perf_counter()
        theta, nlp_result, cost0 = refine(
            structure, work, s1.model.theta, criterion=settings.criterion,
            shooting_interval=settings.shooting_interval,
            regularization=settings.regularization, options=settings.ipopt_options,
            accept_acceptable=settings.accept_acceptable)
        t_stage2 = time.perf_counter() - t0
        success, status, iters, cost = (nlp_result.success, nlp_result.return_status,
                                        nlp_result.iterations, nlp_result.f)
    else:
        theta, t_stage2, success, status, iters = s1.model.theta, 0.0, True, "not run", 0
        cost0 = cost = float("nan")
    model = to_physical(theta) if np.all(np.isfinite(theta)) else initial
    fit = fit_report(model, data, "simulation")
    pfit = fit_report(model, data, "prediction")
    result = IdentificationResult(
        model=model, initial_model=initial, fit=fit, prediction_fit=pfit, success=success,
        return_status=status, iterations=iters, cost=cost, cost_initial=cost0,
        t_stage1=t_stage1, t_stage2=t_stage2, wall_time=time.perf_counter() - t_start,
        condition_number=s1.condition_number, settings=settings, nlp=nlp_result)
    if not success:
        raise ConvergenceError(
            f"stage 2 ({settings.criterion} criterion) did not converge: Ipopt returned "
            f"{status!r} after {iters} iterations (cost {cost0:.3e} -> {cost:.3e}); raise "
            "'ipopt.max_iter', add regularization, or check the excitation", result)
    return result
