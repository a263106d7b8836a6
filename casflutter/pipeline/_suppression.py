"""Stage ``suppression``: paper Fig. 11 where a wind tunnel would test it.

At each of ``suppression.speed_factors`` times the truth's own flutter speed (the paper
measured Fig. 11 on the real wing at an LCO condition), the truth's LCO is established, the
controller's gain is ramped 0 -> 1, held and released, in the tunnel's turbulence with noisy
sensors and through the flap servo with its travel and rate limits
(:func:`casflutter.truth.suppression_runs`).  The attenuation of each run is
``1 - rms(closed loop, hold) / rms(open-loop LCO)`` of the dominant sensor.

An attenuation means a suppressed LCO only where the truth's linearised loop with the
controller is stable at that speed.  Where it is not, the wing cannot come to rest under the
controller and only the loop's nonlinearities (the servo's limits) keep it bounded, yet the
sensors' rms can still fall below the open loop's LCO during the hold (on the seed wing, a
controller whose linearised loop is unstable from V = 0.89 measured 92 % at 1.2 Vf).  Each
run therefore says whether its speed lies inside the interval the verification layer
certifies on the truth (:attr:`SuppressionStage.certified`), and the stage warns where it
does not.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import control

from .._format import result_repr
from ..truth import SuppressionResult, suppression_runs
from ._config import RunConfig
from ._model import FlutterStage

__all__ = ["SuppressionStage", "suppression_stage"]

log = logging.getLogger("casflutter.pipeline")


@dataclass(frozen=True)
class SuppressionStage:
    """The suppression stage: one gain-ramp run per speed.

    Attributes
    ----------
    runs : tuple of SuppressionResult
        One run per ``suppression.speed_factors``, in that order.
    V_flutter : float
        The speed the factors multiply: the truth's flutter speed (the ROM's where the truth
        has no flutter in the search range).
    reference : str
        ``"truth"`` or ``"rom"``: whose flutter speed ``V_flutter`` is.
    certified : tuple of float or None
        ``(lo, hi)`` over which the verification layer certifies the truth's linearised loop
        with the controller stable (the controller stage's ``"truth"`` check); ``None`` where
        there is no such certificate.
    """

    __repr__ = result_repr

    runs: tuple
    V_flutter: float
    reference: str = "truth"
    certified: tuple | None = None

    @property
    def attenuation_percent(self) -> tuple:
        """The attenuation of each run [%] (``None`` where the open loop was at rest)."""
        return tuple(r.attenuation_percent for r in self.runs)

    @property
    def linear_loop_certified(self) -> tuple:
        """For each run, whether its speed lies inside :attr:`certified`: the truth's
        linearised loop is certified stable there, so an attenuation is that of a suppressed
        LCO (``None`` for every run without a certificate)."""
        if self.certified is None:
            return tuple(None for _ in self.runs)
        lo, hi = self.certified
        return tuple(bool(lo <= r.V <= hi) for r in self.runs)

    def at(self, speed_factor: float) -> SuppressionResult:
        """The run at ``speed_factor`` times :attr:`V_flutter`.

        Raises
        ------
        KeyError
            No run at that factor.
        """
        for r in self.runs:
            if r.speed_factor is not None and abs(r.speed_factor - speed_factor) <= 1e-9:
                return r
        raise KeyError(f"no suppression run at {speed_factor:g} x the flutter speed; the "
                       f"runs are at {[r.speed_factor for r in self.runs]}")


def suppression_stage(cfg: RunConfig, truth, flutters: FlutterStage, lco,
                      K: control.StateSpace, *, mode: int, dt: float,
                      certified: tuple | None = None) -> SuppressionStage:
    """Stage ``suppression`` (module docstring).

    Where the LCO stage simulated the truth at one of the speeds, its converged run is the
    start; at the others the truth's LCO is established first
    (:func:`casflutter.truth.truth_lco`, ``lco.duration`` per simulation).

    Parameters
    ----------
    cfg : RunConfig
        The configuration: ``[suppression]``, the sensors, ``lco.duration`` and
        ``lco.initial_deflection`` (the deflection and the tap), ``seed``.
    truth : AeroelasticTruth
        The simulator.
    flutters : FlutterStage
        The flutter searches (the truth's flutter speed, else the model's).
    lco : LcoResult or None
        The LCO stage, whose truth run may be at one of the speeds.
    K : control.StateSpace
        The controller (``v_c = +K zm``).
    mode : int
        0-based flutter mode, deflected to start an LCO and tapped at the release.
    dt : float
        Sample time of the loop (the records').
    certified : tuple of float, optional
        ``(lo, hi)`` over which the verification layer certifies the truth's linearised loop
        with ``K`` stable; a run outside it is warned about (module docstring).

    Returns
    -------
    SuppressionStage
    """
    has_truth_flutter = flutters.truth is not None and flutters.truth.flutter is not None
    V_ref = float(flutters.truth.Vf if has_truth_flutter else flutters.Vf)
    known = {}
    if lco is not None and lco.truth is not None:
        known[lco.truth.V / V_ref] = lco.truth   # the LCO stage's converged truth runs
        known.update({c.speed_factor: c.truth for c in lco.speed_following})
    runs = suppression_runs(truth, K, V_ref, cfg.suppression, dt=dt, mode=mode,
                            deflection=cfg.lco.initial_deflection,
                            lco_duration=cfg.lco.duration, sensor_rows=cfg.sensors.rows or None,
                            sensor=cfg.sensors.kind, seed=cfg.seed, lcos=known,
                            workers=cfg.suppression.workers)
    for r in runs:
        if not r.started_from_lco:
            log.info("the truth has no LCO at V = %.4f: the suppression run starts from a "
                     "deflected mode", r.V)
        log.info("suppression at %.4g x Vf (V = %.4f): attenuation %.1f %%, flap peak %.3g "
                 "rad, rate peak %.3g rad/s%s", r.speed_factor, r.V,
                 float("nan") if r.attenuation_percent is None else r.attenuation_percent,
                 r.flap_peak, r.flap_rate_peak, _saturation(r))
    stage = SuppressionStage(runs=runs, V_flutter=V_ref,
                             reference="truth" if has_truth_flutter else "rom",
                             certified=None if certified is None else
                             tuple(float(v) for v in certified))
    for r, ok in zip(runs, stage.linear_loop_certified):
        if ok is False:
            log.warning("suppression at %.4g x Vf (V = %.4f): the truth's linearised loop with "
                        "this controller is certified stable only over [%.5g, %.5g]: the wing "
                        "cannot come to rest there, and the attenuation of %.1f %% is not that "
                        "of a suppressed LCO", r.speed_factor, r.V,
                        *stage.certified, float("nan") if r.attenuation_percent is None
                        else r.attenuation_percent)
    return stage


def _saturation(r: SuppressionResult) -> str:
    """How long the servo sat at its limits during the hold, for the log line."""
    parts = [f"{what} at its limit {share:.0f} % of the hold"
             for what, share in (("travel", r.flap_saturated_percent),
                                 ("rate", r.flap_rate_saturated_percent))
             if share is not None and share > 0]
    return "; flap " + ", ".join(parts) if parts else ""
