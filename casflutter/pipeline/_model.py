"""The model stages of a run: from the problem to the loop family every analysis takes.

Each kind of problem has one route, chosen in one place (:data:`ROUTES`) by what the problem
offers:

* a **truth** simulator (typical section, Goland wing, the paper's wing, rig files): chirp
  records at ``V0``, the ROM (HWL of eq. 1-4 or common denominator), Σf by ERA and Tustin
  (eq. 5), ΣAE(V) (eq. 8-9) and its flutter beside the truth's (stages 1-5 of the paper), with
  the identification speed iterated to the ROM's own flutter speed when asked;
* a **wing file** with records only (``kind = "wing"``): the same on its records, without the
  truth-only parts;
* a **GAF file** (``kind = "gaf"``): the rational-function approximation of ``Q(ik)``, ΣAE(U)
  in the airspeed, its flutter beside the p–k solution, and Σf frozen at the flutter speed;
* a **plant family file** (``kind = "plant_family"``): the gridded family itself and every
  open-loop crossing in its range.

The result is a :class:`ModelStage` (the model and the family the controller stage designs
on) and a :class:`FlutterStage` (every flutter search of the route).
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

from .._format import result_repr
from .._settings import build_settings, settings_as
from ..aeroelastic import (AeroelasticSystem, FlutterResult, ParametricSystem, PKResult,
                           RFASystem, SpeedFollowingROM, TruthLoop, control_reversal,
                           family_flutter, find_flutter, load_family, pk_flutter,
                           speed_following_rom)
from ..data import IOData
from ..errors import CasflutterError, ConfigError, ConvergenceError, DataError
from ..ident import (CommonDenominatorResult, FitReport, HWLModel, IdentificationResult,
                     IdentificationSettings, fit_report, identify, identify_common_denominator)
from ..realize import (ParametricROM, RationalApproximation, Realization, RFASettings, fit_rfa,
                       realize, speed_nodes)
from ..truth import (AeroelasticTruth, GAFProblem, RecordSettings, WingProblem,
                     frozen_aero_truth, truth_records)
from ._config import RunConfig

__all__ = ["ModelStage", "FlutterStage", "ParametricResult", "Route", "ROUTES", "route_of"]

log = logging.getLogger("casflutter.pipeline")


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
class ModelStage:
    """The model a run analyses and the loop family its controller stage designs on.

    Attributes
    ----------
    family : PlantFamily
        What the flutter search, the design and the verification take: ΣAE(V) of the ROM
        (eq. 8-9), or the gridded family of a family file.
    system : AeroelasticSystem or None
        The ROM loop of eq. 8 (``None`` for a family file, or a GAF file whose RFA has
        ``p`` terms: no proper Σf).
    data : IOData or None
        The chirp records of the last identification.
    identification : IdentificationResult or CommonDenominatorResult or None
        The ROM (``.model``).
    identification_history : tuple of (float, float or None)
        ``(V0, Vf_ROM)`` of every identification (more than one with ``rom.v0_iterations``).
    fit : FitReport or None
        Free-run fit of the ROM on its records (paper Fig. 7).
    realization : Realization or None
        Σf by ERA and Tustin (eq. 5).
    rfa : RationalApproximation or None
        The RFA of a GAF file's ``Q(ik)``.
    rfa_system : RFASystem or None
        Its ΣAE(U) in the airspeed [m/s].
    V0 : float or None
        The identification speed (the records' speed).
    speed_following : SpeedFollowingROM or None
        The paper's HWL ROM (``rom.method = "hwl"``) made to follow the wing over speed
        (records' coupling delay removed, Σf's time scaled by V / V0,
        :func:`casflutter.aeroelastic.speed_following_rom`), beside the paper's frozen loop
        of eq. 8; ``None`` for other ROMs (``rom.convective`` scales a common-denominator
        ROM's time itself) and routes.
    """

    __repr__ = result_repr

    family: object
    system: AeroelasticSystem | None = None
    data: IOData | None = None
    identification: IdentificationResult | CommonDenominatorResult | None = None
    identification_history: tuple = ()
    fit: FitReport | None = None
    realization: Realization | None = None
    rfa: RationalApproximation | None = None
    rfa_system: RFASystem | None = None
    V0: float | None = None
    speed_following: SpeedFollowingROM | None = None


@dataclass(frozen=True)
class FlutterStage:
    """Every flutter search of a run's route.

    Attributes
    ----------
    rom : FlutterResult or None
        Of the model's loop: ΣAE(V) of the ROM (the paper's route, Table I), or the
        family's crossings.
    truth : FlutterResult or None
        Of the truth (``None`` without one).
    frozen : FlutterResult or None
        Of the truth with its aerodynamics frozen at ``V0`` (stage ``frozen``).
    parametric : ParametricResult or None
        Stage ``parametric``.
    rfa : FlutterResult or None
        Of a GAF file's ΣAE(U) (speeds in m/s).
    pk : PKResult or None
        The p–k solution on the same ``Q(ik)``.
    Vf : float or None
        The speed the LFT is built at: the ROM loop's flutter speed (a GAF file's ``Uf /
        U_ref``, where Σf is frozen); ``None`` without a flutter crossing, or when the ROM
        loop is unstable already at the start of ``flutter.V_range`` (its crossings are then
        no flutter onsets: ``rom.unstable_at_start``).
    convective : FlutterResult or None
        Of the speed-following ROM (:attr:`ModelStage.speed_following`).
    reversals : mapping of str to ControlReversal or None
        The flutter mode's control reversal (:func:`casflutter.aeroelastic.control_reversal`,
        flap behind the servo of ``controller.servo_omega``) on ``"speed_following"``,
        ``"rom"`` (the paper's loop) and ``"truth"``; ``None`` where the mode has none.
    """

    __repr__ = result_repr

    rom: FlutterResult | None = None
    truth: FlutterResult | None = None
    frozen: FlutterResult | None = None
    parametric: ParametricResult | None = None
    rfa: FlutterResult | None = None
    pk: PKResult | None = None
    Vf: float | None = None
    convective: FlutterResult | None = None
    reversals: Mapping[str, object] = field(default_factory=dict)


# ---------------------------------------------------------------------------- routes
@dataclass(frozen=True)
class Route:
    """One kind of problem: what it is called, what it cannot do, and its model stages.

    Attributes
    ----------
    kind : str
        ``"truth"``, ``"wing"``, ``"gaf"`` or ``"family"``.
    stages : tuple of str
        The model stages it runs, in order (for the progress lines).
    offers : frozenset of str
        What its problems offer the later stages: ``"truth"`` (a simulator: its flutter,
        LCO, closed loops and suppression), ``"records"`` (a ROM, hence LCO on a nonlinear
        one), ``"lft"`` (a ROM loop with a flutter speed: the paper's LFT).
    """

    __repr__ = result_repr

    kind: str
    stages: tuple
    offers: frozenset


ROUTES = {
    "truth": Route("truth", ("data", "rom", "realize", "structure", "flutter"),
                   frozenset({"truth", "records", "lft"})),
    "wing": Route("wing", ("data", "rom", "realize", "structure", "flutter"),
                  frozenset({"records", "lft"})),
    "gaf": Route("gaf", ("rfa", "flutter", "realize", "structure"), frozenset({"lft"})),
    "family": Route("family", ("family", "flutter"), frozenset()),
}
"""The routes by kind of problem (module docstring)."""


def route_of(problem) -> Route:
    """The route of a loaded problem (:meth:`ProblemSection.load`).

    Parameters
    ----------
    problem : object
        A truth simulator, a wing file, a GAF file or a family file.

    Returns
    -------
    Route

    Raises
    ------
    ConfigError
        Anything else.
    """
    for kind, cls in (("truth", AeroelasticTruth), ("gaf", GAFProblem), ("wing", WingProblem)):
        if isinstance(problem, cls):
            return ROUTES[kind]
    if hasattr(problem, "speeds") and hasattr(problem, "feedback"):     # a family file
        return ROUTES["family"]
    raise ConfigError(f"the problem is a {type(problem).__name__}, which casflutter.pipeline.run "
                      "does not take; give a truth problem, a wing file (kind = \"wing\" or "
                      "\"gaf\") or a plant family file (kind = \"plant_family\")")


# ---------------------------------------------------------------------------- ROM route
def _identify(data, cfg: RunConfig):
    """The ROM of the records: the identification result."""
    r = cfg.rom
    if r.method == "common_denominator":
        return identify_common_denominator(data, r.na, r.nb)
    settings = replace(settings_as(r, IdentificationSettings),
                       ipopt_options={**cfg.solver.ipopt, **r.ipopt_options})
    return identify(data, tuple(r.orders), settings=settings)


def _flutter_kw(cfg: RunConfig) -> dict:
    return dict(n_grid=cfg.flutter.n_grid, max_refine=cfg.flutter.max_refine)


def _rom_flutter(system, V_range, kw: dict) -> FlutterResult:
    """:func:`find_flutter` on the ROM loop, its warning about a loop unstable at the range's
    start held back (:func:`rom_model` says it in its own words, with the fix)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*unstable already at", category=RuntimeWarning)
        return find_flutter(system, V_range, **kw)


def _unstable_note(flutter: FlutterResult, system: AeroelasticSystem) -> str:
    """Why a ROM loop unstable already at the low end of ``flutter.V_range`` has no flutter
    speed, and the fix."""
    V_lo = float(flutter.tracking.V[0])
    text = (f"the ROM loop ΣAE(V) is unstable already at V = {V_lo:g}, the start of "
            f"flutter.V_range (spectral abscissa {flutter.spectral_abscissa_start:.3g})")
    if not system.rom_stable:
        text += ": Σf, the identified ROM, is unstable on its own"
    text += ("; its crossing at V = {:.5g} is no flutter onset".format(flutter.Vf)
             if flutter.Vf is not None else "") + ", so the ROM has no flutter speed"
    if not system.rom_stable:
        return text + ("; identify a ROM that is stable on its own (see its fit error; other "
                       "rom.orders, rom.na / rom.nb or rom.method)")
    return text + (f"; the loop flutters below V = {V_lo:g} or the ROM is poor there: lower "
                   "the start of flutter.V_range")


def _needing(cfg: RunConfig) -> str:
    """What of the configuration needs the ROM's flutter speed, in words."""
    stages = [repr(s) for s in cfg.stages if s in ("lco", "controller")]
    if stages:
        return f"stage{'s' if len(stages) > 1 else ''} {' and '.join(stages)} need" + (
            "s" if len(stages) == 1 else "")
    return f"rom.v0_iterations = {cfg.rom.v0_iterations} needs"


def rom_model(cfg: RunConfig, problem, structure, progress, *, needs_vf: bool
              ) -> tuple[ModelStage, FlutterStage]:
    """Stages 1-5 on a truth or a wing file: records, ROM, Σf, ΣAE(V), flutter; repeated at
    the ROM's own flutter speed with ``rom.v0_iterations > 1``.

    Parameters
    ----------
    cfg : RunConfig
        The configuration (``data.V0`` is a wing file's own records' speed).
    problem : AeroelasticTruth or WingProblem
        The problem.
    structure : ModalStructure
        Σs with the run's sensors.
    progress : object
        ``stage(name)`` context manager of the run's progress.
    needs_vf : bool
        A later stage needs the ROM's flutter speed.

    Returns
    -------
    (ModelStage, FlutterStage)
        The records, the ROM, its fit, Σf and ΣAE(V); the flutter of the ROM loop, of the
        truth and (``rom.method = "hwl"``) of the speed-following ROM.  A ROM loop unstable
        already at the low end of ``flutter.V_range`` (``FlutterResult.unstable_at_start``,
        e.g. an unstable Σf) has no flutter speed: ``FlutterStage.Vf`` is ``None`` and a
        warning says why, while ``FlutterStage.rom`` keeps the search with its crossings.

    Raises
    ------
    CasflutterError
        No ROM flutter in ``flutter.V_range``, or a ROM loop unstable already at its low
        end, when ``needs_vf``.
    """
    truth = problem if isinstance(problem, AeroelasticTruth) else None
    records = settings_as(cfg.data, RecordSettings)
    vr, kw = cfg.flutter.V_range, _flutter_kw(cfg)
    V0, history, flutter_truth = float(cfg.data.V0), [], None
    for it in range(cfg.rom.v0_iterations):
        with progress.stage("data"):
            data = truth_records(truth, records, V0=V0) if truth is not None else problem.records
        with progress.stage("rom"):
            ident = _identify(data, cfg)
        with progress.stage("realize"):
            real = realize(ident.model, cfg.rom.nf)
        with progress.stage("structure"):
            system = AeroelasticSystem.from_parts(
                real.sigma_f, structure, warn_unstable=False,
                convective_V0=V0 if cfg.rom.convective else None)
        with progress.stage("flutter"):
            flutter = _rom_flutter(system, vr, kw)
            if not system.rom_stable and not flutter.unstable_at_start:
                log.warning("Σf is unstable on its own (ΣAE unstable at V = 0), though its "
                            "loop is stable at V = %g", vr[0])
            # a loop unstable already at the range's start has no flutter onset in it
            Vf = None if flutter.unstable_at_start else flutter.Vf
            last = (it == cfg.rom.v0_iterations - 1 or Vf is None
                    or abs(Vf - V0) <= cfg.rom.v0_rtol * Vf)
            if last and truth is not None:
                flutter_truth = find_flutter(truth, vr, **kw)
            if flutter.unstable_at_start:
                why = _unstable_note(flutter, system)
                if needs_vf:
                    raise CasflutterError(f"{why}; {_needing(cfg)} the ROM's flutter speed")
                log.warning("%s", why)
            elif Vf is None and needs_vf:
                raise CasflutterError(f"the ROM identified at V0 = {V0:.4g} has no flutter "
                                      f"crossing in V ∈ {vr}: {flutter.message}; widen "
                                      "flutter.V_range")
            history.append((V0, None if Vf is None else float(Vf)))
        if last:
            break
        V0 = float(Vf)
    model = ident.model
    fit = (ident.fit if isinstance(ident, IdentificationResult)
           else fit_report(model, data, "simulation"))
    log.info("%s; fit error %% %s", model, ", ".join(f"{e:.4g}" for e in fit.error_percent))
    note = (f"ROM Vf = {Vf:.5g}" if Vf is not None
            else "ROM: no flutter speed (its loop is unstable already at V = "
                 f"{vr[0]:g})" if flutter.unstable_at_start
            else "ROM: no flutter in flutter.V_range")
    if flutter_truth is not None:
        note += (f"; truth Vf = {flutter_truth.Vf:.5g}" if flutter_truth.flutter is not None
                 else "; truth: no flutter in flutter.V_range")
    log.info(note)
    sf, reversals = None, {}
    if cfg.rom.method == "hwl" and isinstance(model, HWLModel) and not cfg.rom.convective:
        with progress.stage("flutter"):
            sf, reversals = _speed_following(cfg, model, structure, V0, system, truth)
    stage = ModelStage(family=system, system=system, data=data, identification=ident,
                       identification_history=tuple(history), fit=fit, realization=real, V0=V0,
                       speed_following=sf)
    return stage, FlutterStage(rom=flutter, truth=flutter_truth, Vf=Vf,
                               convective=None if sf is None else sf.flutter,
                               reversals=reversals)


def _speed_following(cfg: RunConfig, model: HWLModel, structure, V0: float, system, truth):
    """The ROM that follows the wing over speed and the flutter mode's control reversal on
    it, on the paper's loop and on the truth (flap behind ``controller.servo_omega``);
    ``(None, {})`` with a note when the ROM's input delay is shorter than the records'
    coupling delay."""
    delay = cfg.data.coupling_delay if truth is not None else 0
    if model.orders.r < delay:
        log.info("no speed-following ROM: the ROM's input delay r = %d is shorter than the "
                 "records' coupling delay %d", model.orders.r, delay)
        return None, {}
    fl = cfg.flutter
    sf = speed_following_rom(model, structure, V0, coupling_delay=delay, V_range=fl.V_range,
                             n_grid=fl.n_grid, max_refine=fl.max_refine)
    servo = cfg.controller.servo_omega
    families = {"speed_following": sf.system, "rom": system}
    if servo > 0:
        families = {name: fam.with_servo(servo) for name, fam in families.items()}
        if truth is not None:
            families["truth"] = TruthLoop(truth, servo, sensors=structure)
    speeds = np.linspace(*fl.V_range, 48)
    reversals = {name: control_reversal(fam, speeds) for name, fam in families.items()}
    V = sf.flutter.Vf
    log.info("speed-following ROM Vf = %s; control reversal %s",
             "none" if V is None else f"{V:.5g}",
             ", ".join(f"{k} {r.V:.4g}" for k, r in reversals.items() if r is not None))
    return sf, reversals


def frozen_flutter(cfg: RunConfig, truth, V0: float) -> FlutterResult:
    """Stage ``frozen``: the truth's flutter with its aerodynamics frozen at ``V0``."""
    return find_flutter(frozen_aero_truth(truth, V0), cfg.flutter.V_range, **_flutter_kw(cfg))


def parametric_flutter(cfg: RunConfig, truth, structure) -> ParametricResult:
    """Stage ``parametric``: common-denominator ROMs at several speeds, interpolated in V,
    and their flutter."""
    vr = cfg.flutter.V_range
    records = settings_as(cfg.data, RecordSettings)
    speeds = speed_nodes(vr, cfg.parametric.n_speeds)
    prom = ParametricROM(speeds, tuple(
        identify_common_denominator(truth_records(truth, records, V0=float(v)), cfg.rom.na,
                                    cfg.rom.nb) for v in speeds))
    psys = ParametricSystem(prom, structure)
    return ParametricResult(prom, psys, find_flutter(psys, vr, n_grid=cfg.flutter.n_grid,
                                                     max_refine=cfg.parametric.max_refine))


# ---------------------------------------------------------------------------- GAF route
def gaf_settings(cfg: RunConfig, gaf: GAFProblem) -> RFASettings:
    """The RFA settings of a GAF file, checked before any work."""
    try:
        settings = build_settings(RFASettings, gaf.rfa)
    except ConfigError as exc:
        raise ConfigError(f"[gaf] of the wing file {gaf.path}: {exc}") from None
    if "controller" in cfg.stages and settings.poly_order != 0:
        raise ConfigError(f"stages: 'controller' on the GAF problem {gaf.name!r} needs the "
                          "frozen Σf of eq. 5, which is proper only without p, p^2 terms; set "
                          f"gaf.poly_order = 0 in {gaf.path} (now {settings.poly_order}) or "
                          "drop the controller stage")
    if cfg.rom.convective:
        raise ConfigError("rom.convective: a GAF problem's rational-function aerodynamics "
                          "already scale with the speed; leave it false")
    return settings


#: airspeeds of the p–k cross-check over ``gaf.U_range``
_PK_SPEEDS = 29


def _pk_span(table, structure, U: np.ndarray, m: int, start: int):
    """p–k on mode ``m`` over ``U[start:end]``, ``end`` as large as the table allows from
    ``start``: ``(PKResult, end)``, or ``(None, start)`` when the iteration leaves the table
    already between ``U[start]`` and ``U[start + 1]``."""
    def solve(end):
        try:
            return pk_flutter(table, structure, U[start:end], modes=(m,))
        except DataError:          # the iteration needs k beyond the table
            return None

    res = solve(U.size)
    if res is not None:
        return res, U.size
    good, bad, best = start + 2, U.size, solve(start + 2)
    if best is None:
        return None, start
    while bad - good > 1:          # the largest end the table holds
        mid = (good + bad) // 2
        trial = solve(mid)
        if trial is None:
            bad = mid
        else:
            good, best = mid, trial
    return best, good


def _pk_mode(gaf: GAFProblem, structure, U: np.ndarray, m: int):
    """p–k on mode ``m`` over the speeds ``U`` where the table holds it: from the first speed
    whose in-vacuo reduced frequency ``omega b / U`` lies inside the table (later while the
    iteration still leaves the table there), up to where it leaves the table.

    Returns
    -------
    (PKResult or None, int, int, str)
        The solution on ``U[start:end]`` (``None``: the mode cannot be followed anywhere in
        ``U``), ``start``, ``end``, and why it is followed over a part of ``U`` or not at all
        (``""`` over the whole of ``U``).
    """
    table = gaf.table
    k_max = float(table.k[-1])
    beyond = f"p–k needs k beyond the table's k <= {k_max:g}"
    inside = np.flatnonzero(float(structure.omega[m]) * table.b <= k_max * U)
    if inside.size == 0:
        return None, 0, 0, (f"the in-vacuo k = omega b / U lies beyond the table's k <= "
                            f"{k_max:g} up to U = {U[-1]:g} m/s")
    try:
        for start in range(int(inside[0]), U.size - 1):
            res, end = _pk_span(table, structure, U, m, start)
            if res is not None:
                break
        else:
            return None, 0, 0, f"{beyond} at every speed"
    except ConvergenceError as exc:
        return None, 0, 0, str(exc)
    if start == 0 and end == U.size:
        return res, start, end, ""
    if end == U.size:
        return res, start, end, f"below it {beyond}"
    if start == 0:
        return res, start, end, f"above it {beyond}"
    return res, start, end, f"elsewhere {beyond}"


def pk_check(gaf: GAFProblem, structure) -> PKResult:
    """The p–k solution on a GAF file's table over ``gaf.U_range``
    (:func:`casflutter.aeroelastic.pk_flutter`), each mode followed over the speeds where
    the table holds it, and a note on every mode it leaves out.

    p–k follows a mode from its in-vacuo frequency, and every iteration must stay inside the
    table's reduced frequencies: a mode whose ``k = omega b / U`` lies beyond the table at
    the low speeds is followed from the first speed where it does not (and where the
    iteration stays inside), up to the last speed where the iteration stays inside; a mode
    the table never holds is left out.

    Parameters
    ----------
    gaf : GAFProblem
        The GAF file.
    structure : ModalStructure
        Σs of its modes.

    Returns
    -------
    PKResult
        Every mode p–k could follow (``modes``), ``NaN`` at the speeds where it could not;
        the lowest flutter speed among them; ``message`` names the modes left out or
        followed over a part of the speeds, and why.  With no mode followed at all
        ``modes`` is empty and the message says why p–k is unavailable.
    """
    U = np.linspace(*gaf.U_range, _PK_SPEEDS)
    names = gaf.table.mode_names
    tracked, best, spans = [], None, []
    notes: dict = {}           # what is said -> the modes it is said of
    for m in range(structure.n_modes):
        res, start, end, why = _pk_mode(gaf, structure, U, m)
        if res is None:
            notes.setdefault(f"left out: {why}", []).append(m)
            continue
        tracked.append(m)
        spans.append((start, end, res))
        if why:
            notes.setdefault(f"followed for U in [{U[start]:.4g}, {U[end - 1]:.4g}] m/s only "
                             f"({why})", []).append(m)
        if res.eigenvalues[0, 0].real > 0:
            where = "the start of gaf.U_range" if start == 0 else "where p–k starts to follow it"
            notes.setdefault(f"unstable already at U = {U[start]:.4g} m/s, {where}: its "
                             "flutter lies lower, outside this check", []).append(m)
        if res.found and (best is None or res.flutter_speed < best.flutter_speed):
            best = res
    notes = [f"mode{'s' if len(ms) > 1 else ''} "
             + ", ".join(f"{m + 1} ({names[m]!r})" for m in ms) + f" {text}"
             for text, ms in notes.items()]
    nU, nm = U.size, len(tracked)
    lam = np.full((nU, nm), np.nan + 1j * np.nan)
    k = np.full((nU, nm), np.nan)
    its = np.zeros((nU, nm), dtype=int)
    for j, (start, end, res) in enumerate(spans):
        lam[start:end, j], k[start:end, j] = res.eigenvalues[:, 0], res.k[:, 0]
        its[start:end, j] = res.iterations[:, 0]
    if notes:
        log.info("p–k on the table's k <= %g: %s", float(gaf.table.k[-1]), "; ".join(notes))
    if not tracked:
        msg = "unavailable: no mode can be followed on the table; " + "; ".join(notes)
    elif best is not None:
        msg = best.message + "".join(f"; {n}" for n in notes)
    else:
        msg = (f"no tracked mode's damping crosses zero for U in [{U[0]:g}, {U[-1]:g}] m/s; "
               + ("extend the speeds" if not notes else "; ".join(notes) + "; a flutter "
                  "where p–k cannot follow a mode is not checked: extend the table to larger "
                  "k"))
    found = best is not None
    return PKResult(U, tuple(tracked), tuple(names[m] for m in tracked), lam, k, its, found,
                    best.flutter_speed if found else None, best.flutter_omega if found else None,
                    best.flutter_k if found else None, best.flutter_mode if found else None, msg)


def gaf_model(cfg: RunConfig, gaf: GAFProblem, structure, progress
              ) -> tuple[ModelStage, FlutterStage]:
    """The GAF route: the RFA of ``Q(ik)``, flutter in m/s beside p–k, Σf frozen at the
    flutter speed and ΣAE(V) (the LFT of eq. 14 is exact at Vf).

    Parameters
    ----------
    cfg : RunConfig
        The configuration.
    gaf : GAFProblem
        The GAF file.
    structure : ModalStructure
        Σs with the run's sensors.
    progress : object
        The run's progress.

    Returns
    -------
    (ModelStage, FlutterStage)
        The RFA and its ΣAE(U); its flutter in m/s and the p–k solution (:func:`pk_check`:
        each mode over the speeds the table holds it at; where p–k can follow no mode its
        message says why, and the RFA's flutter stands).

    Raises
    ------
    CasflutterError
        The RFA system has no flutter crossing in the file's airspeed range.
    """
    settings = gaf_settings(cfg, gaf)
    U_lo, U_hi = gaf.U_range
    with progress.stage("rfa"):
        rfa = fit_rfa(gaf.table, settings)
        rsys = RFASystem(rfa, structure, gaf.U_ref)
    log.info("%s", rfa.summary())
    with progress.stage("flutter"):
        fl_U = find_flutter(rsys, (U_lo, U_hi), n_grid=gaf.n_grid,
                            max_refine=cfg.flutter.max_refine)
        pk = pk_check(gaf, structure)
    log.info("RFA ΣAE(U): %s; p–k: %s",
             f"Uf = {fl_U.Vf:.5g} m/s, {fl_U.omega_f:.5g} rad/s" if fl_U.Vf is not None
             else "no flutter", f"{pk.flutter_speed:.5g} m/s" if pk.found else "no flutter")
    if fl_U.Vf is None:
        raise CasflutterError(f"the RFA system of {gaf.name!r} has no flutter crossing in "
                              f"U ∈ [{U_lo:g}, {U_hi:g}] m/s: {fl_U.message}; widen "
                              "gaf.U_range")
    if settings.poly_order != 0:   # no proper Σf: the flutter route ends here
        return (ModelStage(family=rsys, rfa=rfa, rfa_system=rsys),
                FlutterStage(rfa=fl_U, pk=pk))
    Vf = rsys.speed_index(float(fl_U.Vf))
    with progress.stage("realize"):
        sigma_f = rsys.frozen_sigma_f(float(fl_U.Vf))
    with progress.stage("structure"):
        system = AeroelasticSystem.from_parts(sigma_f, structure, warn_unstable=False)
        flutter = find_flutter(system, cfg.flutter.V_range, **_flutter_kw(cfg))
    if flutter.Vf is None or abs(flutter.Vf / Vf - 1) > 1e-3:
        at = "nowhere" if flutter.Vf is None else f"at V = {flutter.Vf:.6g}"
        log.warning("ΣAE(V) of Σf frozen at Uf flutters %s in %s, not at Uf / U_ref = %.6g; "
                    "the LFT is built at Uf / U_ref, where the frozen system is exact", at,
                    cfg.flutter.V_range, Vf)
    return (ModelStage(family=system, system=system, rfa=rfa, rfa_system=rsys),
            FlutterStage(rom=flutter, rfa=fl_U, pk=pk, Vf=Vf))


# ---------------------------------------------------------------------------- family route
def family_model(cfg: RunConfig, record, progress) -> tuple[ModelStage, FlutterStage]:
    """The family route: the gridded family of a family file and every open-loop crossing
    in its range (:func:`casflutter.aeroelastic.family_flutter`).

    Parameters
    ----------
    cfg : RunConfig
        The configuration.
    record : casflutter.data.FamilyFile
        The family file as read.
    progress : object
        The run's progress.

    Returns
    -------
    (ModelStage, FlutterStage)
        The family; its crossings.
    """
    with progress.stage("family"):
        family = load_family(record)
    log.info("%s", family.describe())
    with progress.stage("flutter"):
        fl = family_flutter(family)
    log.info("open loop: %s", fl.onsets(family.speed_unit, family.time_unit))
    return ModelStage(family=family), FlutterStage(rom=fl, Vf=fl.Vf)


def controlled_family(cfg: RunConfig, model: ModelStage):
    """The design family of a model: its family, a ROM loop behind the flap servo.

    The multi-speed design on the HWL ROM takes its loop made to follow the wing over speed
    (:attr:`ModelStage.speed_following`): the frozen loop of eq. 8 stands for the wing near
    V0 only, and its flutter mode's control reversal comes 30 % late on the seed wing.

    Parameters
    ----------
    cfg : RunConfig
        The configuration (``controller.method``, ``controller.servo_omega``).
    model : ModelStage
        The model stages' result.

    Returns
    -------
    PlantFamily

    Raises
    ------
    CasflutterError
        A multi-speed design on an HWL ROM that has no speed-following loop.
    """
    servo = cfg.controller.servo_omega
    system = model.system
    if (cfg.controller.method == "multispeed" and isinstance(system, AeroelasticSystem)
            and system.convective_V0 is None and model.rfa_system is None):
        if model.speed_following is None:
            raise CasflutterError("controller.method = \"multispeed\": the ROM has no loop "
                                  "that follows the wing over speed (rom.method = \"hwl\" "
                                  "with rom.convective = false makes one)")
        system = model.speed_following.system
    if system is not None and servo > 0:
        return system.with_servo(servo)
    return model.family


def truth_family(cfg: RunConfig, truth, structure):
    """The truth's own linearisation as a family, flap behind the controller's servo
    (``None`` without a servo: the truth's linearisation has its flap behind one)."""
    servo = cfg.controller.servo_omega
    return TruthLoop(truth, servo, sensors=structure) if servo > 0 else None
