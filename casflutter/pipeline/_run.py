"""The study run: the paper's stages, left to right, on any problem (§IV, Table I).

The model stages depend on the problem and are chosen in one place
(:mod:`casflutter.pipeline._model`, ``ROUTES``): on a truth (or a wing file with records)

1. ``data`` — chirp records of the truth at ``V0`` (:func:`casflutter.truth.truth_records`);
2. ``rom`` — the ROM: the HWL model of eq. 1-4 (:func:`casflutter.ident.identify`) or the
   linear common-denominator model (:func:`casflutter.ident.identify_common_denominator`);
3. ``realize`` — Σf by ERA and Tustin (eq. 5, :func:`casflutter.realize.realize`);
4. ``structure`` — Σs with the configured sensors (eq. 6-7) and ΣAE (eq. 8-9);
5. ``flutter`` — the Hopf points of ΣAE and of the truth (:func:`casflutter.aeroelastic.find_flutter`);

on a GAF file the rational-function approximation of ``Q(ik)`` with p–k beside it, and on a
plant family file (``kind = "plant_family"``) the gridded family and its crossings.  Then the
optional ``stages``, each run only where the problem offers what it needs (a skipped stage is
logged once and listed in ``RunResult.skipped``; ``casflutter run`` refuses, before any
work, a stage list of the configuration's own that names one the problem cannot run,
:func:`check_requested_stages`):

- ``frozen`` — the flutter speed of the truth with its aerodynamics frozen at ``V0``
  (:func:`casflutter.truth.frozen_aero_truth`): the V²-scaling part of the ROM's error;
- ``parametric`` — ROMs identified at several speeds, interpolated in V, and their flutter;
- ``lco`` — the nonlinear ROM in the loop and the truth above their Hopf points (Fig. 9);
  skipped on a linear ROM, which has no limit cycle;
- ``controller`` — one fixed-order controller over a speed interval (§III.C; by default the
  multi-speed design on the run's loop family, the flap behind its servo) and the
  independent verification on that family and on the truth's own linearisation
  (:mod:`casflutter.pipeline._control`);
- ``closed_loop`` — the ROM and the truth above flutter, open and closed loop, and the
  truth's linear closed loop over speed;
- ``suppression`` — the truth with the controller gain ramped 0 -> 1 and released (Fig. 11)
  from its established LCO at each of ``suppression.speed_factors`` times its flutter speed,
  in turbulence with noisy sensors (:mod:`casflutter.pipeline._suppression`).

``run(config)`` from Python writes nothing unless it is given ``out_dir``; ``casflutter run``
writes ``casflutter-run/``.  Progress goes through :mod:`logging` (logger
``casflutter.pipeline``): one line per stage at INFO, and the stages' own Python warnings (an
unstable ROM's free run, records used not as meant) as one WARNING line each.  A run pins the
BLAS pools to one thread (:func:`casflutter._threads.single_threaded`), as the command line
does: the same configuration and seed give bit-identical numbers whatever
``OPENBLAS_NUM_THREADS`` says.
"""

from __future__ import annotations

import logging
import time
import warnings
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import control
import numpy as np

from .._linalg import spectral_abscissa
from .._logging import own_warnings_logged
from .._outputs import provenance, utc_now
from .._processes import map_in_processes
from .._threads import deterministic, single_threaded
from ..aeroelastic import (AeroelasticSystem, FlutterResult, find_flutter, load_family,
                          simulate_loop)
from ..data import envelope_growth_rate
from ..errors import CasflutterError, ConfigError, ConvergenceError, DataWarning
from ..lco import (LCOSettings, compare_lco, lco_branch, rom_lco_branch, rom_loop_flutter,
                   speed_convention)
from ..realize import realize
from ..truth import closed_loop_truth, truth_lco, truth_loop_matrix, truth_loop_sweep
from ._config import RunConfig, load_config
from ._control import ControllerStage, controller_stage, start_controller
from ._exports import check_output_folder, log_flags, write_outputs
from ._model import (ROUTES, FlutterStage, ModelStage, Route, controlled_family, family_model,
                     frozen_flutter, gaf_model, parametric_flutter, rom_model, route_of,
                     truth_family)
from ._result import ClosedLoopChecks, LcoResult, RunResult, SimulationCheck, skipped_notes
from ._suppression import suppression_stage

__all__ = ["run", "model_stages", "design_family", "check_requested_stages"]

log = logging.getLogger("casflutter.pipeline")

#: What each optional stage (or part of one) needs from the problem, and why.
_NEEDS = {"flutter_truth": ("truth", "the truth's flutter search"),
          "frozen": ("truth", "stage 'frozen'"),
          "parametric": ("truth", "stage 'parametric' (records at several speeds)"),
          "lco": ("records", "stage 'lco'"),
          "truth_lco": ("truth", "the truth's LCO of stage 'lco'"),
          "closed_loop": ("truth", "stage 'closed_loop'"),
          "suppression": ("truth", "stage 'suppression'")}

_LACKS = {"truth": "needs a truth simulator", "records": "needs records of a nonlinear model"}


class _Progress:
    """Stage timings, and one INFO line per stage (``[k/n] stage ...``) on the pipeline's
    logger (DEBUG when ``quiet``)."""

    def __init__(self, quiet: bool, names: list[str]):
        self.level = logging.DEBUG if quiet else logging.INFO
        self.names = names
        self.timings: dict[str, float] = {}
        self.t0 = time.perf_counter()

    @contextmanager
    def stage(self, name: str):
        if name not in self.timings:      # once, also when rom.v0_iterations repeats it
            k = self.names.index(name) + 1 if name in self.names else len(self.names)
            log.log(self.level, "[%d/%d] %s ...", k, len(self.names), name)
        t = time.perf_counter()
        yield
        dt = time.perf_counter() - t
        self.timings[name] = self.timings.get(name, 0.0) + dt
        log.debug("stage %s: %.2f s", name, dt)


def _linear_rom(cfg: RunConfig) -> str | None:
    """Why the configured ROM is linear (no limit cycle: above flutter it only grows), or
    ``None``; decided from the configuration."""
    r = cfg.rom
    if r.method == "common_denominator":
        return 'rom.method = "common_denominator" is linear'
    if tuple(r.orders)[4:] == (1, 1):
        return f"rom.orders = {list(r.orders)} has p = q = 1: the HWL model is linear"
    return None


def _skips(cfg: RunConfig, route: Route, problem) -> dict:
    """The optional stages (and parts) the route cannot run, ``{name: "what: why"}``."""
    wanted = set(cfg.stages) | {"flutter_truth"}
    if "lco" in cfg.stages:
        wanted.add("truth_lco")
    name = getattr(problem, "name", cfg.problem.name)
    skipped = {}
    for key in sorted(wanted & set(_NEEDS), key=list(_NEEDS).index):
        need, what = _NEEDS[key]
        if need not in route.offers:
            skipped[key] = f"{what}: {_LACKS[need]}; the {route.kind} problem {name!r} has none"
    linear = _linear_rom(cfg) if "records" in route.offers else None
    if "lco" in cfg.stages and linear and "lco" not in skipped:
        skipped["lco"] = (f"stage 'lco': {linear} and has no limit cycle (above flutter it only "
                          "grows); identify a nonlinear ROM (rom.method = \"hwl\" with p or q "
                          ">= 2, Table I: [3, 1, 1, 1, 2, 2]) or drop 'lco' from stages")
        skipped.pop("truth_lco", None)
    if "lco" in skipped:
        skipped.pop("truth_lco", None)
    return skipped


def check_requested_stages(cfg: RunConfig) -> None:
    """Refuse, before any work, a stage named in ``stages`` that the problem's route cannot
    run (:func:`_skips`: a stage that needs a truth simulator on a wing file, ``lco`` on a
    linear ROM ...), where the configuration names a stage list of its own.  A stage of the
    default list (left out, or spelt out as in the seed wing's files) that cannot run is
    only skipped by :func:`run`, with a note, as is any stage of a configuration that is
    not checked here.  ``casflutter run`` checks every configuration it loads.  The parts
    of a stage that the problem lacks (the truth's flutter or LCO on a wing file) stay
    notes.

    Parameters
    ----------
    cfg : RunConfig
        A validated configuration whose ``stages`` the user gave.

    Raises
    ------
    ConfigError
        Naming each requested stage that cannot run and why.
    """
    if set(cfg.stages) == set(RunConfig().stages):     # the default list: notes only
        return
    problem = cfg.problem.load()
    route = route_of(problem)
    skipped = _skips(cfg, route, problem)
    refused = [s for s in cfg.stages if s in skipped]
    if route.kind == "family":     # a family file runs the controller stage alone
        refused += [s for s in cfg.stages if s != "controller" and s not in refused]
        skipped = {**{s: f"stage {s!r}: a plant family file has no records or simulator "
                          "(only the 'controller' stage runs)" for s in refused}, **skipped}
    if refused:
        hint = ("" if all("from stages" in skipped[s] for s in refused) else
                f"; leave {', '.join(map(repr, refused))} out of stages")
        raise ConfigError(f"stages = {list(cfg.stages)!r} names what cannot run here: "
                          + "; ".join(skipped[s] for s in refused) + hint)


def _checked(cfg: RunConfig, route: Route, problem) -> RunConfig:
    """The configuration fitted to the problem, checked before any work: a wing file's own
    records' speed, its sensors' kind."""
    if route.kind in ("wing", "gaf") and cfg.sensors.kind != problem.structure.sensor:
        raise ConfigError(f"sensors.kind = {cfg.sensors.kind!r} of the run configuration "
                          f"differs from sensors.kind = {problem.structure.sensor!r} of the "
                          f"wing file {problem.path}; set [sensors] kind = "
                          f"\"{problem.structure.sensor}\" in the run configuration")
    if route.kind == "wing":
        if cfg.rom.v0_iterations > 1:
            raise ConfigError(f"rom.v0_iterations = {cfg.rom.v0_iterations}: the records of "
                              f"the wing file {problem.path} are taken at one speed (V0 = "
                              f"{problem.V0:g}); set rom.v0_iterations = 1")
        cfg = replace(cfg, data=replace(cfg.data, V0=float(problem.V0)))
    if route.kind == "family" and cfg.controller.hinf_objective == "lft":
        raise ConfigError("controller.hinf_objective = \"lft\" needs the LFT at a ROM loop's "
                          "flutter speed (eq. 14); a plant family file has none: use "
                          "\"sensors\" or \"auto\"")
    if route.kind == "family" and set(cfg.stages) - {"controller"}:
        log.info("a plant family file has no records or simulator: only the 'controller' "
                 "stage runs")
    if route.kind == "family" and "controller" in cfg.stages:
        # what the design would refuse after the family's flutter analysis, refused now
        family = load_family(problem)
        (lo, hi), (a, b) = cfg.controller.interval, family.speed_range
        if lo < a or hi > b:
            raise ConfigError(f"controller.interval = [{lo:g}, {hi:g}] leaves the speed range "
                              f"[{a:g}, {b:g}] {family.speed_unit} of {family.name}; give an "
                              "interval inside it")
        start_controller(cfg, family)       # names and sizes matched (None without a start)
    return cfg


def _stage_names(cfg: RunConfig, route: Route, skipped) -> list[str]:
    names = list(route.stages)
    for s in cfg.stages:
        if s not in skipped and (route.kind != "family" or s == "controller"):
            names.append(s)
    return names


#: damping coupling (:meth:`AeroelasticTruth.damping_coupling`) above which the ROM's
#: diagonal Σs is said to leave part of the truth's damping out
_COUPLED_DAMPING = 0.05


def _structure(cfg: RunConfig, problem):
    """Σs with the run's sensors (``None`` for a family file)."""
    if not callable(getattr(problem, "modal_structure", None)):
        return None
    coupling = problem.damping_coupling() if callable(
        getattr(problem, "damping_coupling", None)) else 0.0
    if coupling > _COUPLED_DAMPING:
        warnings.warn(
            f"the structural dampers of {getattr(problem, 'name', 'the problem')!r} couple its "
            f"modes (modal damping off the diagonal up to {100 * coupling:.3g} % of the "
            "diagonal), and the ROM's Σs (eq. 7) keeps only the diagonal: the ROM's flutter "
            "speed can differ from the truth's by some per cent, on either side (compare the "
            "two in the flutter table)", DataWarning, stacklevel=2)
    return problem.modal_structure().with_sensors(cfg.sensors.rows or None, cfg.sensors.kind)


def model_stages(cfg: RunConfig, problem, progress=None) -> tuple[ModelStage, FlutterStage]:
    """The model stages of a problem's route (:mod:`casflutter.pipeline._model`).

    Parameters
    ----------
    cfg : RunConfig
        The configuration.
    problem : object
        What ``cfg.problem`` loads.
    progress : optional
        The run's progress (default: one that only times the stages).

    Returns
    -------
    (ModelStage, FlutterStage)
    """
    route = route_of(problem)
    cfg = _checked(cfg, route, problem)
    progress = progress or _Progress(True, list(route.stages))
    structure = _structure(cfg, problem)
    if route.kind == "family":
        return family_model(cfg, problem, progress)
    if route.kind == "gaf":
        return gaf_model(cfg, problem, structure, progress)
    needs_vf = cfg.rom.v0_iterations > 1 or bool(set(cfg.stages) & {"lco", "controller"})
    return rom_model(cfg, problem, structure, progress, needs_vf=needs_vf)


@deterministic
def design_family(cfg: RunConfig):
    """The family a run's controller stage designs on, built by its model stages alone.

    Parameters
    ----------
    cfg : RunConfig
        A run configuration.

    Returns
    -------
    PlantFamily
        The gridded family of a family file; for a ROM, its loop ΣAE(V) with the flap
        behind the servo of ``controller.servo_omega`` (when > 0).
    """
    problem = cfg.problem.load()
    model, _ = model_stages(cfg, problem)
    return controlled_family(cfg, model)


@deterministic
@own_warnings_logged(log)
def run(config: RunConfig | str | Path | None = None, *, out_dir=None, seed: int | None = None,
        quiet: bool = False, write: bool | None = None, overwrite: bool = False) -> RunResult:
    """Run the stages of a configuration (module docstring), and write its outputs when asked.

    Parameters
    ----------
    config : RunConfig, path or None
        Configuration (default: the seed wing's ``problems/seed_wing/run.toml``).
    out_dir : path, optional
        Output folder, checked before any work and written atomically with its
        ``manifest.json`` (:mod:`casflutter.pipeline._exports`); without it nothing is
        written.
    seed : int, optional
        Overrides ``config.seed``.
    quiet : bool
        The stage lines at DEBUG instead of INFO.
    write : bool, optional
        ``False``: write nothing even with ``out_dir`` (default: write when ``out_dir`` is
        given).
    overwrite : bool
        Replace an existing non-empty output folder (as a whole); without it such a folder
        is refused before any work.

    Returns
    -------
    RunResult

    Raises
    ------
    ConfigError
        An invalid configuration, or one that does not fit the problem (before any work).
    OutputError
        An output folder that cannot be written, or exists and is not empty without
        ``overwrite`` (before any work).
    CasflutterError
        No ROM flutter in ``flutter.V_range`` when a later stage needs it (or no truth
        flutter for the closed-loop stage), or a simulation that blew up.
    casflutter.errors.SynthesisError
        No controller of the order held even the low end of the interval.

    See Also
    --------
    load_config : the configuration it runs.

    Examples
    --------
    The typical section's flutter route (records, linear ROM, Σf, flutter), nothing written:

    >>> import casflutter as cf
    >>> from casflutter.pipeline import config_path
    >>> config = cf.load_config(config_path("typical_section", "flutter"), updates={"stages": []})
    >>> result = cf.run(config, quiet=True)
    >>> round(result.flutter.Vf, 4)
    2.2589

    The seed wing's default study (one to two minutes): ``cf.run(cf.load_config())``.
    """
    cfg = config if isinstance(config, RunConfig) else load_config(config)
    if seed is not None:
        cfg = replace(cfg, seed=int(seed))
    writing = out_dir is not None and write is not False
    target = check_output_folder(out_dir, overwrite=overwrite) if writing else None
    info = {**provenance(seed=cfg.seed), "started": utc_now()}
    problem = cfg.problem.load()
    route = route_of(problem)
    cfg = _checked(cfg, route, problem)
    skipped = _skips(cfg, route, problem)
    for line in skipped_notes(skipped):
        log.info(line)
    progress = _Progress(quiet, _stage_names(cfg, route, skipped))
    model, flutters = model_stages(cfg, problem, progress)
    if "frozen" in cfg.stages and "frozen" not in skipped:
        with progress.stage("frozen"):
            flutters = replace(flutters, frozen=frozen_flutter(cfg, problem, model.V0))
    structure = _structure(cfg, problem)
    if "parametric" in cfg.stages and "parametric" not in skipped:
        with progress.stage("parametric"):
            flutters = replace(flutters, parametric=parametric_flutter(cfg, problem, structure))
    truth = problem if "truth" in route.offers else None
    lco = None
    if "lco" in cfg.stages and "lco" not in skipped:
        with progress.stage("lco"):
            lco = _lco(cfg, truth, model.identification.model, structure, flutters.rom,
                       flutters.truth, model.speed_following)
    control_stage = None
    if "controller" in cfg.stages and "controller" not in skipped:
        with progress.stage("controller"):
            control_stage = _controller(cfg, model, flutters, truth, structure)
    closed = sup = None
    if "closed_loop" in cfg.stages and "closed_loop" not in skipped:
        with progress.stage("closed_loop"):
            closed = _closed_loop(cfg, truth, model.identification.model, model.system,
                                  control_stage.lft, control_stage.controller, flutters.rom,
                                  flutters.truth, cfg.sensors.rows or None)
    if "suppression" in cfg.stages and "suppression" not in skipped:
        with progress.stage("suppression"):
            truth_check = control_stage.checks.get("truth")
            sup = suppression_stage(cfg, truth, flutters, lco, control_stage.controller,
                                    mode=_mode(flutters.rom),
                                    dt=model.identification.model.dt,
                                    certified=None if truth_check is None
                                    else truth_check.stable_interval)
    timings = dict(progress.timings, total=time.perf_counter() - progress.t0)
    result = RunResult(config=cfg, problem=problem, route=route.kind, model=model,
                       flutters=flutters, lco=lco, control=control_stage, closed_loop=closed,
                       suppression=sup, skipped=skipped, timings=timings, provenance=info)
    log_flags(result)
    if target is not None:
        result = replace(result, out_dir=target,
                         files=write_outputs(target, result, overwrite=overwrite))
    return result


def _controller(cfg: RunConfig, model: ModelStage, flutters: FlutterStage, truth,
                structure) -> ControllerStage:
    """The controller stage on the model's design family, certified on it and on the
    truth's own linearisation (:func:`casflutter.pipeline._control.controller_stage`)."""
    references = {}
    if truth is not None:
        tf = truth_family(cfg, truth, structure)
        if tf is not None:
            references["truth"] = tf
    system = model.system if model.system is not None and flutters.Vf is not None else None
    stage = controller_stage(cfg, controlled_family(cfg, model), system=system,
                             Vf=flutters.Vf, references=references)
    log.info("controller certified stable over: %s", "; ".join(
        f"{name} " + ("nothing (unstable at the range's start)" if check.stable_interval is None
                      else "[{:.5g}, {:.5g}]".format(*check.stable_interval))
        for name, check in stage.checks.items()))
    return stage


def _mode(res: FlutterResult) -> int:
    """The flutter mode (the mode deflected in the simulations), else mode 0."""
    m = res.flutter_mode
    return int(m) if m is not None and m >= 0 else 0


def _lco(cfg: RunConfig, truth, model, structure, flutter, flutter_truth,
         speed_following=None) -> LcoResult:
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

    Where the run has the ROM that follows the wing over speed and the truth flutters, that
    ROM's LCO is put beside the truth's at ``lco.speed_following_factors`` times the truth's
    flutter speed.
    """
    vr, lc = cfg.flutter.V_range, cfg.lco
    exact = realize(model, "auto")
    sys_exact = AeroelasticSystem.from_parts(exact.sigma_f, structure, warn_unstable=False)
    fl_exact = find_flutter(sys_exact, vr, n_grid=cfg.flutter.n_grid,
                            max_refine=cfg.flutter.max_refine)
    V_hopf = float(fl_exact.Vf) if fl_exact.flutter is not None else float(flutter.Vf)
    V_loop = rom_loop_flutter(model, structure, vr, n_grid=cfg.flutter.n_grid)
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
    loop = "" if V_loop is None else f"loop flutter {V_loop:.5g}, "
    # a frequency is the cycle's; a decay or a divergence has none worth printing
    cycle = (f", {sim.sensors.frequency_hz:.4g} Hz" if sim.sensors.kind == "lco" else "")
    log.info("ROM LCO at V = %.5g (%scontinuous exact-order Hopf %.5g): %s%s", V_lco,
             loop, V_hopf, sim.sensors.kind, cycle)
    # the truth's simulations and the two branches are independent: worker processes
    jobs = []
    if truth is not None:
        V_truth = (float(flutter_truth.Vf) * lc.speed_factor
                   if flutter_truth.flutter is not None else V_lco)
        following = (speed_following if speed_following is not None
                     and flutter_truth.flutter is not None and lc.speed_following_factors
                     else None)
        jobs.append((_truth_lcos, (truth, V_truth, following, crit, model.dt, structure, lc,
                                   flutter_truth.Vf)))
    if lc.branch_points:
        jobs.extend(_branch_jobs(cfg, truth, model, structure))
    done = map_in_processes(_piece, jobs, lc.workers)
    tr, following = done.pop(0) if truth is not None else (None, ())
    for c in following:
        log.info("speed-following ROM's LCO at %.4g x truth Vf (V = %.5g): %s, amplitude "
                 "%s of the truth's", c.speed_factor, c.V, c.rom.sensors.kind,
                 c.describe_error())
    branches = _branches(done)
    return LcoResult(rom=sim, truth=tr, V=V_lco, V_hopf_exact_order=V_hopf,
                     flutter_exact_order=fl_exact, V_hopf_loop=V_loop,
                     speed_following=following, **branches)


def _piece(job):
    """One independent piece of the LCO stage, ``(function, args)``, single-threaded (the
    same numbers in a worker process as here)."""
    fn, args = job
    with single_threaded():
        return fn(*args)


def _truth_lcos(truth, V, speed_following, mode, dt, structure, lc, Vf):
    """The truth's LCO at ``V`` and, given the ROM that follows the wing, that ROM's LCO
    beside the truth's at ``lc.speed_following_factors`` times ``Vf``."""
    tr = truth_lco(truth, V, lc.duration, mode, lc.initial_deflection, dt=dt,
                   sensor_rows=structure.Hs, sensor=structure.sensor,
                   max_extensions=_MAX_EXTENSIONS)
    if speed_following is None:
        return tr, ()
    following = compare_lco(speed_following, truth, Vf, lc.speed_following_factors,
                            duration=lc.duration, mode=mode, deflection=lc.initial_deflection,
                            dt=dt, truth_lcos={lc.speed_factor: tr},
                            max_extensions=_MAX_EXTENSIONS)
    return tr, following


def _branch(key, fn, args, kwargs):
    """``(key, branch, None)``, or ``(key, None, reason)`` when it could not be started."""
    try:
        return key, fn(*args, **kwargs), None
    except (ConfigError, ConvergenceError) as exc:
        return key, None, str(exc)


def _branch_jobs(cfg: RunConfig, truth, model, structure) -> list:
    """The LCO branches of the ROM loop and of the truth (``lco.branch_points`` points
    each; no truth branch on a wing file), as jobs of :func:`_piece`."""
    settings = LCOSettings(max_points=cfg.lco.branch_points, sensor_kind=structure.sensor)
    scale, unit = speed_convention(truth) if truth is not None else (1.0, "speed index")
    ms = truth.modal_structure() if truth is not None else structure
    jobs = [] if truth is None else [
        (_branch, ("truth_branch", lco_branch, (truth, cfg.flutter.V_range, settings),
                   {"problem": "truth"}))]
    jobs.append((_branch, ("rom_branch", rom_lco_branch,
                           (model, structure, cfg.flutter.V_range, settings),
                           {"mode_names": ms.mode_names, "sensor_names": structure.sensor_names,
                            "problem": "ROM loop", "speed_scale": scale, "speed_unit": unit,
                            "time_unit": ms.time_unit})))
    return jobs


def _branches(done) -> dict:
    """The computed branches by key (the reason logged for one that could not be started);
    the ROM loop's outputs in the truth's units."""
    out = {}
    for key, branch, reason in done:
        if branch is None:
            log.info("no %s: %s", key.replace("_", " "), reason)
        else:
            out[key] = branch
    if "truth_branch" in out and "rom_branch" in out:
        # the ROM loop's outputs are the truth's quantities: give them the truth's units
        units = dict(zip(out["truth_branch"].outputs, out["truth_branch"].output_units))
        rb = out["rom_branch"]
        out["rom_branch"] = replace(rb, output_units=tuple(
            units.get(n, u) for n, u in zip(rb.outputs, rb.output_units)))
    return out


#: most continuations of an LCO simulation that still grows
_MAX_EXTENSIONS = 5


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
