"""The study run: the paper's stages, left to right, on a truth problem (§IV, Table I).

Always:

1. ``data`` — chirp records of the truth at ``V0`` (:func:`casflutter.truth.truth_records`);
2. ``rom`` — the ROM: the HWL model of eq. 1-4 (:func:`casflutter.ident.identify`) or the
   linear common-denominator model (:func:`casflutter.ident.identify_common_denominator`);
3. ``realize`` — Σf by ERA and Tustin (eq. 5, :func:`casflutter.realize.realize`);
4. ``structure`` — Σs with the configured sensors (eq. 6-7) and ΣAE (eq. 8-9);
5. ``flutter`` — the Hopf points of ΣAE and of the truth (:func:`casflutter.aeroelastic.find_flutter`).

With ``rom.v0_iterations > 1`` stages 1-5 repeat at the ROM's own flutter speed until the
identification speed and the flutter speed agree.  Then the optional ``stages``:

- ``frozen`` — the flutter speed of the truth with its aerodynamics frozen at ``V0``
  (:func:`casflutter.truth.frozen_aero_truth`): the V²-scaling part of the ROM's error;
- ``parametric`` — ROMs identified at several speeds, interpolated in V, and their flutter;
- ``lco`` — the nonlinear ROM in the loop and the truth above their Hopf points (Fig. 9);
- ``controller`` — the LFT at Vf (eq. 10-15, ``lft``), the fixed-order synthesis (§III.C,
  ``controller``) and the independent verification (``verify``);
- ``closed_loop`` — the ROM and the truth above flutter, open and closed loop, and the
  truth's linear closed loop over speed;
- ``suppression`` — the truth with the controller gain ramped 0 -> 1 and released (Fig. 11).

A wing file without a simulator (``[problem] name`` a ``kind = "wing"`` file: modal data,
sensors and records, :class:`casflutter.truth.WingProblem`) runs the same stages on its records
at its own ``V0``; the stages that need the truth (its flutter search, ``frozen``,
``parametric``, the truth's LCO, ``closed_loop``, ``suppression``) are skipped with a logged
note and listed in ``RunResult.skipped``.  So is ``lco`` when the configured ROM is linear
(the common-denominator ROM, or HWL orders with p = q = 1): a linear model has no limit cycle.

A wing file with frequency-domain aerodynamics (``kind = "gaf"``: modal data and ``Q(ik)``,
:class:`casflutter.truth.GAFProblem`) replaces stages 1-5 by the rational-function
approximation (``rfa``, :func:`casflutter.realize.fit_rfa`), the flutter search of ΣAE(U) in
the airspeed with the p–k solution on the same table beside it (``flutter``), and Σf of the
RFA frozen at the flutter speed with ΣAE(V) (``realize``, ``structure``); the ``controller``
stage then runs on that ΣAE (the LFT of eq. 14 is exact at Vf).  The RFA is linear: ``lco`` is
skipped with the truth-only stages.

Two configurations ship with the package: ``problems/seed_wing/run.toml`` (the paper's
study, ``casflutter run``) and ``problems/typical_section/flutter_check.toml`` (an order-2
controller designed on the ROM identified at its own flutter speed and checked on the
truth); ``problems/NAME/flutter.toml`` are the ROM routes of ``casflutter flutter``.
"""

from __future__ import annotations

import logging
import sys
import time
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import casadi as ca
import control
import numpy as np
from scipy.optimize import brentq

from .._linalg import spectral_abscissa
from .._outputs import provenance, utc_now
from .._settings import settings_as
from ..aeroelastic import (AeroelasticSystem, FlutterResult, ParametricSystem, RFASystem,
                           TruthLoop, build_lft, pk_flutter,
                           find_flutter, simulate_loop)
from ..data import envelope_growth_rate
from ..design import SynthesisOptions, design_flutter_controller, design_interval_controller
from ..errors import CasflutterError, ConfigError, ConvergenceError
from ..ident import (IdentificationResult, IdentificationSettings, fit_report, identify,
                     identify_common_denominator)
from ..lco import (LCOSettings, lco_branch, rom_lco_branch, rom_loop_map,
                   speed_convention)
from ..realize import ParametricROM, RFASettings, fit_rfa, realize, speed_nodes
from ..truth import (AeroelasticTruth, GAFProblem, RecordSettings, WingProblem,
                     closed_loop_truth, frozen_aero_truth, suppression_run,
                     truth_lco, truth_loop_matrix, truth_loop_sweep, truth_records)
from ..verify import (NotHurwitzError, StabilityInterval, speed_family_interval, speed_sweep,
                      verify_controller)
from ._config import RunConfig, load_config
from ._exports import check_output_folder, log_flags, write_outputs
from ._result import (ClosedLoopChecks, LcoResult, ParametricResult, RunResult,
                      SimulationCheck, skipped_notes)

__all__ = ["run"]

log = logging.getLogger("casflutter.pipeline")

#: stages (and parts of stages) that need a truth simulator, skipped on a wing file
_TRUTH_ONLY = {"flutter_truth": "the truth's flutter search", "frozen": "stage 'frozen'",
               "parametric": "stage 'parametric' (records at several speeds)",
               "truth_lco": "the truth's LCO of stage 'lco'",
               "closed_loop": "stage 'closed_loop'", "suppression": "stage 'suppression'"}


class _Progress:
    """Stage timings, and one line per stage on stderr unless quiet (the stage's time at
    DEBUG)."""

    def __init__(self, quiet: bool, names: list[str]):
        self.quiet = quiet
        self.names = names
        self.timings: dict[str, float] = {}
        self.t0 = time.perf_counter()

    @contextmanager
    def stage(self, name: str):
        if not self.quiet and name not in self.timings:   # once, also when rom.v0_iterations
            k = self.names.index(name) + 1                # repeats the stage
            print(f"[{k}/{len(self.names)}] {name} ...", file=sys.stderr, flush=True)
        t = time.perf_counter()
        yield
        dt = time.perf_counter() - t
        self.timings[name] = self.timings.get(name, 0.0) + dt
        log.debug("stage %s: %.2f s", name, dt)

    def note(self, text: str):
        if not self.quiet:
            print(f"      {text}", file=sys.stderr, flush=True)


def _stage_names(cfg: RunConfig, skipped=()) -> list[str]:
    names = ["data", "rom", "realize", "structure", "flutter"]
    for s in cfg.stages:
        if s not in skipped:
            names += ["lft", "controller", "verify"] if s == "controller" else [s]
    return names


def _same_sensors(cfg: RunConfig, wing) -> None:
    """The run's ``[sensors] kind`` must be the wing file's (its rows are read that way)."""
    if cfg.sensors.kind != wing.structure.sensor:
        raise ConfigError(f"sensors.kind = {cfg.sensors.kind!r} of the run configuration "
                          f"differs from sensors.kind = {wing.structure.sensor!r} of the wing "
                          f"file {wing.path}; set [sensors] kind = "
                          f"\"{wing.structure.sensor}\" in the run configuration")


def _gaf_setup(cfg: RunConfig, gaf: GAFProblem) -> tuple[RFASettings, dict]:
    """The RFA settings of a GAF wing file and the stages it skips; checked before any work."""
    try:
        settings = RFASettings(**gaf.rfa)
    except ConfigError as exc:
        raise ConfigError(f"[gaf] of the wing file {gaf.path}: {exc}") from None
    if "controller" in cfg.stages and settings.poly_order != 0:
        raise ConfigError(f"stages: 'controller' on the GAF problem {gaf.name!r} needs the "
                          "frozen Σf of eq. 5, which is proper only without p, p^2 terms; set "
                          f"gaf.poly_order = 0 in {gaf.path} (now {settings.poly_order}) or "
                          "drop the controller stage")
    _same_sensors(cfg, gaf)
    why = f"needs a truth simulator; the wing file {gaf.name!r} has Q(ik) only"
    skipped = {k: f"{v}: {why}" for k, v in _TRUTH_ONLY.items()
               if k in {"flutter_truth"} | set(cfg.stages)}
    if "lco" in cfg.stages:
        skipped["lco"] = ("stage 'lco': the RFA of Q(ik) is linear (no LCO); it needs "
                          "records of a nonlinear model or a truth simulator")
    _log_skipped(skipped)
    return settings, skipped


def _pk_modes(gaf: GAFProblem, U_lo: float) -> tuple[int, ...]:
    """The modes p–k can follow from ``U_lo``: in-vacuo reduced frequency ``omega b / U_lo``
    within 0.8 of the table's largest ``k`` (the iteration must stay inside the table)."""
    k_vac = gaf.structure.omega * gaf.table.b / U_lo
    modes = tuple(int(i) for i in np.flatnonzero(k_vac <= 0.8 * gaf.table.k[-1]))
    return modes or (0,)


def _run_gaf(cfg: RunConfig, gaf: GAFProblem, settings: RFASettings, structure, prog,
             out: dict) -> None:
    """Stages of a GAF wing file (module docstring): RFA, flutter in m/s with p–k, frozen Σf
    and ΣAE(V), and the controller stage on it."""
    U_lo, U_hi = gaf.U_range
    with prog.stage("rfa"):
        rfa = fit_rfa(gaf.table, settings)
        rsys = RFASystem(rfa, structure, gaf.U_ref)
    prog.note(f"{rfa.summary()}")
    with prog.stage("flutter"):
        fl_U = find_flutter(rsys, (U_lo, U_hi), n_grid=gaf.n_grid,
                            max_refine=cfg.flutter.max_refine)
        pk = pk_flutter(gaf.table, structure, np.linspace(U_lo, U_hi, 29),
                        modes=_pk_modes(gaf, U_lo))
    prog.note("RFA ΣAE(U): " + (f"Uf = {fl_U.Vf:.5g} m/s, {fl_U.omega_f:.5g} rad/s"
                                 if fl_U.Vf is not None else "no flutter") + "; p–k: "
              + (f"{pk.flutter_speed:.5g} m/s" if pk.found else "no flutter"))
    if fl_U.Vf is None:
        raise CasflutterError(f"the RFA system of {gaf.name!r} has no flutter crossing in "
                              f"U ∈ [{U_lo:g}, {U_hi:g}] m/s: {fl_U.message}; widen "
                              "gaf.U_range")
    out.update(rfa=rfa, rfa_system=rsys, rfa_flutter=fl_U, pk=pk)
    if settings.poly_order != 0:   # no proper Σf: the flutter route ends here
        out.update(system=None, flutter=None)
        return
    Vf = float(fl_U.Vf) / gaf.U_ref
    with prog.stage("realize"):
        sigma_f = rsys.frozen_sigma_f(float(fl_U.Vf))
    with prog.stage("structure"):
        system = AeroelasticSystem.from_parts(sigma_f, structure, warn_unstable=False)
        flutter = find_flutter(system, cfg.flutter.V_range, n_grid=cfg.flutter.n_grid,
                               max_refine=cfg.flutter.max_refine)
    if flutter.Vf is None or abs(flutter.Vf / Vf - 1) > 1e-3:
        at = "nowhere" if flutter.Vf is None else f"at V = {flutter.Vf:.6g}"
        prog.note(f"warning: ΣAE(V) of Σf frozen at Uf flutters {at} in "
                  f"{cfg.flutter.V_range}, not at Uf / U_ref = {Vf:.6g}; the LFT is built at "
                  "Uf / U_ref, where the frozen system is exact")
    out.update(system=system, flutter=flutter, gaf_Vf=Vf)


def _wing_setup(cfg: RunConfig, wing: WingProblem) -> tuple[RunConfig, dict]:
    """A wing file's configuration (``data.V0`` the records' speed) and the truth-only stages
    it skips, ``{stage: reason}``; checked before any work."""
    if cfg.rom.v0_iterations > 1:
        raise ConfigError(f"rom.v0_iterations = {cfg.rom.v0_iterations}: the records of the "
                          f"wing file {wing.path} are taken at one speed (V0 = {wing.V0:g}); "
                          "set rom.v0_iterations = 1")
    _same_sensors(cfg, wing)
    why = f"needs a truth simulator; the wing file {wing.name!r} has records only"
    lco = "lco" in cfg.stages and not _linear_rom_skips(cfg)     # (else no LCO stage at all)
    wanted = {"flutter_truth"} | set(cfg.stages) | ({"truth_lco"} if lco else set())
    skipped = {k: f"{v}: {why}" for k, v in _TRUTH_ONLY.items() if k in wanted}
    _log_skipped(skipped)
    return replace(cfg, data=replace(cfg.data, V0=float(wing.V0))), skipped


def _log_skipped(skipped: dict) -> None:
    """One log line per reason: ``skipped A, B (reason)``."""
    for line in skipped_notes(skipped):
        log.info(line)


def _linear_rom_skips(cfg: RunConfig) -> dict:
    """``{"lco": reason}`` when the configured ROM is linear (a linear model has no limit
    cycle: above flutter it only grows), else ``{}``; decided from the configuration."""
    r = cfg.rom
    if "lco" not in cfg.stages:
        return {}
    if r.method == "common_denominator":
        what = 'rom.method = "common_denominator" is linear'
    elif tuple(r.orders)[4:] == (1, 1):
        what = f"rom.orders = {list(r.orders)} has p = q = 1: the HWL model is linear"
    else:
        return {}
    return {"lco": f"stage 'lco': {what} and has no limit cycle (above flutter it only "
                   "grows); identify a nonlinear ROM (rom.method = \"hwl\" with p or q >= 2, "
                   "Table I: [3, 1, 1, 1, 2, 2]) or drop 'lco' from stages"}


def _mode(res: FlutterResult) -> int:
    """The flutter mode (the mode deflected in the simulations), else mode 0."""
    m = res.flutter_mode
    return int(m) if m is not None and m >= 0 else 0


def _identify(data, cfg: RunConfig):
    """The ROM of the records: ``(identification result, model)``."""
    r = cfg.rom
    if r.method == "common_denominator":
        ident = identify_common_denominator(data, r.na, r.nb)
    else:
        settings = replace(settings_as(r, IdentificationSettings),
                           ipopt_options={**cfg.solver.ipopt, **r.ipopt_options})
        ident = identify(data, tuple(r.orders), settings=settings)
    return ident, ident.model


def run(config: RunConfig | str | Path | None = None, *, out_dir=None, seed: int | None = None,
        quiet: bool = False, write: bool = True, overwrite: bool = False) -> RunResult:
    """Run the stages of a configuration (module docstring) and write its outputs.

    Parameters
    ----------
    config : RunConfig, path or None
        Configuration (default: the seed wing's ``problems/seed_wing/run.toml``).
    out_dir : path, optional
        Output folder (default ``casflutter-run``), checked before any work and written
        atomically with its ``manifest.json`` (:mod:`casflutter.pipeline._exports`).
    seed : int, optional
        Overrides ``config.seed``.
    quiet : bool
        No progress on stderr.
    write : bool
        Write files (summary, figures, report, ROM, controller and plant, manifest).
    overwrite : bool
        Replace an existing non-empty output folder (as a whole); without it such a folder
        is refused before any work.

    Returns
    -------
    RunResult

    Raises
    ------
    ConfigError
        An invalid configuration (before any work).
    OutputError
        An output folder that cannot be written, or exists and is not empty without
        ``overwrite`` (before any work).
    CasflutterError
        No ROM flutter in ``flutter.V_range`` when a later stage needs it (or no truth
        flutter for the closed-loop stage), or a simulation that blew up.
    casflutter.errors.SynthesisError
        No synthesis start stabilised the design plants.

    See Also
    --------
    load_config : the configuration it runs.

    Examples
    --------
    The typical section's flutter route (records, linear ROM, Σf, flutter) without writing files:

    >>> import casflutter as cf
    >>> from casflutter.pipeline import config_path
    >>> config = cf.load_config(config_path("typical_section", "flutter"), updates={"stages": []})
    >>> result = cf.run(config, write=False, quiet=True)
    >>> round(result.flutter.Vf, 4)
    2.2589

    The paper's study on the seed wing (about a minute): ``cf.run(cf.load_config())``.
    """
    cfg = config if isinstance(config, RunConfig) else load_config(config)
    if seed is not None:
        cfg = replace(cfg, seed=int(seed))
    target = check_output_folder(out_dir, overwrite=overwrite) if write else None
    info = {**provenance(seed=cfg.seed), "started": utc_now()}
    problem = cfg.problem.load()
    truth = problem if isinstance(problem, AeroelasticTruth) else None
    skipped: dict = {}
    if isinstance(problem, WingProblem):
        cfg, skipped = _wing_setup(cfg, problem)
    elif isinstance(problem, GAFProblem):
        rfa_settings, skipped = _gaf_setup(cfg, problem)
    elif truth is None:
        raise ConfigError(f"problem.name = {cfg.problem.name!r} is a {type(problem).__name__}, "
                          "which casflutter.pipeline.run does not take; give a truth problem "
                          "or a wing file (kind = \"wing\")")
    if not isinstance(problem, GAFProblem) and (linear := _linear_rom_skips(cfg)):
        _log_skipped(linear)
        skipped = {**skipped, **linear}
    names = _stage_names(cfg, skipped)
    if isinstance(problem, GAFProblem):
        names = ["rfa", "flutter", "realize", "structure"] + names[5:]
    prog = _Progress(quiet, names)
    structure = problem.modal_structure().with_sensors(cfg.sensors.rows or None,
                                                       cfg.sensors.kind)
    rows = cfg.sensors.rows or None
    records = settings_as(cfg.data, RecordSettings)
    vr = cfg.flutter.V_range
    flutter_kw = dict(n_grid=cfg.flutter.n_grid, max_refine=cfg.flutter.max_refine)
    needs_vf = cfg.rom.v0_iterations > 1 or bool(set(cfg.stages) & {"lco", "controller"})
    out: dict = {"config": cfg, "truth": truth, "problem": problem, "skipped": skipped}
    if isinstance(problem, GAFProblem):
        if cfg.rom.convective:
            raise ConfigError("rom.convective: a GAF problem's rational-function "
                              "aerodynamics already scale with the speed; leave it false")
        _run_gaf(cfg, problem, rfa_settings, structure, prog, out)
        Vf = out.pop("gaf_Vf", None)
        out.update(data=None, identification=None, identification_history=(), fit=None,
                   realization=None, flutter_truth=None)
        if "controller" in cfg.stages and "controller" not in skipped:
            _controller_stages(cfg, out["system"], Vf, prog, out)
        return _finish(out, prog, target, write, overwrite, info)

    # 1-5: records, ROM, Σf, ΣAE, flutter; repeated at the ROM's own flutter speed
    V0, history = cfg.data.V0, []
    for it in range(cfg.rom.v0_iterations):
        with prog.stage("data"):
            data = (truth_records(truth, records, V0=V0) if truth is not None
                    else problem.records)
        with prog.stage("rom"):
            ident, model = _identify(data, cfg)
        with prog.stage("realize"):
            real = realize(model, cfg.rom.nf)
        with prog.stage("structure"):
            system = AeroelasticSystem.from_parts(
                real.sigma_f, structure, warn_unstable=False,
                convective_V0=float(V0) if cfg.rom.convective else None)
            if not system.rom_stable:
                prog.note("warning: Σf is unstable on its own (ΣAE unstable at V = 0)")
        with prog.stage("flutter"):
            flutter = find_flutter(system, vr, **flutter_kw)
            Vf = flutter.Vf
            last = (it == cfg.rom.v0_iterations - 1 or Vf is None
                    or abs(Vf - V0) <= cfg.rom.v0_rtol * Vf)
            if last:
                flutter_truth = (find_flutter(truth, vr, **flutter_kw) if truth is not None
                                 else None)
            if Vf is None and needs_vf:
                raise CasflutterError(f"the ROM identified at V0 = {V0:.4g} has no flutter "
                                      f"crossing in V ∈ {vr}: {flutter.message}; widen "
                                      "flutter.V_range")
            history.append((float(V0), None if Vf is None else float(Vf)))
        if last:
            break
        V0 = float(Vf)
    fit = (ident.fit if isinstance(ident, IdentificationResult)
           else fit_report(model, data, "simulation"))
    prog.note(f"{model}; fit error % " + ", ".join(f"{e:.4g}" for e in fit.error_percent))
    rom_vf = f"ROM Vf = {Vf:.5g}" if Vf is not None else "ROM: no flutter in flutter.V_range"
    if flutter_truth is not None:   # no truth on a wing file: nothing to say of it
        rom_vf += (f"; truth Vf = {flutter_truth.Vf:.5g}" if flutter_truth.flutter is not None
                   else "; truth: no flutter in flutter.V_range")
    prog.note(rom_vf)
    out.update(data=data, identification=ident, identification_history=tuple(history),
               fit=fit, realization=real, system=system, flutter=flutter,
               flutter_truth=flutter_truth)
    crit = _mode(flutter)

    if "frozen" in cfg.stages and "frozen" not in skipped:
        with prog.stage("frozen"):
            out["flutter_frozen"] = find_flutter(frozen_aero_truth(truth, V0), vr, **flutter_kw)
    if "parametric" in cfg.stages and "parametric" not in skipped:
        with prog.stage("parametric"):
            speeds = speed_nodes(vr, cfg.parametric.n_speeds)
            prom = ParametricROM(speeds, tuple(
                identify_common_denominator(truth_records(truth, records, V0=float(v)),
                                            cfg.rom.na, cfg.rom.nb) for v in speeds))
            psys = ParametricSystem(prom, structure)
            out["parametric"] = ParametricResult(prom, psys, find_flutter(
                psys, vr, n_grid=cfg.flutter.n_grid, max_refine=cfg.parametric.max_refine))
    if "lco" in cfg.stages and "lco" not in skipped:
        with prog.stage("lco"):
            out["lco"] = _lco(cfg, truth, model, structure, flutter, flutter_truth, prog)
    if "controller" in cfg.stages:
        _controller_stages(cfg, system, Vf, prog, out, truth=truth, structure=structure)
    if "closed_loop" in cfg.stages and "closed_loop" not in skipped:
        with prog.stage("closed_loop"):
            out["closed_loop"] = _closed_loop(cfg, truth, model, system, out["lft"],
                                              out["controller"], flutter, flutter_truth, rows)
    if "suppression" in cfg.stages and "suppression" not in skipped:
        with prog.stage("suppression"):
            # the truth flutters at its own speed: suppress its LCO there (paper Fig. 11 was
            # measured on the real wing at an LCO condition)
            V_ref = flutter_truth.Vf if flutter_truth.flutter is not None else Vf
            V_run = float(V_ref) * cfg.suppression.speed_factor
            lco = out.get("lco")
            if lco is not None and abs(lco.truth.V - V_run) <= 1e-9 * V_run:
                tr = lco.truth  # the LCO stage's truth run at this speed: its converged LCO
            else:  # the LCO stage did not run at this speed: let the truth's LCO converge
                tr = truth_lco(truth, V_run, cfg.lco.duration, crit, cfg.lco.initial_deflection,
                               dt=model.dt, sensor_rows=rows, sensor=cfg.sensors.kind)
            x0 = tr.final_state if tr.kind == "lco" else None
            if x0 is None:
                prog.note(f"the truth has no LCO at V = {V_run:.4f} ({tr.kind}): the "
                          "suppression run starts from a deflected mode")
            out["suppression"] = suppression_run(
                truth, out["controller"], float(V_ref), cfg.suppression, dt=model.dt,
                mode=crit, deflection=cfg.lco.initial_deflection, sensor_rows=rows,
                sensor=cfg.sensors.kind, x0=x0)
    return _finish(out, prog, target, write, overwrite, info)


def _controller_stages(cfg: RunConfig, system, Vf: float, prog, out: dict, truth=None,
                       structure=None) -> None:
    """The LFT at Vf (eq. 10-15), the fixed-order synthesis (§III.C) and the verification,
    on the ROM loop and, with a truth, on the truth's own linearisation."""
    with prog.stage("lft"):
        lft = build_lft(system, Vf)
    with prog.stage("controller"):
        c = cfg.controller
        options = replace(settings_as(c, SynthesisOptions),
                          ipopt={**cfg.solver.ipopt, **c.ipopt})
        if c.method == "interval":
            # stability of the scaled ROM loop (flap behind the servo) over the whole
            # interval first, then the order; no synthesis, γ is the verification's
            design = design_interval_controller(
                system.with_servo(c.flap_rate_bandwidth), c.interval, c.order,
                orders=c.reduction_orders, decay=c.interval_decay, n_speeds=c.n_speeds)
            syn, K = None, design.controller
            out["interval_design"] = design
            if not design.met:
                held = design.full_order.met
                prog.note(f"no order-{c.order} controller found that holds the interval "
                          f"{list(c.interval)}; kept the order-{K.nstates} controller "
                          + ("that holds it" if held else "of the full-order continuation, "
                             f"which reached {list(design.full_order.reached)}"))
        else:
            # γ of the LFT at Vf (eq. 14-16), each design plant with its own loop shift, and
            # ΣAE(V) kept stable over controller.interval; K acts on the physical sensors
            design = design_flutter_controller(
                system, Vf, c.order, speeds=tuple(c.speeds), interval=tuple(c.interval),
                n_speeds=c.n_speeds, decay=c.interval_decay, steps=c.steps, starts=c.starts,
                seed=cfg.seed, options=options, flap_rate_weight=c.flap_rate_weight,
                flap_rate_bandwidth=c.flap_rate_bandwidth)
            syn, K = design.synthesis, design.controller
    with prog.stage("verify"):
        ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta)
        if cfg.verify.sweep:
            lo, hi = cfg.verify.sweep
            out["rom_sweep"] = speed_sweep(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf,
                                           n_delta=lft.n_delta,
                                           V=np.linspace(lo * Vf, hi * Vf, cfg.verify.n_sweep))
        if system.convective_V0 is not None:
            out["rom_interval"] = _rom_interval(system, K, cfg, prog)
        if truth is not None:
            out["truth_interval"] = _truth_interval(truth, structure, K, cfg, prog)
    out.update(lft=lft, synthesis=syn, controller=K, verification=ver)


def _rom_interval(system, K, cfg: RunConfig, prog) -> StabilityInterval | None:
    """The exact stable speed interval of a ROM loop whose time scales with V
    (``rom.convective``) closed by ``K``, the flap behind the truth's servo: the LFT frozen
    at Vf is exact only at Vf, this loop at every speed.  See :func:`_family_interval`."""
    return _family_interval(system.with_servo(cfg.controller.flap_rate_bandwidth), K, cfg,
                            prog, "the scaled ROM loop")


def _truth_interval(truth, structure, K, cfg: RunConfig, prog) -> StabilityInterval | None:
    """The exact stable speed interval of the truth's own linearisation closed by ``K``, the
    flap behind the servo: the interval on the wing the ROM stands in for.  See
    :func:`_family_interval`."""
    return _family_interval(TruthLoop(truth, cfg.controller.flap_rate_bandwidth,
                                      sensors=structure), K, cfg, prog,
                            "the truth's linear loop")


def _family_interval(family, K, cfg: RunConfig, prog, what: str) -> StabilityInterval | None:
    """The verification layer's exact stable interval of a loop family closed by ``K``
    (servo of ``controller.flap_rate_bandwidth``), grown from ``data.V0``; ``None`` (and a
    note) when K does not hold the loop at V0."""
    try:
        return speed_family_interval(lambda V: family.loop(V).flap_to_sensors(), K,
                                     cfg.data.V0)
    except NotHurwitzError:
        prog.note(f"the controller does not stabilise {what} at V0 = {cfg.data.V0:.4g}")
        return None


def _finish(out: dict, prog, target: Path | None, write: bool, overwrite: bool,
            info: dict) -> RunResult:
    """The result with its timings and provenance, and its files (written atomically into
    ``target``) when ``write``."""
    timings = dict(prog.timings)
    timings["total"] = time.perf_counter() - prog.t0
    result = RunResult(**out, timings=timings, provenance=info)
    log_flags(result)
    if write:
        result = replace(result, out_dir=target,
                         files=write_outputs(target, result, overwrite=overwrite))
    return result


def _lco(cfg: RunConfig, truth, model, structure, flutter, flutter_truth, prog) -> LcoResult:
    """Paper Fig. 9: the ROM's and the truth's LCO a little above their own Hopf points.

    The ROM's own flutter point is that of the loop it is simulated in: the sampled-data
    loop of the nonlinear ROM with Σs (a Neimark--Sacker point of the map of
    :func:`casflutter.lco.rom_loop_map`).  Its speed differs from the Hopf speed of the
    continuous ΣAE by the sampling (the zero-order hold and the one-sample coupling), by
    several per cent for the seed wing, so a speed a few per cent above the continuous Hopf
    point can lie below the loop's.  The ROM is simulated ``speed_factor`` times above the
    loop's point and the truth the same factor above its own Hopf point (the ROM's speed can
    be far above the truth's flutter speed, where the truth diverges); each simulation is
    continued while it still grows.  The Hopf speed of the exact-order continuous ΣAE is
    kept for the record.
    """
    vr, lc = cfg.flutter.V_range, cfg.lco
    exact = realize(model, "auto")
    sys_exact = AeroelasticSystem.from_parts(exact.sigma_f, structure, warn_unstable=False)
    fl_exact = find_flutter(sys_exact, vr, n_grid=cfg.flutter.n_grid,
                            max_refine=cfg.flutter.max_refine)
    V_hopf = float(fl_exact.Vf) if fl_exact.flutter is not None else float(flutter.Vf)
    V_loop = _loop_hopf(model, structure, vr, cfg.flutter.n_grid)
    V_lco = (V_loop if V_loop is not None else V_hopf) * lc.speed_factor
    crit = _mode(flutter)
    n = int(round(lc.duration / model.dt))
    xs0 = structure.displaced_state(crit, lc.initial_deflection)
    for _ in range(_MAX_EXTENSIONS + 1):
        sim = simulate_loop(model, structure, V_lco, n, xs0=xs0)
        if sim.stopped_early or sim.modes.kind != "divergence":
            break
        # still growing: continue from where the structure ended (the ROM's past outputs
        # restart at zero, a small kick that the converging LCO forgets)
        xs0 = sim.xs[-1]
    tr = None
    if truth is not None:
        V_truth = (float(flutter_truth.Vf) * lc.speed_factor
                   if flutter_truth.flutter is not None else V_lco)
        tr = truth_lco(truth, V_truth, lc.duration, crit, lc.initial_deflection, dt=model.dt,
                       sensor_rows=structure.Hs, sensor=structure.sensor,
                       max_extensions=_MAX_EXTENSIONS)
    loop = "" if V_loop is None else f"loop flutter {V_loop:.5g}, "
    prog.note(f"ROM LCO at V = {V_lco:.5g} ({loop}continuous exact-order Hopf {V_hopf:.5g}): "
              f"{sim.sensors.kind}, {sim.sensors.frequency_hz:.4g} Hz")
    branches = _branches(cfg, truth, model, structure, prog) if lc.branch_points else {}
    return LcoResult(rom=sim, truth=tr, V=V_lco, V_hopf_exact_order=V_hopf,
                     flutter_exact_order=fl_exact, V_hopf_loop=V_loop, **branches)


def _branches(cfg: RunConfig, truth, model, structure, prog) -> dict:
    """The LCO branches of the ROM loop and of the truth (``lco.branch_points`` points
    each; no truth branch on a wing file), or the reason a branch could not be started."""
    settings = LCOSettings(max_points=cfg.lco.branch_points, sensor_kind=structure.sensor)
    scale, unit = speed_convention(truth) if truth is not None else (1.0, "speed index")
    ms = truth.modal_structure() if truth is not None else structure
    out = {}
    computations = [] if truth is None else [
        ("truth_branch", lambda: lco_branch(truth, cfg.flutter.V_range, settings,
                                            problem="truth"))]
    for key, compute in (
            *computations,
            ("rom_branch", lambda: rom_lco_branch(
                model, structure, cfg.flutter.V_range, settings, mode_names=ms.mode_names,
                sensor_names=structure.sensor_names, problem="ROM loop", speed_scale=scale,
                speed_unit=unit, time_unit=ms.time_unit))):
        try:
            out[key] = compute()
        except (ConfigError, ConvergenceError) as exc:
            prog.note(f"no {key.replace('_', ' ')}: {exc}")
    if "truth_branch" in out and "rom_branch" in out:
        # the ROM loop's outputs are the truth's quantities: give them the truth's units
        units = dict(zip(out["truth_branch"].outputs, out["truth_branch"].output_units))
        rb = out["rom_branch"]
        out["rom_branch"] = replace(rb, output_units=tuple(
            units.get(n, u) for n, u in zip(rb.outputs, rb.output_units)))
    return out


#: most continuations of an LCO simulation that still grows
_MAX_EXTENSIONS = 5


def _loop_hopf(model, structure, vrange, n_grid: int) -> float | None:
    """Speed of the first Neimark--Sacker point of the sampled-data ROM loop in ``vrange``
    (the spectral radius of its linearisation at rest crossing one), or None."""
    F = rom_loop_map(model, structure)
    s, V = ca.SX.sym("s", int(F.size1_in(0))), ca.SX.sym("V")
    jac = ca.Function("loop_jacobian", [s, V], [ca.jacobian(F(s, V), s)])
    zero = np.zeros(int(F.size1_in(0)))

    def radius(v: float) -> float:
        lam = np.linalg.eigvals(np.asarray(jac(zero, v), float))
        osc = lam[np.abs(lam.imag) > 1e-9]
        return float(np.max(np.abs(osc))) - 1.0 if osc.size else -1.0

    grid = np.linspace(max(vrange[0], 1e-3), vrange[1], n_grid)
    r = np.array([radius(v) for v in grid])
    if r[0] >= 0:
        return None
    up = np.flatnonzero((r[:-1] < 0) & (r[1:] >= 0))
    if up.size == 0:
        return None
    k = int(up[0])
    return float(brentq(radius, grid[k], grid[k + 1], xtol=1e-10))


def _rate(timepts, X) -> float:
    """Largest envelope growth rate over the columns, second half of the record."""
    h = timepts.size // 2
    return float(max(envelope_growth_rate(timepts[h:], X[h:, j]) for j in range(X.shape[1])))


def _closed_loop(cfg: RunConfig, truth, model, system, lft, K, flutter, flutter_truth,
                 rows) -> ClosedLoopChecks:
    """The loops above flutter, open and closed, and the truth's closed loop over speed."""
    s = cfg.closed_loop
    if flutter_truth.Vf is None:
        raise CasflutterError(f"the truth has no flutter in {cfg.flutter.V_range}: "
                              f"{flutter_truth.message}")
    Vf, Vt = float(flutter.Vf), float(flutter_truth.Vf)
    act = dict(actuator_omega=s.actuator_omega, actuator_zeta=s.actuator_zeta)
    sweep = truth_loop_sweep(truth, K, Vt, Vt * np.linspace(*s.sweep_range, s.n_sweep),
                             sensor_rows=rows, **act)
    # the discrete ROM in the loop, and the linear loops of the same ROM at V: the LFT
    # closed at ΔV (eq. 15), open and with K
    V = s.speed_factor * Vf
    structure = system.structure
    n = int(round(s.duration / model.dt))
    xs0 = structure.displaced_state(_mode(flutter), s.deflection)
    ol = simulate_loop(model, structure, V, n, xs0=xs0)
    cl = simulate_loop(model, structure, V, n, xs0=xs0, controller=K)
    G = lft.close(V ** 2 - lft.Vf ** 2)
    Gv = control.ss(G.A, np.asarray(G.B)[:, -1:], G.C, np.asarray(G.D)[:, -1:])
    A_cl = np.asarray(control.feedback(Gv, K, sign=1).A)
    rom_sim = SimulationCheck("rom", float(V), ol.timepts, ol.zm, cl.zm,
                              _rate(ol.timepts, ol.zm), _rate(cl.timepts, cl.zm),
                              spectral_abscissa(G.A), spectral_abscissa(A_cl))
    # the sampled-data truth with the flap actuator
    V = s.speed_factor * Vt
    t = np.arange(0.0, s.duration, s.dt)
    x0 = truth.displaced_state(_mode(flutter_truth), s.deflection)
    kw = dict(act, sensor="displacement", sensor_rows=rows)
    tol = closed_loop_truth(truth, K, V, t, x0, lambda tt: 0.0, **kw).zm
    tcl = closed_loop_truth(truth, K, V, t, x0, lambda tt: 1.0, **kw).zm
    if not (np.all(np.isfinite(tol)) and np.all(np.isfinite(tcl))):
        raise CasflutterError(f"the truth simulation at V = {V:.4f} blew up; shorten "
                              "closed_loop.duration or lower closed_loop.speed_factor")
    A_cl = truth_loop_matrix(truth, K, V, sensor_rows=rows, **act)
    truth_sim = SimulationCheck("truth", float(V), t, tol, tcl, _rate(t, tol), _rate(t, tcl),
                                spectral_abscissa(truth.state_matrix(V)),
                                spectral_abscissa(A_cl))
    return ClosedLoopChecks(truth_sweep=sweep, rom_simulation=rom_sim,
                            truth_simulation=truth_sim)
