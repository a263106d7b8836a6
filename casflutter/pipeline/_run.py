"""``casflutter run``: the paper's study end to end (§IV, Table I).

Stages (each timed, progress on stderr):

1. chirp records of the truth at the nominal speed ``V0`` (modal displacements and flap);
2. HWL ROM with the configured orders (paper: (3, 1, 1, 1, 2, 2)), eq. 1--4;
3. linearise -> ERA -> Tustin -> Σf (eq. 5);
4. Σs (eq. 6--7, accelerometer sensors) and ΣAE (eq. 8--9);
5. Hopf: flutter speed index Vf, its frequency and the critical mode (and the truth's own);
6. nonlinear ROM simulation at Vf -> LCO and its spectrum (paper Fig. 9), beside the truth's;
7. LFT at Vf (eq. 10--15);
8. fixed-order controller on the sensors (paper §III.C);
9. verification: γ, small-gain and exact stable intervals of V (independent code);
10. closed-loop nonlinear truth simulation with the controller gain ramped 0 -> 1 and released
    (paper Fig. 11): LCO attenuation.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import CasflutterError
from ._config import RunConfig, load_config

__all__ = ["RunResult", "run_pipeline"]


@dataclass(frozen=True)
class RunResult:
    """Everything ``casflutter run`` produced.

    Attributes
    ----------
    summary : dict
        The content of ``summary.json``.
    out_dir : Path
        Where the files were written.
    files : dict
        Name -> path of every file written.
    objects : dict
        The live objects of each stage (model, realisation, system, flutter results,
        LFT, synthesis and verification results, simulations), for scripts.
    """

    summary: dict
    out_dir: Path
    files: dict
    objects: dict = field(repr=False, default_factory=dict)


class _Progress:
    def __init__(self, quiet: bool, n_stages: int = 10):
        self.quiet = quiet
        self.n = n_stages
        self.timings: dict[str, float] = {}
        self.t0 = time.perf_counter()

    def stage(self, k: int, name: str):
        progress = self

        class _Ctx:
            def __enter__(self_inner):
                if not progress.quiet:
                    print(f"[{k}/{progress.n}] {name} ...", file=sys.stderr, flush=True)
                self_inner.t = time.perf_counter()
                return self_inner

            def __exit__(self_inner, exc_type, exc, tb):
                dt = time.perf_counter() - self_inner.t
                progress.timings[name] = dt
                if not progress.quiet and exc_type is None:
                    print(f"      {name}: {dt:.2f} s", file=sys.stderr, flush=True)
                return False

        return _Ctx()

    def note(self, text: str):
        if not self.quiet:
            print(f"      {text}", file=sys.stderr, flush=True)


def _jsonable(x: Any):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def delayed(data, samples: int):
    """Records whose forces lag the motion by ``samples`` (the explicit CFD coupling delay,
    see :class:`~casflutter.pipeline._config.DataSection`)."""
    from ..data import IOData, Record

    if samples == 0:
        return data
    recs = tuple(Record(np.vstack([np.zeros((samples, r.n_outputs)), r.y[:-samples]]), r.u,
                        r.v, r.name) for r in data.records)
    return IOData(recs, data.dt, data.output_names, data.u_names, data.v_name, data.meta)


def _flutter_summary(res, hz_per_unit: float) -> dict:
    if res.flutter is None:
        return {"V": None, "freq_hz": None, "mode": None, "status": res.status}
    mode = res.flutter_mode
    return {"V": float(res.Vf), "freq_hz": float(res.omega_f) / (2 * np.pi) * hz_per_unit,
            "mode": None if mode is None or mode < 0 else int(mode) + 1, "status": res.status}


def run_pipeline(config: RunConfig | str | Path | None = None, *, out_dir=None,
                 seed: int | None = None, quiet: bool = False, write: bool = True) -> RunResult:
    """Run the study (module docstring) and write its outputs.

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
    """
    from ..aeroelastic import AeroelasticSystem, build_lft, find_flutter, simulate_loop
    from ..design import SynthesisOptions, design_flutter_controller
    from ..ident import identify
    from ..realize import realize
    from ..truth import load_problem
    from ..verify import verify_controller
    from ._rom_data import truth_records
    from ._suppression import (accelerometer_structure, sensor_rows_of, suppression_run,
                               truth_lco)

    cfg = config if isinstance(config, RunConfig) else load_config(config)
    if seed is not None:
        cfg = replace(cfg, seed=int(seed))
    out = Path(out_dir or "casflutter-run")
    prog = _Progress(quiet)
    objects: dict[str, Any] = {}
    sets = [f"{k}={v}" for k, v in cfg.problem.set.items()]
    truth = load_problem(cfg.problem.name, sets)
    objects["truth"] = truth
    ms = truth.modal_structure()
    # the accelerometers of every stage: Σs, the LFT, the truth's LCO and the suppression run
    Hs = sensor_rows_of(truth, cfg.sensors.rows)
    objects["sensor_rows"] = Hs
    hz = 1.0  # frequencies are cycles per the problem's time unit (seconds for the seed wing)

    with prog.stage(1, "data"):
        d = cfg.data
        data = delayed(truth_records(truth, d.V0, dt=d.dt, duration=d.duration,
                                     band=tuple(d.band_hz), amplitude=d.amplitude),
                       d.coupling_delay)
        objects["data"] = data
    with prog.stage(2, "rom"):
        ident = identify(data, tuple(cfg.rom.orders), criterion=cfg.rom.criterion,
                         regularization=cfg.rom.regularization,
                         ipopt_options=dict(cfg.solver.ipopt))
        model = ident.model
        objects["identification"] = ident
        prog.note(f"{model}; fit error % " +
                  ", ".join(f"{e:.3f}" for e in ident.fit.error_percent))
    with prog.stage(3, "realize"):
        real = realize(model, cfg.rom.nf)
        objects["realization"] = real
    with prog.stage(4, "structure"):
        structure = accelerometer_structure(truth, Hs)
        system = AeroelasticSystem.from_parts(real.sigma_f, structure, warn_unstable=False)
        objects["system"] = system
        if not system.rom_stable:
            prog.note("warning: Σf is unstable on its own (ΣAE unstable at V = 0)")
    with prog.stage(5, "flutter"):
        vr = tuple(cfg.flutter.vrange)
        # a bounded refinement: repeated lag eigenvalues of identical strips make the
        # eigenvector matching ambiguous without changing any crossing
        flutter = find_flutter(system, vr, n_grid=cfg.flutter.n_grid, max_refine=3)
        N = truth.n_modes
        flutter_truth = find_flutter(truth, vr, n_grid=cfg.flutter.n_grid, max_refine=3,
                                     mode_states=[np.array([i, N + i]) for i in range(N)],
                                     omega=ms.omega)
        objects["flutter"], objects["flutter_truth"] = flutter, flutter_truth
        if flutter.flutter is None:
            raise CasflutterError(f"the ROM has no flutter crossing in V ∈ {vr}: "
                                  f"{flutter.message}; widen flutter.vrange")
        Vf = float(flutter.Vf)
        prog.note(f"ROM Vf = {Vf:.4f}, {flutter.frequency_hz * hz:.3f} Hz; truth Vf = "
                  f"{flutter_truth.Vf if flutter_truth.flutter else float('nan'):.4f}")
    with prog.stage(6, "lco"):
        # The nonlinear ROM carries its full linear part (exact order); when Σf is truncated
        # (the paper's nf = 15) its own Hopf point differs from Vf.  Simulate a few per cent
        # above the Hopf point of the exact-order linearisation, where the LCO develops.
        exact = realize(model, "auto")
        sys_exact = AeroelasticSystem.from_parts(exact.sigma_f, structure, warn_unstable=False)
        fl_exact = find_flutter(sys_exact, vr, n_grid=cfg.flutter.n_grid, max_refine=3)
        objects["flutter_exact_order"] = fl_exact
        V_hopf = float(fl_exact.Vf) if fl_exact.flutter is not None else Vf
        V_lco = V_hopf * cfg.lco.speed_factor
        n_steps = int(round(cfg.lco.duration / model.dt))
        xs0 = np.zeros(2 * truth.n_modes)
        crit = flutter.flutter_mode if flutter.flutter_mode is not None and flutter.flutter_mode >= 0 else 0
        xs0[2 * crit] = cfg.lco.initial_deflection
        lco = simulate_loop(model, structure, V_lco, n_steps, xs0=xs0)
        objects["lco"] = lco
        objects["lco_speeds"] = {"V_hopf_exact_order": V_hopf, "V": V_lco}
        # the truth's own LCO: the same distance above its own Hopf point (the ROM's speed
        # can be far above the truth's flutter speed, where the truth diverges)
        V_lco_truth = (float(flutter_truth.Vf) * cfg.lco.speed_factor
                       if flutter_truth.flutter is not None else V_lco)
        lco_truth = truth_lco(truth, V_lco_truth, cfg.lco.duration, crit,
                              cfg.lco.initial_deflection, dt=model.dt, sensor_rows=Hs)
        lco_truth["V"] = V_lco_truth
        objects["lco_truth"] = lco_truth
        prog.note(f"ROM LCO at V = {V_lco:.4f} (exact-order Hopf {V_hopf:.4f}): "
                  f"{lco.sensors.kind}, {lco.sensors.frequency_hz:.3f} Hz")
    with prog.stage(7, "lft"):
        lft = build_lft(system, Vf)
        objects["lft"] = lft
    with prog.stage(8, "controller"):
        c = cfg.controller
        opts = SynthesisOptions(time_limit=c.time_limit or None, max_outer=c.max_outer,
                                max_iter=c.max_iter, zero_start=c.zero_start,
                                stability_margin=c.stability_margin,
                                max_stab_rounds=c.max_stab_rounds,
                                strictly_proper=c.strictly_proper,
                                ipopt=dict(cfg.solver.ipopt))
        # γ of the LFT at Vf (eq. 14-16) with ΣAE(V) kept stable over controller.interval;
        # the controller acts on the physical accelerometers (feed-through closed exactly)
        design = design_flutter_controller(system, Vf, c.order, speeds=tuple(c.speeds),
                                           interval=tuple(c.interval), n_speeds=c.n_speeds,
                                           decay=c.decay, steps=c.steps, starts=c.starts,
                                           seed=cfg.seed, options=opts)
        syn, K = design.synthesis, design.controller
        objects["design"] = design
        objects["synthesis"], objects["controller"] = syn, K
    with prog.stage(9, "verify"):
        ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta)
        objects["verification"] = ver
    with prog.stage(10, "suppression"):
        # the truth flutters at its own speed: suppress its LCO there (paper Fig. 11 was
        # measured on the real wing at an LCO condition)
        V_lco = float(flutter_truth.Vf) if flutter_truth.flutter is not None else Vf
        sup = suppression_run(truth, K, cfg, V_lco, dt=model.dt, mode=crit)
        objects["suppression"] = sup
    summary = _summary(cfg, ident, real, system, flutter, flutter_truth, lco, lco_truth, syn,
                       ver, sup, hz, prog, objects.get("lco_speeds", {}))
    files: dict[str, Path] = {}
    if write:
        files = _write_outputs(out, summary, objects, cfg, prog)
    return RunResult(summary, out, files, objects)


def _summary(cfg, ident, real, system, flutter, flutter_truth, lco, lco_truth, syn, ver, sup,
             hz, prog, objects_speeds) -> dict:
    model = ident.model
    sens = lco.sensors if getattr(lco, "sensors", None) is not None else lco.modes
    timings = dict(prog.timings)
    timings["total"] = time.perf_counter() - prog.t0
    small = getattr(ver, "small_gain_V", None)
    stable = getattr(ver, "exact_V", None)
    return _jsonable({
        "problem": cfg.problem.name,
        "V0": cfg.data.V0,
        "n_sensors": int(system.structure.n_sensors),
        "orders": list(model.orders.as_tuple()),
        "n_params": model.n_params,
        "fit_error_percent": list(ident.fit.error_percent),
        "nf": real.order,
        "ns": 2 * model.n_modes,
        "nae": int(system.state_matrix(0.0).shape[0]),
        "flutter": _flutter_summary(flutter, hz),
        "flutter_truth": _flutter_summary(flutter_truth, hz),
        "lco": {"V": objects_speeds.get("V"),
                "V_hopf_exact_order": objects_speeds.get("V_hopf_exact_order"),
                "freq_hz": sens.frequency_hz * hz if sens.frequency_hz is not None else None,
                "amplitude": list(sens.amplitude), "kind": sens.kind,
                "truth_V": lco_truth.get("V"),
                "truth_freq_hz": lco_truth.get("freq_hz"),
                "truth_amplitude": lco_truth.get("amplitude"),
                "truth_kind": lco_truth.get("kind")},
        "controller": {"order": syn.order, "gamma": syn.gamma if ver is None else ver.gamma,
                       "small_gain_V": list(small) if small is not None else None,
                       "stable_V": list(stable) if stable is not None else None,
                       "stable": bool(ver.stable)},
        "suppression": {"attenuation_percent": sup.get("attenuation_percent"),
                        "lco_returns": sup.get("lco_returns"),
                        "V": sup.get("V")},
        "timings_s": timings,
        "seed": cfg.seed,
    })


def _write_outputs(out: Path, summary: dict, objects: dict, cfg: RunConfig, prog) -> dict:
    from scipy.io import savemat

    from ..verify import controller_to_json
    from ._report import write_figures, write_html

    out.mkdir(parents=True, exist_ok=True)
    files = {}
    tmp = out / "summary.json.tmp"
    with open(tmp, "w") as fh:
        json.dump(summary, fh, indent=2)
    tmp.replace(out / "summary.json")
    files["summary"] = out / "summary.json"
    objects["identification"].model.save(out / "rom.npz")
    files["rom"] = out / "rom.npz"
    K = objects["controller"]
    with open(out / "controller.json", "w") as fh:
        json.dump(controller_to_json(K), fh, indent=2)
    files["controller_json"] = out / "controller.json"
    savemat(out / "controller.mat", {"A": np.asarray(K.A), "B": np.asarray(K.B),
                                      "C": np.asarray(K.C), "D": np.asarray(K.D)})
    files["controller_mat"] = out / "controller.mat"
    with open(out / "config.json", "w") as fh:
        json.dump(_jsonable(cfg.to_dict()), fh, indent=2)
    files["config"] = out / "config.json"
    figs = write_figures(out, objects, cfg)
    files.update(figs)
    files["report"] = write_html(out, summary, figs)
    return files
