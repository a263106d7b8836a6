"""The controller stage of a run: design, then certify, on plant families (paper §III.C-IV).

The design takes the run's loop family, the one the model stages built (the ROM loop ΣAE(V)
of eq. 8-9 with its aerodynamic time following the speed and the flap behind its servo, or
a gridded family read from a file), and one of two methods:

* ``"multispeed"`` — one fixed-order controller that keeps the family decaying over
  ``controller.interval`` and, among such controllers, the smallest worst H∞ objective over
  the speeds (:func:`casflutter.design.design_over_speeds`);
* ``"paper"`` — the paper's design: γ of the LFT at Vf (eq. 14-16) with the flap-rate weight
  (:func:`casflutter.design.synthesize`), the interval only measured afterwards.

Then the verification layer, which shares no code with the design, certifies the controller
on the design family and on every reference model the problem has (the truth's own
linearisation with the flap behind the same servo): the stable speed interval, the absolute
and robust flutter speeds and the margins (:func:`casflutter.verify.verify_family`), how far
the design family's response lies from the reference's (:func:`casflutter.verify.model_mismatch`:
where the design family's certificate stops carrying over), and, on a ROM loop, the paper's γ
and small-gain interval of the LFT at Vf (:func:`casflutter.verify.verify_controller`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace
from typing import Mapping

import control
import numpy as np

from .._format import result_repr
from .._settings import settings_as
from ..aeroelastic import FEEDBACK_SIGNS, AeroelasticLFT, build_lft
from ..design import (MultiSpeedDesign, MultiSpeedSettings, SynthesisOptions,
                      SynthesisResult, default_objective, design_over_speeds, synthesize,
                      with_flap_rate)
from ..errors import CasflutterError
from ..verify import (FamilyVerification, ModelMismatch, SpeedSweep, VerificationReport,
                      match_controller, model_mismatch, speed_sweep, verify_controller,
                      verify_family)
from ._config import RunConfig

__all__ = ["ControllerStage", "controller_stage", "multispeed_settings", "start_controller"]

log = logging.getLogger("casflutter.pipeline")

#: speeds at which the design family's response is compared with each reference's: equally
#: spaced over the reference's verification range, its start left out
MISMATCH_SPEEDS = 5


@dataclass(frozen=True)
class ControllerStage:
    """What the controller stage produced.

    Attributes
    ----------
    controller : control.StateSpace
        ``K`` from the family's measurements to its controls, applied with the family's
        ``feedback`` convention (``v = +K zm`` on a ROM loop, paper Fig. 3).
    method : str
        ``"multispeed"`` or ``"paper"``.
    family : PlantFamily
        The design family.
    design : MultiSpeedDesign or None
        The multi-speed design (``method = "multispeed"``).
    synthesis : SynthesisResult or None
        The paper's synthesis on the LFT at Vf (``method = "paper"``).
    lft : AeroelasticLFT or None
        The LFT at Vf (eq. 14) of a ROM loop, on which the paper's γ is verified.
    verification : VerificationReport or None
        γ, the small-gain and the exact intervals of the LFT at Vf (eq. 10-16).
    checks : mapping of str to FamilyVerification
        The verification layer's certificate on each model: ``"design"`` (the design family)
        and, with a truth, ``"truth"`` (its own linearisation, flap behind the servo).
    mismatch : mapping of str to ModelMismatch
        For each reference of ``checks`` (the truth), how far the design family's
        control-to-measurement response lies from it at five speeds spread over both
        verification ranges (:func:`casflutter.verify.model_mismatch`): where a
        certificate on the design family stops carrying over.
    design_time_s : float
        Seconds spent designing (the verification not included).
    sweep : SpeedSweep or None
        The dense eigenvalue sweep of the LFT's loop over ``verify.sweep`` x Vf
        (:func:`casflutter.verify.speed_sweep`), when asked.
    """

    __repr__ = result_repr

    controller: control.StateSpace
    method: str
    family: object
    design: MultiSpeedDesign | None = None
    synthesis: SynthesisResult | None = None
    lft: AeroelasticLFT | None = None
    verification: VerificationReport | None = None
    checks: Mapping[str, FamilyVerification] = field(default_factory=dict)
    mismatch: Mapping[str, ModelMismatch] = field(default_factory=dict)
    design_time_s: float = float("nan")
    sweep: SpeedSweep | None = None

    @property
    def order(self) -> int:
        """The controller's order."""
        return int(self.controller.nstates)


def _paper_plant(system, Vf: float, cfg: RunConfig):
    """The LFT at Vf (eq. 14) and the H∞ plants of the paper's design, the LFTs at
    ``controller.speeds`` x Vf (with the flap-rate output when ``controller.flap_rate_weight
    > 0``)."""
    c = cfg.controller
    lft = build_lft(system, Vf)

    def plant(factor: float):
        P = lft.P if factor == 1.0 else build_lft(system, factor * Vf).P
        if c.flap_rate_weight > 0:
            P = with_flap_rate(P, lft.nmeas, c.flap_rate_weight, c.flap_rate_bandwidth)
        return P

    return lft, [plant(float(f)) for f in c.speeds]


def multispeed_settings(cfg: RunConfig, objective: str) -> MultiSpeedSettings:
    """The multi-speed design's settings of a run configuration's ``[controller]`` table.

    Parameters
    ----------
    cfg : RunConfig
        The run configuration.
    objective : str
        The H∞ objective (``[controller] hinf_objective`` or the caller's choice): the
        settings bound the loop's sensitivities when it is ``"sensitivity"``.

    Returns
    -------
    MultiSpeedSettings
    """
    c = cfg.controller
    return MultiSpeedSettings(
        decay=c.interval_decay, n_speeds=c.n_speeds, hinf_speeds=c.hinf_speeds,
        rate_weight=c.flap_rate_weight, rate_bandwidth=c.flap_rate_bandwidth,
        sensitivity=objective == "sensitivity",
        strictly_proper=c.strictly_proper, stable_controller=c.stable_controller,
        random_starts=c.random_starts,
        full_order=c.full_order, reduction_orders=c.reduction_orders,
        synthesis=replace(settings_as(c, SynthesisOptions), ipopt={**cfg.solver.ipopt,
                                                                   **c.ipopt}))


def start_controller(cfg: RunConfig, family, feedback: str | None = None
                     ) -> control.StateSpace | None:
    """``controller.start`` matched to a design family.

    The file's controller is matched to the family's signals by name
    (:func:`casflutter.verify.match_controller`: the file's ``inputs``/``outputs`` and
    ``feedback``, or the family's order and convention), then written from all of the
    family's measurements to all of its controls, a channel the file leaves out as a zero
    row or column.

    Parameters
    ----------
    cfg : RunConfig
        The configuration (``controller.start``).
    family : PlantFamily
        The design family.
    feedback : {"positive", "negative"}, optional
        The convention of the controller returned (default the family's): ``u = +K y`` for
        the paper's synthesis on the LFT (eq. 14).

    Returns
    -------
    control.StateSpace or None
        ``None`` without a start.

    Raises
    ------
    ConfigError, DimensionError
        A controller whose names or sizes do not match the family's (named).
    """
    if not cfg.controller.start:
        return None
    fc = match_controller(family, cfg.controller.start)
    sig = family.signals
    rows = [list(sig.controls).index(name) for name in fc.controls]
    cols = [list(sig.measurements).index(name) for name in fc.measurements]
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float))
                  for M in (fc.K.A, fc.K.B, fc.K.C, fc.K.D))
    n, nu, ny = A.shape[0], len(sig.controls), len(sig.measurements)
    Bf, Cf, Df = np.zeros((n, ny)), np.zeros((nu, n)), np.zeros((nu, ny))
    Bf[:, cols] = B.reshape(n, len(cols))
    Cf[rows, :] = C.reshape(len(rows), n)
    Df[np.ix_(rows, cols)] = D
    sign = fc.sign * FEEDBACK_SIGNS[feedback or family.feedback]   # u = fc.sign K y
    log.info("controller: starting from %s (order %d, %s feedback%s)", cfg.controller.start, n,
             fc.feedback, "; " + "; ".join(fc.notes) if fc.notes else "")
    return control.ss(A, Bf, sign * Cf, sign * Df, inputs=list(sig.measurements),
                      outputs=list(sig.controls), name="K0")


def design_objective(cfg: RunConfig, family, has_lft: bool) -> str:
    """The multi-speed design's H∞ objective: ``controller.hinf_objective``, with
    ``"auto"`` resolved (``"lft"`` where the run has the LFT at the ROM loop's flutter
    speed, else :func:`casflutter.design.default_objective` of the family)."""
    objective = cfg.controller.hinf_objective
    if objective == "auto":
        objective = "lft" if has_lft else default_objective(family)
    return objective


def _multispeed(cfg: RunConfig, family, lft_plants=None) -> MultiSpeedDesign:
    c = cfg.controller
    if c.hinf_objective == "lft" and lft_plants is None:
        raise CasflutterError("controller.hinf_objective = \"lft\" needs the LFT at the ROM "
                              "loop's flutter speed (eq. 14); this problem has no ROM loop "
                              "with a flutter speed: use \"sensors\" or \"auto\"")
    objective = design_objective(cfg, family, lft_plants is not None)
    hinf = lft_plants if objective == "lft" and c.hinf_speeds else None
    K0 = start_controller(cfg, family)
    return design_over_speeds(family, tuple(c.interval), c.order,
                              settings=multispeed_settings(cfg, objective), seed=cfg.seed,
                              initial=() if K0 is None else (K0,), hinf_plants=hinf)


def _paper(cfg: RunConfig, family, P, lft) -> SynthesisResult:
    c = cfg.controller
    options = replace(settings_as(c, SynthesisOptions), ipopt={**cfg.solver.ipopt, **c.ipopt})
    K0 = start_controller(cfg, family, "positive")       # the LFT's v = +K zm (eq. 14)
    return synthesize(P, lft.nmeas, lft.ncon, c.order, starts=c.starts, seed=cfg.seed,
                      initial=K0, options=options)


def _warn_without_margins(checks: Mapping, interval, unit: str, margins) -> None:
    """Warn, per model, where the loop is certified stable inside the requested interval but
    its loop-at-a-time margins fall below ``margins`` there: stable, not robustly so.  The
    multi-speed design asks only for a decay rate, and a loop that passes close to the
    critical point meets it; the verification's robust flutter speed says where it does."""
    lo, hi = interval
    for name, check in checks.items():
        robust, top = check.robust_flutter_speed, check.stable_interval
        if robust is None or top is None or robust >= min(hi, top[1]):
            continue
        log.warning("controller: on %s the loop is certified stable to %.5g %s, but its "
                    "margins (%g dB / %g deg) hold only to %.5g (%s): from there to %.5g, "
                    "inside the requested (%.5g, %.5g), it is stable, not robustly so", name,
                    top[1], unit, margins[0], margins[1], robust, check.robust_reason,
                    min(hi, top[1]), lo, hi)


def verification_range(family, cfg: RunConfig) -> tuple[float, float]:
    """The speeds a controller is certified over: the family's own range where it is
    finite, else from 0 to the larger of the flutter search's top and the design interval's
    top."""
    lo, hi = family.speed_range
    if math.isfinite(hi):
        return float(lo), float(hi)
    tops = [cfg.flutter.V_range[1]] + ([cfg.controller.interval[1]]
                                       if cfg.controller.interval else [])
    return float(lo), float(max(tops))


def controller_stage(cfg: RunConfig, family, *, system=None, Vf: float | None = None,
                     references: Mapping[str, object] = ()) -> ControllerStage:
    """Design a controller on ``family`` and certify it (module docstring).

    Parameters
    ----------
    cfg : RunConfig
        The run's configuration (``[controller]``, ``[verify]``).
    family : PlantFamily
        The design family.
    system : AeroelasticSystem, optional
        The ROM loop without the servo, when there is one: its LFT at ``Vf`` is the paper's
        design plant and carries the paper's γ.
    Vf : float, optional
        The ROM loop's flutter speed (with ``system``).
    references : mapping of str to PlantFamily
        Further models to certify the controller on (e.g. ``{"truth": TruthLoop(...)}``).

    Returns
    -------
    ControllerStage

    Raises
    ------
    CasflutterError
        ``method = "paper"`` without a ROM loop and its flutter speed.
    casflutter.errors.SynthesisError
        No start held even the interval's low end, or the paper's synthesis stabilised
        nothing.
    """
    c = cfg.controller
    t0 = time.perf_counter()
    lft = P = None
    if system is not None and Vf is not None:
        lft, P = _paper_plant(system, Vf, cfg)
    design = syn = None
    if c.method == "paper":
        if lft is None:
            raise CasflutterError("controller.method = \"paper\" designs on the LFT at the ROM "
                                  "loop's flutter speed (eq. 14); this problem has no ROM loop "
                                  "with a flutter speed: use method = \"multispeed\"")
        syn = _paper(cfg, family, P, lft)
        sig = family.signals    # the LFT's K reads the measurements and drives the flap
        K = control.ss(syn.controller.A, syn.controller.B, syn.controller.C,
                       syn.controller.D, inputs=list(sig.measurements),
                       outputs=list(sig.controls), name="K")
    else:                       # design_over_speeds names K after the family
        design = _multispeed(cfg, family, P)
        K = design.controller
        if not design.held:
            log.warning("controller: %s", design.message)
    t_design = time.perf_counter() - t0
    rng = verification_range(family, cfg)
    checks = {"design": verify_family(family, K, speed_range=rng, margins=c.margins)}
    mismatch = {}
    for name, ref in dict(references).items():
        ref_range = verification_range(ref, cfg)
        checks[name] = verify_family(ref, K, speed_range=ref_range, margins=c.margins)
        # the speeds both verification ranges share, their start left out
        lo, hi = max(ref_range[0], rng[0]), min(ref_range[1], rng[1])
        m = replace(model_mismatch(ref, family, np.linspace(lo, hi, MISMATCH_SPEEDS + 1)[1:]),
                    model="design model", reference=name)
        mismatch[name] = m
        log.debug("design model against the %s: worst relative response error %s at V = %s "
                  "(%.3g-%.3g rad per %s, the lightly damped modes)", name,
                  ", ".join(f"{e:.3g}" for e in m.worst()),
                  ", ".join(f"{V:.3g}" for V in m.speeds), *m.band, family.time_unit)
    if design is not None:
        _warn_without_margins(checks, design.interval, family.speed_unit, c.margins)
    ver = sweep = None
    if lft is not None:
        ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta)
        if cfg.verify.sweep:
            lo, hi = cfg.verify.sweep
            sweep = speed_sweep(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta,
                                V=np.linspace(lo * Vf, hi * Vf, cfg.verify.n_sweep))
    return ControllerStage(controller=K, method=c.method, family=family, design=design,
                           synthesis=syn, lft=lft, verification=ver, checks=checks,
                           mismatch=mismatch,
                           design_time_s=t_design, sweep=sweep)
