"""Goodness of fit of an HWL model on records: free-run simulation or mu-step prediction
(the error of the paper's Fig. 7)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..data import IOData
from ..errors import ConfigError
from ._model import HWLModel

__all__ = ["FitReport", "fit_report"]


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
    The example ROM scored on longer records than it was identified from:

    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> held_out = cf.truth_records(truth, V0=1.8, dt=0.1, duration=90.0, band=(0.002, 1.0))
    >>> fit = cf.fit_report(cf.example_rom(), held_out)
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
