"""The settings of the two-stage identification (:class:`IdentificationSettings`), checked on
construction, and the warning of a result that is not fully converged."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from .._nlp import DEFAULT_IPOPT_OPTIONS
from ..errors import ConfigError

__all__ = ["IdentificationSettings", "IdentificationWarning"]

_CRITERIA = ("prediction", "simulation")
_SOLVERS = ("auto", "gauss-newton", "ipopt")


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
