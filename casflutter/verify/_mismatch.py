"""How far a model family's control-to-measurement response lies from a reference's.

A controller certified on a model (a ROM loop) holds the plant it stands for (the wing) only
as far as the two respond alike where the loop needs them to.  The measure here is the
relative error of the frequency response from the controls to the measurements,

``e(ω, V) = σmax(G_ref(jω, V) − G(jω, V)) / σmax(G(jω, V))``,

the smallest ``δ`` such that ``G_ref = G + Δ`` with ``σmax(Δ) ≤ δ σmax(G)``: 0.1 is a gain
error of 10 % or a phase error of about 6° in the largest channel.  A certificate on the
model carries over where this error is small against the loop's margins at the frequencies
where the closed loop is critical; where it is large (for the seed wing's ROMs: below the
first bending mode at high speed), a controller that relies on those frequencies may hold
the model and not the plant.  Computed with python-control's state-space evaluation; shares
no code with :mod:`casflutter.design`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import DimensionError
from ._margins import omega_grid_of

__all__ = ["ModelMismatch", "model_mismatch"]


@dataclass(frozen=True)
class ModelMismatch:
    """The relative response error of a model family against a reference family.

    Attributes
    ----------
    model, reference : str
        The families' names.
    speeds : ndarray, shape (ns,)
        Speeds compared, in the families' speed unit.
    omega : ndarray, shape (nw,)
        Frequencies [rad per the families' time unit].
    relative_error : ndarray, shape (ns, nw)
        ``σmax(G_ref − G) / σmax(G)`` at each speed and frequency (module docstring; ``nan``
        where the model's response is zero).
    band : tuple of float
        ``(lo, hi)`` [rad per time unit]: half the lowest to twice the highest natural
        frequency of the reference's lightly damped open-loop poles (damping ratio below
        0.3) at the speeds, where flutter and its control happen (the
        whole grid when it has none); far outside it both responses are small and their
        relative error says little about the loop.
    speed_unit, time_unit : str
        The families' units.
    """

    __repr__ = result_repr

    model: str
    reference: str
    speeds: np.ndarray
    omega: np.ndarray
    relative_error: np.ndarray
    band: tuple
    speed_unit: str = "speed index"
    time_unit: str = "s"

    def worst(self, lo: float | None = None, hi: float | None = None) -> np.ndarray:
        """The largest relative error at each speed over the frequencies in ``[lo, hi]``.

        Parameters
        ----------
        lo, hi : float, optional
            Frequency band [rad per time unit]; default :attr:`band`.

        Returns
        -------
        ndarray, shape (ns,)
        """
        lo = self.band[0] if lo is None else lo
        hi = self.band[1] if hi is None else hi
        band = (self.omega >= lo) & (self.omega <= hi)
        if not np.any(band):
            raise ValueError(f"no frequency of the comparison lies in [{lo:g}, {hi:g}] "
                             f"(it spans [{self.omega[0]:.3g}, {self.omega[-1]:.3g}])")
        return np.nanmax(self.relative_error[:, band], axis=1)


def _channels(reference, model) -> tuple[tuple, tuple]:
    """The model's controls and measurements in the reference's order: by name where both
    families use the same names, else by position."""
    rs, ms = reference.signals, model.signals
    if (len(rs.controls), len(rs.measurements)) != (len(ms.controls), len(ms.measurements)):
        raise DimensionError(
            f"the reference has {len(rs.controls)} controls and {len(rs.measurements)} "
            f"measurements, the model {len(ms.controls)} and {len(ms.measurements)}: compare "
            "families with the same controls and measurements")
    controls = rs.controls if set(rs.controls) == set(ms.controls) else ms.controls
    measurements = (rs.measurements if set(rs.measurements) == set(ms.measurements)
                    else ms.measurements)
    return tuple(controls), tuple(measurements)


#: damping ratio below which an open-loop pole counts as a lightly damped mode
LIGHT_DAMPING = 0.3


def _poles(reference, speeds) -> np.ndarray:
    return np.concatenate([np.linalg.eigvals(np.atleast_2d(reference.state_matrix(float(V))))
                           for V in speeds])


def _light_band(poles: np.ndarray, omega: np.ndarray) -> tuple[float, float]:
    """Half the lowest to twice the highest natural frequency of the lightly damped poles
    (the whole grid without any)."""
    wn = np.abs(poles)
    light = np.isfinite(wn) & (poles.imag > 0) & (-poles.real < LIGHT_DAMPING * wn)
    if not np.any(light):
        return float(omega.min()), float(omega.max())
    return 0.5 * float(wn[light].min()), 2.0 * float(wn[light].max())


def model_mismatch(reference, model, speeds, omega=None, *, n_omega: int = 400
                   ) -> ModelMismatch:
    """The relative error of ``model``'s control-to-measurement response against
    ``reference``'s (module docstring).

    Parameters
    ----------
    reference, model : casflutter.aeroelastic.PlantFamily
        The plant (e.g. a truth's linearisation, flap behind its servo) and the model that
        stands for it (e.g. the ROM loop a controller is designed on); the same controls and
        measurements (by name, else by position) and the same units.
    speeds : sequence of float
        Speeds inside both families' ranges.
    omega : sequence of float, optional
        Frequencies [rad per time unit]; default ``n_omega`` points on a log grid a decade
        either side of the reference's open-loop pole moduli, with the poles' own
        frequencies (the margins' grid, :mod:`._margins`).
    n_omega : int
        Points of the default grid.

    Returns
    -------
    ModelMismatch

    Examples
    --------
    The typical section against its aerodynamics frozen at V = 1.8 (the V² scaling of
    eq. 8): the same plant at 1.8, another one away from it.

    >>> from casflutter import frozen_aero_truth, load_problem
    >>> from casflutter.aeroelastic import TruthLoop
    >>> from casflutter.verify import model_mismatch
    >>> truth = load_problem("typical_section")
    >>> wing, frozen = TruthLoop(truth, 100.0), TruthLoop(frozen_aero_truth(truth, 1.8), 100.0)
    >>> m = model_mismatch(wing, frozen, [1.8, 2.2])
    >>> bool(m.worst()[0] < 1e-9), bool(m.worst()[1] > 0.01)
    (True, True)
    """
    if reference.time_unit != model.time_unit or reference.speed_unit != model.speed_unit:
        raise DimensionError(
            f"the reference's units (speed {reference.speed_unit!r}, time "
            f"{reference.time_unit!r}) are not the model's (speed {model.speed_unit!r}, time "
            f"{model.time_unit!r}): compare families in the same units")
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)):
        raise ValueError(f"speeds = {speeds!r}: give one or more finite speeds")
    for V in speeds:
        reference.check_speed(float(V))
        model.check_speed(float(V))
    controls, measurements = _channels(reference, model)
    poles = _poles(reference, speeds)
    w = (omega_grid_of(poles[np.isfinite(poles)], int(n_omega)) if omega is None
         else np.asarray(omega, dtype=float).ravel())
    if w.size == 0 or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("omega: give one or more finite frequencies >= 0 [rad per time unit]")
    err = np.empty((speeds.size, w.size))
    for k, V in enumerate(speeds):
        G_ref = reference.control_plant(float(V))(1j * w, squeeze=False)
        G = model.control_plant(float(V), controls, measurements)(1j * w, squeeze=False)
        # python-control returns (outputs, inputs, frequencies): singular values per frequency
        diff = np.linalg.svd(np.moveaxis(G_ref - G, -1, 0), compute_uv=False)
        size = np.linalg.svd(np.moveaxis(G, -1, 0), compute_uv=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            err[k] = np.where(size[:, 0] > 0, diff[:, 0] / size[:, 0], np.nan)
    return ModelMismatch(model=getattr(model, "name", "model"),
                         reference=getattr(reference, "name", "reference"), speeds=speeds,
                         omega=w, relative_error=err, band=_light_band(poles, w),
                         speed_unit=model.speed_unit,
                         time_unit=model.time_unit)
