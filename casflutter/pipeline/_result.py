"""The typed result of a study run, one field per stage, and its JSON summary."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import control
import numpy as np

from .._format import result_repr
from ..aeroelastic import (AeroelasticLFT, AeroelasticSystem, FlutterResult, LoopSimulation,
                           ParametricSystem, PKResult, RFASystem)
from ..data import IOData
from ..design import IntervalDesign, SynthesisResult
from .._outputs import plain_json
from ..ident import CommonDenominatorResult, FitReport, IdentificationResult
from ..lco import LCOBranch
from ..realize import ParametricROM, RationalApproximation, Realization
from ..truth import AeroelasticTruth, SuppressionResult, TruthLco, TruthLoopSweep
from ..verify import SpeedSweep, StabilityInterval, VerificationReport
from ._config import RunConfig
from ._exports import label_summary
from ._units import speed_scale, speed_values

__all__ = ["RunResult", "LcoResult", "ParametricResult", "SimulationCheck",
           "ClosedLoopChecks"]


@dataclass(frozen=True)
class LcoResult:
    """The LCO stage (paper Fig. 9).

    Attributes
    ----------
    rom : LoopSimulation
        The nonlinear ROM in the loop with Σs at ``V``.
    truth : TruthLco or None
        The truth's own response a little above its own flutter speed (``None`` on a wing
        file, which has no simulator).
    V : float
        Speed of the ROM simulation: ``lco.speed_factor`` times ``V_hopf_loop`` (or
        ``V_hopf_exact_order`` when the loop has no flutter point in the range).
    V_hopf_exact_order : float
        Hopf speed of the continuous ΣAE with the ROM realised at its exact order (the
        nonlinear ROM carries its full linear part; a truncated Σf has another Hopf point).
    flutter_exact_order : FlutterResult
        The flutter search of that exact-order continuous loop.
    V_hopf_loop : float or None
        The ROM's own flutter speed: the Neimark--Sacker point of the sampled-data loop it is
        simulated in (:func:`casflutter.lco.rom_loop_map`); None when there is none in the
        flutter search range.
    truth_branch, rom_branch : LCOBranch or None
        The LCO branches of the truth and of the ROM loop from their flutter points
        (``lco.branch_points > 0``).
    """

    __repr__ = result_repr

    rom: LoopSimulation
    truth: TruthLco | None
    V: float
    V_hopf_exact_order: float
    flutter_exact_order: FlutterResult
    V_hopf_loop: float | None = None
    truth_branch: LCOBranch | None = None
    rom_branch: LCOBranch | None = None


@dataclass(frozen=True)
class ParametricResult:
    """The parametric-ROM stage.

    Attributes
    ----------
    rom : ParametricROM
        Common-denominator ROMs at several speeds, interpolated in V.
    system : ParametricSystem
        Its ΣAE(V).
    flutter : FlutterResult
        Its flutter search.
    """

    __repr__ = result_repr

    rom: ParametricROM
    system: ParametricSystem
    flutter: FlutterResult


@dataclass(frozen=True)
class SimulationCheck:
    """Open- and closed-loop simulation at one speed above flutter.

    Attributes
    ----------
    model : str
        ``"rom"`` or ``"truth"``.
    V : float
        Speed index.
    timepts : ndarray
        Sample times.
    open_loop, closed_loop : ndarray, shape (K, m)
        Sensor records.
    open_rate, closed_rate : float
        Envelope growth rates (largest over the sensors, second half of the record)
        [1 / time unit].
    open_eig_rate, closed_eig_rate : float
        Spectral abscissae of the linear open and closed loops at ``V``.
    """

    __repr__ = result_repr

    model: str
    V: float
    timepts: np.ndarray
    open_loop: np.ndarray
    closed_loop: np.ndarray
    open_rate: float
    closed_rate: float
    open_eig_rate: float
    closed_eig_rate: float

    @property
    def grows_open_decays_closed(self) -> bool:
        """The open loop grows and the closed loop decays (rates and amplitudes)."""
        n = self.timepts.size
        first, last = slice(0, n // 4), slice(3 * n // 4, n)

        def amp(X, sl):
            return float(np.max(np.abs(X[sl])))

        return bool(self.open_rate > 0 and self.closed_rate < 0
                    and amp(self.open_loop, last) > amp(self.open_loop, first)
                    and amp(self.closed_loop, last) < amp(self.closed_loop, first))


@dataclass(frozen=True)
class ClosedLoopChecks:
    """The closed-loop stage: the loops above flutter and the truth's closed-loop sweep.

    Attributes
    ----------
    truth_sweep : TruthLoopSweep
        The truth's linear loop with the controller and the actuator over speed.
    rom_simulation, truth_simulation : SimulationCheck
        Open and closed loop above each model's flutter speed.
    """

    __repr__ = result_repr

    truth_sweep: TruthLoopSweep
    rom_simulation: SimulationCheck
    truth_simulation: SimulationCheck


#: Plain JSON values (non-finite floats as ``None``).
_jsonable = plain_json


def _pair(t):
    return None if t is None else [float(t[0]), float(t[1])]


def _flutter_summary(res: FlutterResult | None) -> dict | None:
    if res is None:
        return None
    if res.flutter is None:
        return {"V": None, "freq_hz": None, "mode": None, "status": res.status}
    mode = res.flutter_mode
    return {"V": float(res.Vf), "freq_hz": float(res.omega_f) / (2 * np.pi),
            "mode": None if mode is None or mode < 0 else int(mode) + 1, "status": res.status}


def skipped_notes(skipped: Mapping[str, str]) -> list[str]:
    """``skipped A, B (reason)``: one line per reason of a run's skipped stages (each
    ``"what: why"``)."""
    by_reason: dict = {}
    for text in skipped.values():
        what, _, why = text.partition(": ")
        by_reason.setdefault(why, []).append(what)
    return [f"skipped {', '.join(whats)} ({why})" for why, whats in by_reason.items()]


def _rel(a, b):
    return None if a is None or b is None else float(a / b - 1.0)


@dataclass(frozen=True)
class RunResult:
    """Everything a study run produced, one typed field per stage (``None``: not run).

    Attributes
    ----------
    config : RunConfig
        The configuration.
    truth : AeroelasticTruth or None
        The truth simulator (``None`` on a wing file).
    data : IOData or None
        The chirp records of the last identification (``None`` on a GAF wing file, which
        has ``Q(ik)`` instead of records; so are ``identification``, ``fit`` and
        ``realization``).
    identification : IdentificationResult or CommonDenominatorResult or None
        The ROM (``.model``).
    identification_history : tuple of (float, float)
        ``(V0, Vf_ROM)`` of every identification (more than one with ``rom.v0_iterations``).
    fit : FitReport
        Free-run fit of the ROM on its records (paper Fig. 7).
    realization : Realization
        Σf by ERA and Tustin (eq. 5).
    system : AeroelasticSystem
        ΣAE(V) (eq. 8-9); on a GAF wing file with Σf of the RFA frozen at the flutter speed
        (``None`` when the RFA has ``p`` terms: no proper Σf).
    flutter : FlutterResult
        Flutter search of the ROM.
    flutter_truth : FlutterResult or None
        Of the truth (``None`` on a wing file).
    flutter_frozen : FlutterResult or None
        Of the truth with its aerodynamics frozen at ``V0`` (stage ``frozen``).
    parametric : ParametricResult or None
        Stage ``parametric``.
    lco : LcoResult or None
        Stage ``lco``.
    lft : AeroelasticLFT or None
        LFT at the ROM's Vf (eq. 14; stage ``controller``).
    synthesis : SynthesisResult or None
        The fixed-order synthesis (``None`` with ``controller.method = "interval"``).
    interval_design : IntervalDesign or None
        The design of ``controller.method = "interval"``: the full-order continuation and
        the order reduction.
    controller : control.StateSpace or None
        ``K`` from the sensors to the flap (``v = K zm``).
    verification : VerificationReport or None
        γ and the speed intervals (eq. 10-16).
    rom_sweep : SpeedSweep or None
        Dense eigenvalue sweep of the ROM loop (``verify.sweep``).
    rom_interval : StabilityInterval or None
        For a ROM whose time scales with V (``rom.convective``): the exact stable speed
        interval of its loop closed by the controller, the flap behind the same servo as the
        truth's (:meth:`casflutter.aeroelastic.AeroelasticSystem.with_servo`), grown from
        ``data.V0``.  ``None`` for the paper's frozen ROM, whose exact interval is the
        verification's (the LFT is exact at every speed), or when the controller does not
        hold the scaled loop at V0.
    truth_interval : StabilityInterval or None
        Exact stable speed interval of the truth's own linearisation closed by the
        controller, the flap behind a servo of ``controller.flap_rate_bandwidth``
        (:class:`casflutter.aeroelastic.TruthLoop`), grown from ``data.V0``; ``None``
        without a truth, or when the controller does not hold the truth at V0.
    closed_loop : ClosedLoopChecks or None
        Stage ``closed_loop``.
    suppression : SuppressionResult or None
        Stage ``suppression`` (paper Fig. 11).
    timings : mapping
        Seconds per stage and ``"total"``.
    out_dir : Path or None
        Where the files were written.
    files : mapping
        Name -> path of every file written.
    problem : object
        What ``[problem]`` loaded: the truth, or a :class:`casflutter.truth.WingProblem`.
    skipped : mapping
        Stage (or part of a stage) -> why it did not run (the truth-only stages on a wing
        file).
    rfa : RationalApproximation or None
        The RFA of a GAF wing file's ``Q(ik)``.
    rfa_system : RFASystem or None
        Its ΣAE(U) in the airspeed [m/s].
    rfa_flutter : FlutterResult or None
        The flutter search of ``rfa_system`` (speeds in m/s, frequencies in rad/s).
    pk : PKResult or None
        The p–k solution on the same ``Q(ik)`` (the independent check).
    provenance : mapping
        What produced the run (:func:`casflutter._outputs.provenance`: version, seed,
        thread settings, libraries) and its start time (``started``).
    """

    __repr__ = result_repr

    config: RunConfig
    truth: AeroelasticTruth | None
    data: IOData | None
    identification: IdentificationResult | CommonDenominatorResult | None
    identification_history: tuple
    fit: FitReport | None
    realization: Realization | None
    system: AeroelasticSystem | None
    flutter: FlutterResult | None
    flutter_truth: FlutterResult | None
    flutter_frozen: FlutterResult | None = None
    parametric: ParametricResult | None = None
    lco: LcoResult | None = None
    lft: AeroelasticLFT | None = None
    synthesis: SynthesisResult | None = None
    interval_design: IntervalDesign | None = None
    controller: control.StateSpace | None = None
    verification: VerificationReport | None = None
    rom_sweep: SpeedSweep | None = None
    rom_interval: StabilityInterval | None = None
    truth_interval: StabilityInterval | None = None
    closed_loop: ClosedLoopChecks | None = None
    suppression: SuppressionResult | None = None
    timings: Mapping[str, float] = field(default_factory=dict)
    out_dir: Path | None = None
    files: Mapping[str, Path] = field(default_factory=dict)
    problem: Any = None
    skipped: Mapping[str, str] = field(default_factory=dict)
    rfa: RationalApproximation | None = None
    rfa_system: RFASystem | None = None
    rfa_flutter: FlutterResult | None = None
    pk: PKResult | None = None
    provenance: Mapping[str, Any] = field(default_factory=dict)

    # ------------------------------------------------------------------ flutter speeds
    @property
    def Vf(self) -> float | None:
        """The ROM's flutter speed index (the LFT's nominal speed)."""
        return None if self.flutter is None else self.flutter.Vf

    @property
    def Vf_truth(self) -> float | None:
        """The truth's flutter speed index."""
        return None if self.flutter_truth is None else self.flutter_truth.Vf

    @property
    def rom_error(self) -> float | None:
        """``(Vf_rom - Vf_truth) / Vf_truth``."""
        return _rel(self.Vf, self.Vf_truth)

    @property
    def scaling_error(self) -> float | None:
        """``(Vf_frozen - Vf_truth) / Vf_truth``: the error the V² scaling alone causes."""
        return None if self.flutter_frozen is None else _rel(self.flutter_frozen.Vf,
                                                             self.Vf_truth)

    @property
    def convective_V0(self) -> float | None:
        """The speed index from which the ROM's time is scaled (``rom.convective``), or
        ``None`` for Σf frozen at V0 (eq. 8)."""
        return None if self.system is None else self.system.convective_V0

    @property
    def identification_error(self) -> float | None:
        """What identification and Tustin add: ``(Vf_rom - Vf_frozen) / Vf_frozen`` for the
        ROM of eq. 8 (frozen at V0, as the frozen-aero truth), the :attr:`rom_error` for a
        ROM whose time scales with V (``rom.convective``: it stands for the truth itself)."""
        if self.convective_V0 is not None:
            return self.rom_error
        return None if self.flutter_frozen is None else _rel(self.Vf,
                                                             self.flutter_frozen.Vf)

    @property
    def parametric_error(self) -> float | None:
        """``(Vf_parametric - Vf_truth) / Vf_truth``."""
        return None if self.parametric is None else _rel(self.parametric.flutter.Vf,
                                                         self.Vf_truth)

    def explanation(self) -> str:
        """The ROM's flutter-speed error and its cause, in words.

        Returns
        -------
        str
        """
        def pct(x):
            return "n/a" if x is None else f"{100 * x:+.3f}%"
        V0 = speed_values(self.config.data.V0, speed_scale(
            getattr(self, "problem", None) or self.truth))
        air = (f" (U0 = {V0['airspeed_m_s']:.4g} m/s)" if V0.get("airspeed_m_s") is not None
               else "")
        text = (f"ROM identified at speed index V0 = {V0['speed_index']:g}{air}: Vf error "
                f"{pct(self.rom_error)} vs the truth.")
        if self.convective_V0 is not None:
            text += (" Its time is scaled with the speed (rom.convective), so its aerodynamic "
                     "lags follow the reduced frequency as the truth's do.")
            if self.flutter_frozen is not None:
                text += (f" Without that scaling (eq. 8 as the paper writes it) the ROM "
                         f"would stand for the truth with its aerodynamics frozen at V0, "
                         f"which flutters at {pct(self.scaling_error)}.")
        elif self.flutter_frozen is not None:
            text += (f" The V² scaling of ΣAE freezes the aerodynamic time scale (reduced "
                     f"frequency, Wagner lag rates, apparent mass and damping) at V0; the truth "
                     f"with its aerodynamics frozen at V0 flutters at "
                     f"{pct(self.scaling_error)}, so the scaling explains the error up to "
                     f"{pct(self.identification_error)} from identification and Tustin.")
        if self.parametric is not None:
            text += (f" Parametric ROM ({len(self.parametric.rom.speeds)} speeds): "
                     f"{pct(self.parametric_error)}.")
        return text

    def skipped_notes(self) -> list[str]:
        """The stages that did not run and why, one line per reason.

        Returns
        -------
        list of str
            ``skipped A, B (reason)``; empty when every stage ran.
        """
        return skipped_notes(self.skipped)

    # ------------------------------------------------------------------ verification
    @property
    def gamma(self) -> float | None:
        """Verified ``‖T_w̄z‖∞`` of the nominal loop (eq. 16)."""
        return None if self.verification is None else float(self.verification.gamma)

    @property
    def required_V(self) -> tuple | None:
        """``verify.required`` times Vf (``None`` without a target)."""
        req = self.config.verify.required
        if not req or self.Vf is None:
            return None
        return (req[0] * self.Vf, req[1] * self.Vf)

    @property
    def rom_stable_V(self) -> tuple | None:
        """The exact stable speed interval of the ROM loop closed by the controller: the
        verification's (on the LFT, eq. 10-15) for the paper's frozen ROM, the scaled loop's
        (:attr:`rom_interval`) for a ROM whose time scales with V.  ``None`` without a
        controller or when it does not hold the loop."""
        if self.verification is None:
            return None
        if self.convective_V0 is not None:
            ri = self.rom_interval
            return None if ri is None else (float(ri.lower), float(ri.upper))
        return self.verification.exact_V if self.verification.stable else None

    @property
    def controlled_rom(self):
        """The ROM loop family that the controller closes and :attr:`rom_stable_V` judges:
        ΣAE(V) itself (eq. 8), or for a ROM whose time scales with V, ΣAE(V) with the flap
        behind the servo of ``controller.flap_rate_bandwidth``
        (:meth:`~casflutter.aeroelastic.AeroelasticSystem.with_servo`).  ``None`` without a
        ROM loop."""
        if self.system is None:
            return None
        if self.convective_V0 is not None and self.controller is not None:
            return self.system.with_servo(self.config.controller.flap_rate_bandwidth)
        return self.system

    @property
    def interval_ok(self) -> bool | None:
        """The verified exact stable interval (:attr:`rom_stable_V`) contains
        :attr:`required_V` (``None`` without a target or a verification)."""
        if self.required_V is None or self.verification is None:
            return None
        ex = self.rom_stable_V
        lo, hi = self.required_V
        return bool(ex is not None and ex[0] <= lo and ex[1] >= hi)

    @property
    def success(self) -> bool:
        """Every check that ran passed: the interval target, and both closed-loop
        simulations grow open loop and decay closed loop."""
        ok = self.interval_ok is not False
        if self.closed_loop is not None:
            ok = ok and self.closed_loop.rom_simulation.grows_open_decays_closed \
                and self.closed_loop.truth_simulation.grows_open_decays_closed
        return bool(ok)

    # ------------------------------------------------------------------ summary
    def summary(self) -> dict:
        """The measured numbers as plain JSON values (``summary.json``).

        Returns
        -------
        dict
            ``problem``, ``V0``, ``n_sensors``, ``orders``, ``n_params``,
            ``fit_error_percent``, ``nf``, ``ns``, ``nae``, ``flutter``, ``flutter_truth``,
            ``lco``, ``controller``, ``suppression`` (``None`` when the stage did not run),
            ``timings_s``, ``seed``; ``skipped`` (stage -> reason) when a stage was
            skipped; and, for the stages that ran, ``v0_history``,
            ``flutter_frozen``, ``flutter_parametric``, ``verification`` and
            ``closed_loop``.
        """
        cfg = self.config
        model = None if self.identification is None else self.identification.model
        structure = (self.system.structure if self.system is not None
                     else self.rfa_system.structure)
        out = {
            "problem": cfg.problem.name,
            "V0": cfg.data.V0 if model is not None else None,
            "n_sensors": int(structure.n_sensors),
            "orders": None if model is None else list(model.orders.as_tuple()),
            "n_params": None if model is None else model.n_params,
            "fit_error_percent": None if self.fit is None else list(self.fit.error_percent),
            "nf": None if self.realization is None else self.realization.order,
            "ns": 2 * structure.n_modes,
            "nae": (None if self.system is None
                    else int(self.system.state_matrix(0.0).shape[0])),
            "flutter": _flutter_summary(self.flutter),
            "flutter_truth": _flutter_summary(self.flutter_truth),
            "lco": self._lco_summary(),
            "controller": self._controller_summary(),
            "suppression": None if self.suppression is None else {
                "attenuation_percent": self.suppression.attenuation_percent,
                "lco_returns": self.suppression.lco_returns, "V": self.suppression.V,
                "open_loop_amplitude": list(self.suppression.open_loop_amplitude),
                "closed_loop_amplitude": list(self.suppression.closed_loop_amplitude),
                "dominant_sensor": self.suppression.dominant_sensor,
                "started_from_lco": self.suppression.started_from_lco,
                "flap_limit": cfg.suppression.flap_limit,
                "flap_rate_limit": cfg.suppression.flap_rate_limit},
            "timings_s": dict(self.timings),
            "seed": cfg.seed,
        }
        if self.skipped:
            out["skipped"] = dict(self.skipped)
        if self.convective_V0 is not None:
            out["convective_V0"] = float(self.convective_V0)
        if cfg.rom.v0_iterations > 1:
            out["v0_history"] = [list(map(float, p)) for p in self.identification_history]
        if self.flutter_frozen is not None:
            out["flutter_frozen"] = _flutter_summary(self.flutter_frozen)
        if self.parametric is not None:
            out["flutter_parametric"] = _flutter_summary(self.parametric.flutter)
        if self.verification is not None and cfg.verify.required:
            ver = self.verification
            out["verification"] = {
                "gamma_delta": float(ver.hinf_delta.gamma),
                "small_gain_V_delta": _pair(ver.small_gain_V_delta),
                "required_V": _pair(self.required_V), "interval_ok": self.interval_ok,
                "synthesis_gammas": (None if self.synthesis is None
                                     else [float(g) for g in self.synthesis.gammas]),
                "synthesis_converged": (None if self.synthesis is None
                                        else bool(self.synthesis.converged)),
                "success": self.success}
        U_ref = getattr(self.problem, "U_ref", None)
        if U_ref is not None and out["flutter"] is not None and out["flutter"]["V"] is not None:
            out["flutter"]["airspeed_m_s"] = out["flutter"]["V"] * U_ref
        if self.rfa is not None:
            out["rfa"] = self._rfa_summary()
        if self.closed_loop is not None:
            cl = self.closed_loop
            out["closed_loop"] = {
                "truth_stable_V": _pair(cl.truth_sweep.stable_V),
                "simulations": {s.model: {"V": s.V, "open_rate": s.open_rate,
                                          "closed_rate": s.closed_rate,
                                          "open_eig_rate": s.open_eig_rate,
                                          "closed_eig_rate": s.closed_eig_rate}
                                for s in (cl.rom_simulation, cl.truth_simulation)}}
        return _jsonable(label_summary(out, self))

    def _rfa_summary(self) -> dict:
        """The RFA, its flutter in m/s and rad/s and the p–k check (GAF wing files)."""
        r, fl, pk = self.rfa, self.rfa_flutter, self.pk
        mode = fl.flutter_mode if fl is not None else None
        return {
            "method": r.method, "n_lags": int(r.n_lags), "poly_order": int(r.poly_order),
            "lag_roots": [float(g) for g in r.gamma], "n_lag_states": int(r.n_lag_states),
            "fit_error": float(r.fit_error),
            "max_element_error": float(np.max(r.error_rel)),
            "flutter": None if fl is None or fl.Vf is None else {
                "airspeed_m_s": float(fl.Vf), "omega_rad_s": float(fl.omega_f),
                "k": float(fl.omega_f) * r.b / float(fl.Vf),
                "mode": None if mode is None or mode < 0 else int(mode) + 1},
            "pk": None if pk is None or not pk.found else {
                "airspeed_m_s": float(pk.flutter_speed), "omega_rad_s": float(pk.flutter_omega),
                "k": float(pk.flutter_k), "mode": int(pk.flutter_mode) + 1},
            "units": {"airspeed": "m/s", "omega": "rad/s", "k": "omega b / U"}}

    def _lco_summary(self) -> dict | None:
        if self.lco is None:
            return None
        sim, tr = self.lco.rom, self.lco.truth
        sens = sim.sensors if sim.sensors is not None else sim.modes
        return {"V": self.lco.V, "V_hopf_exact_order": self.lco.V_hopf_exact_order,
                "V_hopf_loop": self.lco.V_hopf_loop,
                "freq_hz": sens.frequency_hz, "amplitude": list(sens.amplitude),
                "kind": sens.kind, "truth_V": None if tr is None else tr.V,
                "truth_freq_hz": None if tr is None else tr.freq_hz,
                "truth_amplitude": None if tr is None else list(tr.amplitude),
                "truth_kind": None if tr is None else tr.kind,
                "branches": {name: {"V_hopf": br.hopf.V, "kind": br.hopf.kind,
                                    "points": len(br.points), "completed": br.completed}
                             for name, br in (("truth", self.lco.truth_branch),
                                              ("rom", self.lco.rom_branch))
                             if br is not None}}

    def _controller_summary(self) -> dict | None:
        if self.verification is None:
            return None
        ver = self.verification
        ti = self.truth_interval
        out = {"order": int(self.controller.nstates), "gamma": ver.gamma,
                "small_gain_V": _pair(ver.small_gain_V), "stable_V": _pair(self.rom_stable_V),
                "stable": bool(ver.stable),
                # an upper end without a crossing is written as null
                "truth_stable_V": None if ti is None else [
                    float(ti.lower), float(ti.upper) if math.isfinite(ti.upper) else None],
                "truth_servo_omega": (self.config.controller.flap_rate_bandwidth
                                      if self.truth is not None else None)}
        d = self.interval_design
        if d is not None:
            red = () if d.reduction is None else d.reduction.steps
            out["interval_design"] = {
                "order_requested": d.order, "met": d.met,
                "full_order": int(d.full_order.controller.nstates),
                "full_order_reached": list(d.full_order.reached),
                "orders_held": {str(st.order): st.met for st in red}}
        if self.convective_V0 is not None:
            # stable_V is the scaled loop's; the LFT's intervals hold for Σf frozen at Vf
            out["rom_servo_omega"] = self.config.controller.flap_rate_bandwidth
            out["stable_V_frozen_at_Vf"] = _pair(ver.exact_V)
        return out
