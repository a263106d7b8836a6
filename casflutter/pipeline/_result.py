"""The typed result of a study run, one field per stage, and its JSON summary."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import control
import numpy as np

from .._format import result_repr
from ..aeroelastic import FlutterResult, LoopSimulation
from .._outputs import plain_json
from ..lco import LcoComparison, LCOBranch
from ..truth import AeroelasticTruth, TruthLco, TruthLoopSweep
from ._config import RunConfig
from ._control import ControllerStage, design_objective
from ._exports import label_summary
from ._model import FlutterStage, ModelStage, ParametricResult
from ._suppression import SuppressionStage
from ._units import speed_scale, speed_values

__all__ = ["RunResult", "LcoResult", "ParametricResult", "SimulationCheck",
           "ClosedLoopChecks", "ModelStage", "FlutterStage", "ControllerStage",
           "SuppressionStage"]


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
    speed_following : tuple of LcoComparison
        The LCO of the ROM that follows the wing over speed beside the truth's, at
        ``lco.speed_following_factors`` times the truth's flutter speed (empty without a
        speed-following ROM or a truth).
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
    speed_following: tuple[LcoComparison, ...] = ()


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
    """A flutter search's block of ``summary.json``: its first destabilising flutter crossing
    (``V``, ``freq_hz``, ``mode`` from 1), ``status``, and whether the loop is unstable
    already at the low end of the range (``unstable_at_start``, with the spectral abscissa
    there): a crossing is then no flutter onset, and ``V`` no flutter speed."""
    if res is None:
        return None
    start = {"unstable_at_start": bool(res.unstable_at_start),
             "spectral_abscissa_start": float(res.spectral_abscissa_start)}
    if res.flutter is None:
        return {"V": None, "freq_hz": None, "mode": None, "status": res.status, **start}
    mode = res.flutter_mode
    return {"V": float(res.Vf), "freq_hz": float(res.omega_f) / (2 * np.pi),
            "mode": None if mode is None or mode < 0 else int(mode) + 1, "status": res.status,
            **start}


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
    """Everything a study run produced, one typed result per stage (``None``: not run).

    Attributes
    ----------
    config : RunConfig
        The configuration.
    problem : object
        What ``[problem]`` loaded: a truth, a wing file, a GAF file or a family file.
    route : str
        The problem's route (:data:`casflutter.pipeline.ROUTES`): ``"truth"``, ``"wing"``,
        ``"gaf"`` or ``"family"``.
    model : ModelStage
        The model stages: the ROM (records, identification, Σf) or the RFA, and the loop
        family the analyses take.
    flutters : FlutterStage
        Every flutter search: the model's (the paper's route), the truth's, the frozen and
        parametric ROMs', the RFA's and p–k.
    lco : LcoResult or None
        Stage ``lco``.
    control : ControllerStage or None
        Stage ``controller``: the design and the verification layer's certificates.
    closed_loop : ClosedLoopChecks or None
        Stage ``closed_loop``.
    suppression : SuppressionStage or None
        Stage ``suppression`` (paper Fig. 11): one run per ``suppression.speed_factors``.
    skipped : mapping
        Stage (or part of a stage) -> why it did not run.
    timings : mapping
        Seconds per stage and ``"total"``.
    out_dir : Path or None
        Where the files were written (``None``: nothing written).
    files : mapping
        Name -> path of every file written.
    provenance : mapping
        What produced the run (:func:`casflutter._outputs.provenance`: version, seed,
        thread settings, libraries) and its start time (``started``).
    """

    __repr__ = result_repr

    config: RunConfig
    problem: Any
    route: str
    model: ModelStage
    flutters: FlutterStage
    lco: LcoResult | None = None
    control: ControllerStage | None = None
    closed_loop: ClosedLoopChecks | None = None
    suppression: SuppressionStage | None = None
    skipped: Mapping[str, str] = field(default_factory=dict)
    timings: Mapping[str, float] = field(default_factory=dict)
    out_dir: Path | None = None
    files: Mapping[str, Path] = field(default_factory=dict)
    provenance: Mapping[str, Any] = field(default_factory=dict)

    # ------------------------------------------------------------------ the stages' parts
    @property
    def truth(self) -> AeroelasticTruth | None:
        """The truth simulator (``None`` without one)."""
        return self.problem if isinstance(self.problem, AeroelasticTruth) else None

    @property
    def data(self):
        """The chirp records of the last identification (``model.data``)."""
        return self.model.data

    @property
    def identification(self):
        """The ROM's identification (``model.identification``)."""
        return self.model.identification

    @property
    def identification_history(self) -> tuple:
        """``(V0, Vf_ROM)`` of every identification."""
        return self.model.identification_history

    @property
    def fit(self):
        """The ROM's free-run fit (paper Fig. 7)."""
        return self.model.fit

    @property
    def realization(self):
        """Σf by ERA and Tustin (eq. 5)."""
        return self.model.realization

    @property
    def system(self):
        """ΣAE(V) of the ROM (eq. 8-9), ``None`` for a family file."""
        return self.model.system

    @property
    def rfa(self):
        """The RFA of a GAF file's ``Q(ik)``."""
        return self.model.rfa

    @property
    def rfa_system(self):
        """ΣAE(U) of the RFA in the airspeed [m/s]."""
        return self.model.rfa_system

    @property
    def flutter(self) -> FlutterResult | None:
        """The flutter search of the model's loop (the paper's route, Table I)."""
        return self.flutters.rom

    @property
    def flutter_truth(self) -> FlutterResult | None:
        """The truth's flutter search."""
        return self.flutters.truth

    @property
    def flutter_frozen(self) -> FlutterResult | None:
        """The truth's with its aerodynamics frozen at V0 (stage ``frozen``)."""
        return self.flutters.frozen

    @property
    def parametric(self) -> ParametricResult | None:
        """Stage ``parametric``."""
        return self.flutters.parametric

    @property
    def rfa_flutter(self) -> FlutterResult | None:
        """The RFA system's flutter search (m/s, rad/s)."""
        return self.flutters.rfa

    @property
    def pk(self):
        """The p–k solution on a GAF file's table."""
        return self.flutters.pk

    @property
    def controller(self):
        """``K`` of the controller stage (``None`` without it)."""
        return None if self.control is None else self.control.controller

    @property
    def lft(self):
        """The LFT at Vf (eq. 14) of a ROM loop's controller stage."""
        return None if self.control is None else self.control.lft

    @property
    def synthesis(self):
        """The paper's synthesis (``controller.method = "paper"``)."""
        return None if self.control is None else self.control.synthesis

    @property
    def design(self):
        """The multi-speed design (``controller.method = "multispeed"``)."""
        return None if self.control is None else self.control.design

    @property
    def verification(self):
        """γ and the intervals of the LFT at Vf (eq. 10-16)."""
        return None if self.control is None else self.control.verification

    @property
    def controlled_rom(self):
        """The loop family the controller was designed on and is certified on first."""
        if self.control is not None:
            return self.control.family
        return self.model.family

    def _check(self, name: str):
        return None if self.control is None else self.control.checks.get(name)

    @property
    def rom_sweep(self):
        """The dense eigenvalue sweep of the LFT's loop over ``verify.sweep`` x Vf
        (:class:`casflutter.verify.SpeedSweep`), when the configuration asks for it."""
        return None if self.control is None else self.control.sweep

    @property
    def rom_stable_V(self) -> tuple | None:
        """The certified stable interval of the design family closed by the controller
        (:func:`casflutter.verify.verify_family`; ``None`` when it does not hold the loop at
        the range's start)."""
        check = self._check("design")
        return None if check is None else check.stable_interval

    @property
    def truth_stable_V(self) -> tuple | None:
        """The certified stable interval of the truth's own linearisation (flap behind the
        servo) closed by the controller."""
        check = self._check("truth")
        return None if check is None else check.stable_interval

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

    def divergence_errors(self) -> dict:
        """The ROMs' divergence speeds against the truth's.

        Returns
        -------
        dict
            ``(Vd - Vd_truth) / Vd_truth`` of the ROM (``"rom"``) and of the parametric ROM
            (``"parametric_rom"``), each ``None`` where either has no divergence in the
            range.
        """
        def vd(res):
            return None if res is None or res.divergence is None else res.divergence.V

        truth = vd(self.flutter_truth)
        parametric = None if self.parametric is None else self.parametric.flutter
        return {"rom": _rel(vd(self.flutter), truth),
                "parametric_rom": _rel(vd(parametric), truth)}

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
            text += (f" The V² scaling of ΣAE freezes the aerodynamic time scale (the "
                     f"reduced frequency: the aerodynamic damping, and any lag or apparent-mass "
                     f"terms) at V0; the truth "
                     f"with its aerodynamics frozen at V0 flutters at "
                     f"{pct(self.scaling_error)}, so the scaling explains the error up to "
                     f"{pct(self.identification_error)} from identification and Tustin.")
        if self.parametric is not None:
            text += (f" Parametric ROM ({len(self.parametric.rom.speeds)} speeds): "
                     f"{pct(self.parametric_error)}.")
        dv = self.divergence_errors()
        if self.flutter_truth is not None and self.flutter_truth.divergence is not None:
            text += (f" Divergence speed error vs the truth's: ROM {pct(dv['rom'])}"
                     + (f", parametric ROM {pct(dv['parametric_rom'])}"
                        if self.parametric is not None else "") + ".")
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
        """The speeds the controller must hold: ``verify.required`` times Vf when given, else
        the multi-speed design's ``controller.interval`` (``None`` without a target)."""
        req = self.config.verify.required
        if req and self.Vf is not None:
            return (req[0] * self.Vf, req[1] * self.Vf)
        if self.control is not None and self.control.method == "multispeed":
            return tuple(self.config.controller.interval)
        return None

    @property
    def interval_ok(self) -> bool | None:
        """The certified stable interval of the design family (:attr:`rom_stable_V`)
        contains :attr:`required_V` (``None`` without a target or a controller).  The
        truth's certificate is reported beside it (:attr:`truth_stable_V`), not required: a
        ROM identified at one speed stands for the truth near that speed only."""
        if self.required_V is None or self.control is None:
            return None
        lo, hi = self.required_V
        return bool(self.control.checks["design"].covers(lo, hi))

    @property
    def robust_ok(self) -> bool | None:
        """The design family's loop-at-a-time margins (``controller.margins``) hold over
        :attr:`required_V`, and its certified interval covers it: the verdict of
        ``casflutter verify --require-v`` on the same family and controller
        (:meth:`casflutter.verify.FamilyVerification.robust_over`); ``None`` without a
        target or a controller.  Required by :attr:`success` only with
        ``verify.require_margins``."""
        if self.required_V is None or self.control is None:
            return None
        return bool(self.control.checks["design"].robust_over(*self.required_V))

    @property
    def rom_unstable_at_start(self) -> bool:
        """The ROM loop (truth and wing routes) is unstable already at the low end of
        ``flutter.V_range`` (``FlutterResult.unstable_at_start``): it has no flutter speed,
        and :attr:`success` is false."""
        return bool(self.route in ("truth", "wing") and self.flutter is not None
                    and self.flutter.unstable_at_start)

    @property
    def success(self) -> bool:
        """Every check that ran passed: the ROM loop is stable at the start of
        ``flutter.V_range`` (:attr:`rom_unstable_at_start`), the interval target holds (and,
        with ``verify.require_margins``, the margins over it: :attr:`robust_ok`), and both
        closed-loop simulations grow open loop and decay closed loop."""
        ok = self.interval_ok is not False and not self.rom_unstable_at_start
        if self.config.verify.require_margins:
            ok = ok and self.robust_ok is not False
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
            ``problem``, ``route``, ``V0``, ``n_sensors``, ``orders``, ``n_params``,
            ``fit_error_percent``, ``nf``, ``ns``, ``nae``, ``flutter``, ``flutter_truth``,
            ``lco``, ``controller``, ``suppression`` (``runs``: one record per speed; the
            first run's numbers also at its top level) (``None`` when the stage did not run),
            ``timings_s``, ``seed``; ``skipped`` (stage -> reason) when a stage was
            skipped; and, for the stages that ran, ``v0_history``, ``flutter_frozen``,
            ``flutter_parametric``, ``verification``, ``rfa``, ``family``,
            ``closed_loop``, and, on an HWL ROM, ``flutter_convective`` (the ROM that
            follows the wing over speed; ``flutter`` stays the paper's frozen route of
            Table I) and ``control_reversal_V`` (the flutter mode's, per loop).
        """
        cfg = self.config
        out = {"problem": cfg.problem.name, "route": self.route, **self._model_summary(),
               "flutter": _flutter_summary(self.flutter),
               "flutter_truth": _flutter_summary(self.flutter_truth),
               "lco": self._lco_summary(), "controller": self._controller_summary(),
               "suppression": self._suppression_summary(),
               "timings_s": dict(self.timings), "seed": cfg.seed}
        if self.skipped:
            out["skipped"] = dict(self.skipped)
        if self.convective_V0 is not None:
            out["convective_V0"] = float(self.convective_V0)
        if cfg.rom.v0_iterations > 1 and self.route in ("truth", "wing"):
            out["v0_history"] = [list(map(float, p)) for p in self.identification_history]
        if self.flutters.convective is not None:
            out["flutter_convective"] = _flutter_summary(self.flutters.convective)
            out["control_reversal_V"] = {name: None if r is None else float(r.V)
                                         for name, r in self.flutters.reversals.items()}
        if self.flutter_frozen is not None:
            out["flutter_frozen"] = _flutter_summary(self.flutter_frozen)
        if self.parametric is not None:
            out["flutter_parametric"] = _flutter_summary(self.parametric.flutter)
        if self.interval_ok is not None:
            out["verification"] = {"required_V": _pair(self.required_V),
                                   "interval_ok": self.interval_ok,
                                   "robust_ok": self.robust_ok,
                                   "margins": list(cfg.controller.margins),
                                   "require_margins": cfg.verify.require_margins,
                                   "success": self.success}
        U_ref = getattr(self.problem, "U_ref", None)
        if U_ref is not None and out["flutter"] is not None and out["flutter"]["V"] is not None:
            out["flutter"]["airspeed_m_s"] = out["flutter"]["V"] * U_ref
        if self.rfa is not None:
            out["rfa"] = self._rfa_summary()
        if self.route == "family":
            out["family"] = self._family_summary()
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

    def _model_summary(self) -> dict:
        """The ROM's sizes and fit (``None`` entries where the route has none)."""
        model = None if self.identification is None else self.identification.model
        structure = (self.system.structure if self.system is not None
                     else self.rfa_system.structure if self.rfa_system is not None else None)
        fam = self.model.family
        return {
            "V0": self.config.data.V0 if model is not None else None,
            "n_sensors": (int(structure.n_sensors) if structure is not None
                          else len(fam.signals.measurements)),
            "orders": None if model is None else list(model.orders.as_tuple()),
            "n_params": None if model is None else model.n_params,
            "fit_error_percent": None if self.fit is None else list(self.fit.error_percent),
            "nf": None if self.realization is None else self.realization.order,
            "ns": None if structure is None else 2 * structure.n_modes,
            "nae": (int(self.system.state_matrix(0.0).shape[0]) if self.system is not None
                    else int(fam.n_states) if self.route == "family" else None)}

    def _family_summary(self) -> dict:
        """A family file's size, signals and every open-loop crossing (``flutter`` of
        ``casflutter flutter FAMILY``), with the status of the first destabilising one and
        whether the family is unstable already at the low end of its range.  ``n_states``
        is the number of states analysed, ``n_states_file`` the number in the file, and
        ``left_out_states`` the file's states (0-based) that were left out as rigid-body
        positions (:func:`casflutter.aeroelastic.load_family`)."""
        fam, fl = self.model.family, self.flutter
        sig = fam.signals
        left_out = [int(i) for i in getattr(fam, "left_out_states", ())]
        return {"name": fam.name, "n_states": int(fam.n_states),
                "n_states_file": int(fam.n_states) + len(left_out),
                "left_out_states": left_out, "speed_unit": fam.speed_unit,
                "time_unit": fam.time_unit, "speed_range": list(fam.speed_range),
                "feedback": fam.feedback, "controls": list(sig.controls),
                "measurements": list(sig.measurements),
                "status": None if fl is None else fl.status,
                "unstable_at_start": None if fl is None else bool(fl.unstable_at_start),
                "spectral_abscissa_start": (None if fl is None
                                            else float(fl.spectral_abscissa_start)),
                "crossings": [] if fl is None else [
                    {"speed": c.V, "omega_rad_s": c.omega, "freq_hz": c.frequency_hz,
                     "branch": int(c.branch), "kind": c.kind, "direction": c.direction}
                    for c in fl.crossings]}

    def _suppression_summary(self) -> dict | None:
        """The tunnel's settings, every run's record (``runs``) and, at the top level, the
        first run's numbers (the keys of a single run)."""
        cfg, stage = self.config.suppression, self.suppression
        if stage is None:
            return None
        sup = stage.runs[0]
        return {"attenuation_percent": sup.attenuation_percent,
                "lco_returns": sup.lco_returns, "V": sup.V,
                "open_loop_amplitude": list(sup.open_loop_amplitude),
                "closed_loop_amplitude": list(sup.closed_loop_amplitude),
                "dominant_sensor": sup.dominant_sensor,
                "started_from_lco": sup.started_from_lco,
                "V_flutter": stage.V_flutter, "flutter_of": stage.reference,
                "flap_limit": cfg.flap_limit, "flap_rate_limit": cfg.flap_rate_limit,
                "command_limiter": cfg.command_limiter,
                "gust_intensity": cfg.gust_intensity, "gust_scale": cfg.gust_scale,
                "noise": cfg.noise,
                "runs": [dict(r.record(), linear_loop_certified=ok)
                         for r, ok in zip(stage.runs, stage.linear_loop_certified)]}

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
        # a frequency and an amplitude are a cycle's: a divergence or a decay has none
        cycle, truth_cycle = sens.kind == "lco", tr is not None and tr.kind == "lco"
        return {"V": self.lco.V, "V_hopf_exact_order": self.lco.V_hopf_exact_order,
                "V_hopf_loop": self.lco.V_hopf_loop,
                "freq_hz": sens.frequency_hz if cycle else None,
                "amplitude": list(sens.amplitude) if cycle else None,
                "kind": sens.kind, "truth_V": None if tr is None else tr.V,
                "truth_freq_hz": tr.freq_hz if truth_cycle else None,
                "truth_amplitude": list(tr.amplitude) if truth_cycle else None,
                "truth_kind": None if tr is None else tr.kind,
                "branches": {name: {"V_hopf": br.hopf.V, "kind": br.hopf.kind,
                                    "points": len(br.points), "completed": br.completed}
                             for name, br in (("truth", self.lco.truth_branch),
                                              ("rom", self.lco.rom_branch))
                             if br is not None},
                "speed_following": [c.record() for c in self.lco.speed_following]}

    def _controller_summary(self) -> dict | None:
        """The controller stage: order, method, the certified intervals and flutter speeds
        on the design family and on the truth, the design family's response error against
        the truth (``model_error``), the paper's γ, the design time."""
        c = self.control
        if c is None:
            return None

        def certified(name: str) -> dict:
            check = c.checks.get(name)
            if check is None:
                return {}
            iv = check.stable_interval
            return {"stable_interval": None if iv is None else [
                        float(iv[0]), float(iv[1]) if math.isfinite(iv[1]) else None],
                    "absolute_flutter_speed": check.absolute_flutter_speed,
                    "robust_flutter_speed": check.robust_flutter_speed,
                    "robust_flutter_reason": check.robust_reason}

        out = {"order": c.order, "method": c.method, **certified("design"),
               "design_time_s": c.design_time_s,
               "servo_omega": ((self.config.controller.servo_omega or None)
                               if self.route != "family" else None)}
        truth = certified("truth")
        if truth:
            out.update({"truth_" + k: v for k, v in truth.items()})
        if c.mismatch:
            out["model_error"] = {name: {"speeds": m.speeds.tolist(),
                                         "worst_relative_error": m.worst().tolist(),
                                         "band": list(m.band)}
                                  for name, m in c.mismatch.items()}
        if c.design is not None:
            d = c.design
            out.update(interval=list(d.interval), held=bool(d.held), reach=d.reached[1],
                       interval_decay=d.decay, design_gamma=d.gamma,
                       hinf_objective=design_objective(self.config, c.family,
                                                       c.lft is not None),
                       design_message=d.message,
                       design_starts=[{"kind": h.kind, "order": h.order,
                                       "reached": list(h.reached)} for h in d.starts],
                       start=self.config.controller.start or None)
        if c.verification is not None:
            ver = c.verification
            out.update(gamma=ver.gamma, small_gain_V=_pair(ver.small_gain_V),
                       lft_stable_V=_pair(ver.exact_V) if ver.stable else None,
                       stable=bool(ver.stable))
        if c.synthesis is not None:
            out["synthesis_gamma"] = float(c.synthesis.gamma)
        syn = c.synthesis if c.design is None else c.design.synthesis
        # the H∞ optimisation met its stopping test, and its iterations (None: no H∞ phase)
        out["hinf_converged"] = None if syn is None else bool(syn.converged)
        out["hinf_iterations"] = None if syn is None else int(syn.best.outer_iterations)
        return out
