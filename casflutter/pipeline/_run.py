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

Two configurations ship with the package: ``problems/seed_wing/run.toml`` (the paper's
study, ``casflutter run``) and ``problems/typical_section/flutter_check.toml`` (an order-2
controller designed on the ROM identified at its own flutter speed and checked on the
truth); ``problems/NAME/flutter.toml`` are the ROM routes of ``casflutter flutter``.
"""

from __future__ import annotations

import json
import sys
import time
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import casadi as ca
import control
import numpy as np
from scipy.io import savemat
from scipy.optimize import brentq

from .._linalg import spectral_abscissa
from .._settings import settings_as
from ..aeroelastic import (AeroelasticSystem, FlutterResult, ParametricSystem, build_lft,
                           find_flutter, simulate_loop)
from ..data import envelope_growth_rate
from ..design import SynthesisOptions, design_flutter_controller
from ..errors import CasflutterError, ConfigError, ConvergenceError
from ..ident import (IdentificationResult, IdentificationSettings, fit_report, identify,
                     identify_common_denominator)
from ..lco import LCOSettings, lco_branch, rom_lco_branch, rom_loop_map, speed_convention
from ..realize import ParametricROM, realize, speed_nodes
from ..report import figure_captions, write_figures, write_html
from ..truth import (RecordSettings, closed_loop_truth, frozen_aero_truth, suppression_run,
                     truth_lco, truth_loop_matrix, truth_loop_sweep, truth_records)
from ..verify import controller_to_json, speed_sweep, verify_controller
from ._config import RunConfig, load_config
from ._result import (ClosedLoopChecks, LcoResult, ParametricResult, RunResult,
                      SimulationCheck, _jsonable)

__all__ = ["run"]


class _Progress:
    """Stage timings, and a line per stage on stderr unless quiet."""

    def __init__(self, quiet: bool, names: list[str]):
        self.quiet = quiet
        self.names = names
        self.timings: dict[str, float] = {}
        self.t0 = time.perf_counter()

    @contextmanager
    def stage(self, name: str):
        if not self.quiet:
            k = self.names.index(name) + 1
            print(f"[{k}/{len(self.names)}] {name} ...", file=sys.stderr, flush=True)
        t = time.perf_counter()
        yield
        dt = time.perf_counter() - t
        self.timings[name] = self.timings.get(name, 0.0) + dt
        if not self.quiet:
            print(f"      {name}: {dt:.2f} s", file=sys.stderr, flush=True)

    def note(self, text: str):
        if not self.quiet:
            print(f"      {text}", file=sys.stderr, flush=True)


def _stage_names(cfg: RunConfig) -> list[str]:
    names = ["data", "rom", "realize", "structure", "flutter"]
    for s in cfg.stages:
        names += ["lft", "controller", "verify"] if s == "controller" else [s]
    return names


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
        quiet: bool = False, write: bool = True) -> RunResult:
    """Run the stages of a configuration (module docstring) and write its outputs.

    Parameters
    ----------
    config : RunConfig, path or None
        Configuration (default: the seed wing's ``problems/seed_wing/run.toml``).
    out_dir : path, optional
        Output folder (default ``casflutter-run``).
    seed : int, optional
        Overrides ``config.seed``.
    quiet : bool
        No progress on stderr.
    write : bool
        Write files (summary, figures, report, ROM, controller).

    Returns
    -------
    RunResult

    Raises
    ------
    ConfigError
        An invalid configuration (before any work).
    CasflutterError
        No ROM flutter in ``flutter.V_range`` when a later stage needs it (or no truth
        flutter for the closed-loop stage), or a simulation that blew up.
    casflutter.errors.SynthesisError
        No synthesis start stabilised the design plants.

    Examples
    --------
    >>> import casflutter as cf                                  # doctest: +SKIP
    >>> result = cf.run(cf.load_config(), write=False)           # doctest: +SKIP
    >>> result.flutter.Vf, result.verification.exact_V           # doctest: +SKIP
    """
    cfg = config if isinstance(config, RunConfig) else load_config(config)
    if seed is not None:
        cfg = replace(cfg, seed=int(seed))
    prog = _Progress(quiet, _stage_names(cfg))
    truth = cfg.problem.load()
    structure = truth.modal_structure().with_sensors(cfg.sensors.rows or None, cfg.sensors.kind)
    rows = cfg.sensors.rows or None
    records = settings_as(cfg.data, RecordSettings)
    vr = cfg.flutter.V_range
    flutter_kw = dict(n_grid=cfg.flutter.n_grid, max_refine=cfg.flutter.max_refine)
    needs_vf = cfg.rom.v0_iterations > 1 or bool(set(cfg.stages) & {"lco", "controller"})
    out: dict = {"config": cfg, "truth": truth}

    # 1-5: records, ROM, Σf, ΣAE, flutter; repeated at the ROM's own flutter speed
    V0, history = cfg.data.V0, []
    for it in range(cfg.rom.v0_iterations):
        with prog.stage("data"):
            data = truth_records(truth, records, V0=V0)
        with prog.stage("rom"):
            ident, model = _identify(data, cfg)
        with prog.stage("realize"):
            real = realize(model, cfg.rom.nf)
        with prog.stage("structure"):
            system = AeroelasticSystem.from_parts(real.sigma_f, structure, warn_unstable=False)
            if not system.rom_stable:
                prog.note("warning: Σf is unstable on its own (ΣAE unstable at V = 0)")
        with prog.stage("flutter"):
            flutter = find_flutter(system, vr, **flutter_kw)
            Vf = flutter.Vf
            last = (it == cfg.rom.v0_iterations - 1 or Vf is None
                    or abs(Vf - V0) <= cfg.rom.v0_rtol * Vf)
            if last:
                flutter_truth = find_flutter(truth, vr, **flutter_kw)
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
    prog.note(f"{model}; fit error % " + ", ".join(f"{e:.3f}" for e in fit.error_percent))
    prog.note(f"ROM Vf = {Vf if Vf is not None else float('nan'):.4f}; truth Vf = "
              f"{flutter_truth.Vf if flutter_truth.flutter else float('nan'):.4f}")
    out.update(data=data, identification=ident, identification_history=tuple(history),
               fit=fit, realization=real, system=system, flutter=flutter,
               flutter_truth=flutter_truth)
    crit = _mode(flutter)

    if "frozen" in cfg.stages:
        with prog.stage("frozen"):
            out["flutter_frozen"] = find_flutter(frozen_aero_truth(truth, V0), vr, **flutter_kw)
    if "parametric" in cfg.stages:
        with prog.stage("parametric"):
            speeds = speed_nodes(vr, cfg.parametric.n_speeds)
            prom = ParametricROM(speeds, tuple(
                identify_common_denominator(truth_records(truth, records, V0=float(v)),
                                            cfg.rom.na, cfg.rom.nb) for v in speeds))
            psys = ParametricSystem(prom, structure)
            out["parametric"] = ParametricResult(prom, psys, find_flutter(
                psys, vr, n_grid=cfg.flutter.n_grid, max_refine=cfg.parametric.max_refine))
    if "lco" in cfg.stages:
        with prog.stage("lco"):
            out["lco"] = _lco(cfg, truth, model, structure, flutter, flutter_truth, prog)
    if "controller" in cfg.stages:
        with prog.stage("lft"):
            lft = build_lft(system, Vf)
        with prog.stage("controller"):
            c = cfg.controller
            options = replace(settings_as(c, SynthesisOptions),
                              ipopt={**cfg.solver.ipopt, **c.ipopt})
            # γ of the LFT at Vf (eq. 14-16), each design plant with its own loop shift, and
            # ΣAE(V) kept stable over controller.interval; K acts on the physical sensors
            design = design_flutter_controller(
                system, Vf, c.order, speeds=tuple(c.speeds), interval=tuple(c.interval),
                n_speeds=c.n_speeds, decay=c.interval_decay, steps=c.steps, starts=c.starts,
                seed=cfg.seed, options=options)
            syn, K = design.synthesis, design.controller
        with prog.stage("verify"):
            ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta)
            if cfg.verify.sweep:
                lo, hi = cfg.verify.sweep
                out["rom_sweep"] = speed_sweep(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf,
                                               n_delta=lft.n_delta,
                                               V=np.linspace(lo * Vf, hi * Vf,
                                                             cfg.verify.n_sweep))
        out.update(lft=lft, synthesis=syn, controller=K, verification=ver)
    if "closed_loop" in cfg.stages:
        with prog.stage("closed_loop"):
            out["closed_loop"] = _closed_loop(cfg, truth, model, system, out["lft"],
                                              out["controller"], flutter, flutter_truth, rows)
    if "suppression" in cfg.stages:
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
    timings = dict(prog.timings)
    timings["total"] = time.perf_counter() - prog.t0
    result = RunResult(**out, timings=timings)
    if write:
        target = Path(out_dir or "casflutter-run")
        result = replace(result, out_dir=target, files=_write_outputs(target, result))
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
    V_truth = (float(flutter_truth.Vf) * lc.speed_factor if flutter_truth.flutter is not None
               else V_lco)
    tr = truth_lco(truth, V_truth, lc.duration, crit, lc.initial_deflection, dt=model.dt,
                   sensor_rows=structure.Hs, sensor=structure.sensor,
                   max_extensions=_MAX_EXTENSIONS)
    prog.note(f"ROM LCO at V = {V_lco:.4f} (loop flutter {V_loop or float('nan'):.4f}, "
              f"continuous exact-order Hopf {V_hopf:.4f}): "
              f"{sim.sensors.kind}, {sim.sensors.frequency_hz:.3f} Hz")
    branches = _branches(cfg, truth, model, structure, prog) if lc.branch_points else {}
    return LcoResult(rom=sim, truth=tr, V=V_lco, V_hopf_exact_order=V_hopf,
                     flutter_exact_order=fl_exact, V_hopf_loop=V_loop, **branches)


def _branches(cfg: RunConfig, truth, model, structure, prog) -> dict:
    """The LCO branches of the ROM loop and of the truth (``lco.branch_points`` points
    each), or the reason a branch could not be started."""
    settings = LCOSettings(max_points=cfg.lco.branch_points, sensor_kind=structure.sensor)
    scale, unit = speed_convention(truth)
    ms = truth.modal_structure()
    out = {}
    for key, compute in (
            ("truth_branch", lambda: lco_branch(truth, cfg.flutter.V_range, settings,
                                                problem="truth")),
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


def _write_outputs(out: Path, result: RunResult) -> dict:
    """``summary.json``, ``rom.npz``, the controller (JSON and .mat), ``config.json``, the
    figures and ``report.html``."""
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    summary = result.summary()
    tmp = out / "summary.json.tmp"
    with open(tmp, "w") as fh:
        json.dump(summary, fh, indent=2)
    tmp.replace(out / "summary.json")
    files["summary"] = out / "summary.json"
    result.identification.model.save(out / "rom.npz")
    files["rom"] = out / "rom.npz"
    K = result.controller
    if K is not None:
        with open(out / "controller.json", "w") as fh:
            json.dump(controller_to_json(K), fh, indent=2)
        files["controller_json"] = out / "controller.json"
        savemat(out / "controller.mat", {"A": np.asarray(K.A), "B": np.asarray(K.B),
                                          "C": np.asarray(K.C), "D": np.asarray(K.D)})
        files["controller_mat"] = out / "controller.mat"
    with open(out / "config.json", "w") as fh:
        json.dump(_jsonable(result.config.to_dict()), fh, indent=2)
    files["config"] = out / "config.json"
    figs = write_figures(out, result)
    files.update(figs)
    files["report"] = write_html(out, summary, figs, figure_captions(result))
    return files
