"""``casflutter flutter``: truth, ROM and parametric-ROM flutter speeds of a problem.

Runs the configuration ``problems/NAME/flutter.toml`` (:func:`casflutter.pipeline.run`: the
paper's ROM route at one speed with the V² scaling, the truth with its aerodynamics frozen at
that speed, and the parametric ROM interpolated in V) beside the full-order truth, prints the
flutter and divergence speeds in the problem's own units (or writes JSON to stdout) and,
with ``--figure PATH``, saves the V–g / V–f figure.

On a GAF wing file (``kind = "gaf"``: modal data and ``Q(ik)``, e.g. ``problems/goland_gaf``)
the route is the rational-function approximation instead: the driver with no optional stage
fits the RFA, finds the flutter of ΣAE(U) in m/s and rad/s and solves p–k on the same table;
both are printed side by side with the published reference of the file, if any.

On a plant family file (``kind = "plant_family"``: state-space models at a grid of speeds,
e.g. ``problems/goland_4flaps``) the route is :mod:`._flutter_family`: every open-loop
crossing of the interpolated grid, in the family's units.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..._outputs import check_figure_path, print_json, save_figure
from ._flutter_family import print_notes

__all__ = ["register", "run", "summarize"]


def register(subparsers) -> None:
    """Add the ``flutter`` sub-command."""
    p = subparsers.add_parser(
        "flutter", help="flutter speed of the truth, the single-speed ROM and the parametric ROM",
        description="Identify an HWL ROM from chirp data of the truth at one speed, close the "
                    "loop with the paper's V^2 scaling and find its flutter speed; do the same "
                    "with a parametric ROM interpolated in V; compare with the truth.  Speeds "
                    "in the problem's unit (speed index for the typical section, m/s for the "
                    "Goland wing).")
    p.add_argument("problem", help="problem name (see `casflutter problems`), rig TOML file, "
                                   "GAF wing file (kind = \"gaf\", e.g. "
                                   "problems/goland_gaf: RFA flutter in m/s with p-k), or "
                                   "plant family file (kind = \"plant_family\", e.g. "
                                   "problems/goland_4flaps: every crossing of the grid)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="change a problem parameter (repeatable)")
    p.add_argument("--vrange", nargs=2, type=float, metavar=("LO", "HI"), default=None,
                   help="speed range of the analysis, in the problem's speed unit")
    p.add_argument("--v0", type=float, default=None,
                   help="nominal speed of the single-speed ROM, in the problem's speed unit")
    p.add_argument("--convective", action="store_true",
                   help="scale the single-speed ROM's time with the speed (rom.convective: "
                        "its lags follow the reduced frequency, as strip theory's do)")
    p.add_argument("--no-parametric", action="store_true",
                   help="skip the parametric ROM (its block is then null)")
    p.add_argument("--truth-only", action="store_true",
                   help="only the truth's flutter and divergence speeds, from the eigenvalues "
                        "of its linearisation (no records, no ROM); the default for a rig "
                        "file without a [rom] table")
    p.add_argument("--figure", default=None, metavar="PATH",
                   help="save the V-g/V-f figure to PATH (.png, .pdf, .svg ...; checked "
                        "before the work); default: no figure")
    p.add_argument("--json", action="store_true", help="write the result as JSON to stdout")
    p.set_defaults(func=run)


def _speed_conv(truth):
    """(V -> problem unit, problem unit -> V, unit name)."""
    if callable(getattr(truth, "airspeed", None)) and callable(getattr(truth, "speed_index",
                                                                      None)):
        return truth.airspeed, truth.speed_index, "m/s"
    return float, float, "speed index " + truth.modal_structure().speed_index


def _freq_unit(truth) -> tuple[float, str]:
    ms = truth.modal_structure()
    if ms.time_unit == "1/omega_theta":
        return 1.0, "Omega/omega_theta"
    return 1.0, f"rad/{ms.time_unit}"


def _block(res, truth, to_unit, fscale) -> dict | None:
    if res is None:
        return None
    names = truth.modal_structure().mode_names
    mode = None
    if res.flutter_mode is not None and 0 <= res.flutter_mode < len(names):
        mode = names[res.flutter_mode]
    return {"V_flutter": None if res.Vf is None else to_unit(res.Vf),
            "omega_flutter": None if res.omega_f is None else res.omega_f * fscale,
            "mode": mode,
            "V_divergence": None if res.divergence is None else to_unit(res.divergence.V),
            "status": res.status,
            "unstable_at_start": bool(res.unstable_at_start),
            "message": res.message}


def summarize(result, problem: str) -> dict:
    """The JSON document of ``casflutter flutter`` for a :class:`casflutter.pipeline.RunResult`."""
    truth = result.truth
    to_unit, _, vunit = _speed_conv(truth)
    fscale, funit = _freq_unit(truth)
    rom_stable = bool(result.system.rom_stable)
    rom = _block(result.flutter, truth, to_unit, fscale)
    rom["rom_stable"] = rom_stable
    parametric = None if result.parametric is None else result.parametric.flutter
    warn = []
    if not rom_stable:
        warn.append("the single-speed ROM is unstable on its own (ΣAE unstable at V = 0): "
                    "its crossings are not flutter onsets")
    # the searches' own messages speak in the speed index: say so when the output does not
    note = "" if vunit.startswith("speed index") else (
        f" (V in this message is the speed index {truth.modal_structure().speed_index}; the "
        f"speeds above are in {vunit})")
    for key, r in (("truth", result.flutter_truth), ("rom", result.flutter),
                   ("parametric_rom", parametric)):
        if r is not None and r.Vf is None:
            warn.append(f"{key}: {r.message}{note}")

    def err(x):
        return None if x is None else float(x)

    return {
        "problem": problem,
        "truth": _block(result.flutter_truth, truth, to_unit, fscale),
        "rom": rom,
        "parametric_rom": _block(parametric, truth, to_unit, fscale),
        "frozen_aero_truth": _block(result.flutter_frozen, truth, to_unit, fscale),
        "units": {"V_flutter": vunit, "V_divergence": vunit, "omega_flutter": funit,
                  "rom_V0": vunit, "V_range": vunit, "parametric_speeds": vunit,
                  "relative_errors": "fraction (0.01 = 1 %)", "timings": "s",
                  "speed_index": truth.modal_structure().speed_index},
        "rom_V0": to_unit(result.config.data.V0),
        "rom_convective": bool(result.config.rom.convective),
        "V_range": [to_unit(v) for v in result.config.flutter.V_range],
        "parametric_speeds": (None if result.parametric is None
                              else [to_unit(v) for v in result.parametric.rom.speeds]),
        "relative_errors": {"rom": err(result.rom_error),
                            "rom_vs_frozen": err(result.identification_error),
                            "v2_scaling": err(result.scaling_error),
                            "parametric_rom": err(result.parametric_error),
                            **{f"{k}_divergence": err(v)
                               for k, v in result.divergence_errors().items()}},
        "explanation": result.explanation(),
        "timings": {k: float(v) for k, v in result.timings.items()},
        "warnings": warn,
    }


def _panels(result) -> list:
    """``(title, FlutterResult)`` of the truth and the ROMs of a run."""
    rom = ("ROM at V0 (time scaled with V)" if result.config.rom.convective
           else "ROM at V0 (V² scaling)")
    panels = [("truth", result.flutter_truth), (rom, result.flutter)]
    if result.parametric is not None:
        panels.append(("parametric ROM", result.parametric.flutter))
    return panels


def _figure(truth, panels: list, path: str, omega_max: float) -> None:
    """The V-g / V-f panels (``(title, FlutterResult)``) in the units of the printed table:
    the problem's speed (m/s where it has a speed scale, with the speed index on a second
    axis; else the speed index) and the table's frequency unit; one legend, the modes
    numbered from 1 and named."""
    import matplotlib.pyplot as plt
    import numpy as np

    from ...lco import speed_convention
    from ...report import frequency_unit, plot_vg_vf

    ms = truth.modal_structure()
    scale, unit = speed_convention(truth)
    index = f"speed index {ms.speed_index.split(',')[0]}"      # the definition, not its terms
    airspeed = unit == "m/s"
    funit = frequency_unit(ms.time_unit) or "rad/s"       # the table's unit
    fig, axes = plt.subplots(2, len(panels), sharex=True, figsize=(5.0 * len(panels), 7.0),
                             squeeze=False)
    legend = {}
    for k, (title, res) in enumerate(panels):
        tr = res.tracking
        # the lightly damped oscillatory (structural) branches; not the real aerodynamic
        # lags nor the fast ROM poles near -2/dt
        lam = tr.eigenvalues
        keep = [b for b in tr.upper_branches()
                if np.max(np.abs(lam[:, b])) < 3.0 * omega_max
                and np.min(tr.damping_ratio[:, b]) < 0.9
                and np.mean(lam[:, b].imag) > 0.02 * omega_max]
        plot_vg_vf(res, branches=keep, ax=(axes[0, k], axes[1, k]), hz=False,
                   frequency_unit=funit, mode_names=ms.mode_names,
                   speed_scale=scale if airspeed else 1.0, speed_unit="m/s" if airspeed else "",
                   speed_label="airspeed U [m/s]" if airspeed else index,
                   index_label=index if airspeed else None)
        axes[0, k].set_title(f"{title}\n{axes[0, k].get_title()}", fontsize="medium")
        for h, lab in zip(*axes[0, k].get_legend_handles_labels()):
            legend.setdefault(lab, h)
        axes[0, k].get_legend().remove()
    fig.legend(list(legend.values()), list(legend), loc="lower center", ncol=min(len(legend), 4),
               fontsize="small", frameon=False)
    fig.tight_layout(rect=(0, 0.03 * (1 + (len(legend) - 1) // 4), 1, 1))
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def _without_rom_route(problem: str) -> bool:
    """A problem file (not a built-in problem) without a ``[rom]`` table: no ROM route."""
    from ...truth import problem_definition, problem_names

    return problem not in problem_names() and "rom" not in problem_definition(problem)


def _run_truth_only(args, truth, label: str, fig_path) -> int:
    """The truth's own flutter and divergence speeds (``--truth-only``, or a problem file
    without ``[rom]`` settings): eigenvalues of its linearisation over the range."""
    from ...aeroelastic import find_flutter
    from ...errors import ConfigError
    from ...lco import default_vrange

    to_unit, from_unit, vunit = _speed_conv(truth)
    fscale, funit = _freq_unit(truth)
    if args.vrange is not None:
        lo, hi = (from_unit(v) for v in args.vrange)
    else:
        try:
            lo, hi = default_vrange(truth)
        except ConfigError:
            raise ConfigError(f"{label}: no speed range for the truth's flutter; give --vrange "
                              "LO HI (or [lco] vrange in the problem file)") from None
    if not 0 <= lo < hi:
        raise ConfigError(f"--vrange: need 0 <= LO < HI, got {to_unit(lo):g} {to_unit(hi):g}")
    res = find_flutter(truth, (lo, hi))
    route = ("--truth-only" if args.truth_only else
             "the problem file has no [rom] table (V0, V_range, dt, duration, band) for the "
             "ROM route")
    doc = {"problem": label, "truth": _block(res, truth, to_unit, fscale), "rom": None,
           "parametric_rom": None, "frozen_aero_truth": None,
           "units": {"V_flutter": vunit, "V_divergence": vunit, "omega_flutter": funit,
                     "V_range": vunit, "speed_index": truth.modal_structure().speed_index},
           "V_range": [to_unit(lo), to_unit(hi)],
           "warnings": [] if res.Vf is not None or res.divergence is not None else
           [f"truth: {res.message}"],
           "note": f"the truth only: {route}", "figure": fig_path}
    if fig_path is not None:
        _figure(truth, [("truth", res)], fig_path, float(truth.modal_structure().omega.max()))
    if args.json:
        print_json(doc)
        return 0
    b = doc["truth"]
    vu = "m/s" if vunit == "m/s" else "index"
    print(f"{label}: flutter speed ({vunit}), frequency ({funit}); {doc['note']}")
    print(f"  {'':8} {f'V_flutter [{vu}]':>18} {'omega_flutter':>14} {'mode':>12} "
          f"{f'V_divergence [{vu}]':>20}")
    print(f"  {'truth':8} {_fmt(b['V_flutter']):>18} {_fmt(b['omega_flutter']):>14} "
          f"{str(b['mode']):>12} {_fmt(b['V_divergence']):>20}")
    return print_notes(doc)


def _fmt(x, unit="") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "none in range"
    return f"{x:.6g}{unit}"


def summarize_gaf(result, problem: str) -> dict:
    """The JSON document of ``casflutter flutter`` on a GAF wing file: the RFA's flutter and
    the p–k check in m/s and rad/s, and their errors against the file's reference."""
    s = result.summary()["rfa"]
    ref = result.problem.definition.get("reference", {}).get("flutter")
    errors = None
    if ref and "airspeed" in ref and "frequency" in ref:
        errors = {key: None if s[key] is None else {
            "airspeed": s[key]["airspeed_m_s"] / ref["airspeed"] - 1.0,
            "omega": s[key]["omega_rad_s"] / ref["frequency"] - 1.0} for key in ("flutter", "pk")}
    warn = []
    if s["flutter"] is None:
        warn.append(f"rfa: {result.rfa_flutter.message}")
    if s["pk"] is None:
        warn.append(f"p-k: {result.pk.message}")
    return {"problem": problem, "route": "rfa", "rfa": {k: s[k] for k in (
                "method", "n_lags", "poly_order", "lag_roots", "n_lag_states", "fit_error",
                "max_element_error")},
            "rfa_flutter": s["flutter"], "pk": s["pk"],
            "reference": None if not ref else {"airspeed_m_s": ref.get("airspeed"),
                                               "omega_rad_s": ref.get("frequency")},
            "relative_errors": errors, "U_range": list(result.problem.U_range),
            "units": {"airspeed": "m/s", "omega": "rad/s", "k": "omega b / U"},
            "timings": {k: float(v) for k, v in result.timings.items()}, "warnings": warn}


def _gaf_config(problem):
    """The run configuration of ``casflutter flutter`` on a GAF wing file: its flutter route
    only, built for the file rather than from the seed wing's defaults.

    Parameters
    ----------
    problem : casflutter.truth.GAFProblem
        The GAF wing file.

    Returns
    -------
    casflutter.pipeline.RunConfig
        No optional stage; the file's sensors' kind; ``rom.nf = "auto"`` (no ROM is
        identified on this route, and the seed wing's ``rom.nf`` is not checked against the
        file's modes); the frozen ΣAE(V) searched over ``gaf.U_range`` as a speed index
        (``U / U_ref``) on ``gaf.n_grid`` points, where its flutter speed ``Uf / U_ref``
        lies.
    """
    from ...pipeline import (FlutterSection, ProblemSection, RomSection, RunConfig,
                             SensorsSection)

    lo, hi = (float(U) / problem.U_ref for U in problem.U_range)
    return RunConfig(problem=ProblemSection(name=str(problem.path)), stages=(),
                     rom=RomSection(nf="auto"),
                     flutter=FlutterSection(V_range=(lo, hi), n_grid=problem.n_grid),
                     sensors=SensorsSection(kind=problem.structure.sensor))


def _run_gaf(args, problem, label: str, fig_path) -> int:
    """``casflutter flutter`` on a GAF wing file."""
    from ...errors import ConfigError
    from ...pipeline import run as run_config

    if args.convective:
        raise ConfigError(f"--convective does not apply to the GAF wing file {problem.path}: "
                          "its rational-function aerodynamics already scale with the airspeed")
    for flag, given in (("--v0", args.v0 is not None), ("--vrange", args.vrange is not None)):
        if given:
            raise ConfigError(f"{flag} does not apply to the GAF wing file {problem.path}: it "
                              "has no records, and its airspeed range is gaf.U_range [m/s]; "
                              "edit the file")
    result = run_config(_gaf_config(problem), quiet=True, write=False)
    doc = summarize_gaf(result, label)
    doc["figure"] = fig_path
    if fig_path is not None:
        import matplotlib.pyplot as plt
        import numpy as np

        from ...report import plot_vg_vf, speed_axes

        pk, fl = result.pk, result.rfa_flutter
        # the oscillatory branches of the modes p-k follows (not the real aerodynamic
        # roots); of every structural mode when p-k follows none
        lam = fl.tracking.eigenvalues
        shown = pk.modes or tuple(range(problem.structure.n_modes))
        low = [b for b in fl.tracking.upper_branches()
               if fl.origin[b] in shown and np.mean(np.abs(lam[:, b].imag)) > 0]
        fig = plot_vg_vf(fl, branches=low, hz=False, speed_unit="m/s",
                         speed_label="airspeed U [m/s]", mode_names=problem.structure.mode_names)
        ag, af = fig.axes
        speed_axes(ag, problem.U_ref, "speed index V = U / U_ref")
        for j in range(len(pk.modes)):
            ag.plot(pk.U, pk.damping_ratio[:, j], "ko", ms=3, mfc="none",
                    label="p–k" if j == 0 else None)
            af.plot(pk.U, pk.omega[:, j], "ko", ms=3, mfc="none")
        ag.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0)
        fig.tight_layout()
        save_figure(fig, fig_path, dpi=110)
        plt.close(fig)
    if args.json:
        print_json(doc)
        return 0
    r = doc["rfa"]
    print(f"{label}: flutter from Q(ik) ({r['method']} RFA, {r['n_lags']} lag roots, fit "
          f"error {r['fit_error']:.2e}); airspeed [m/s], frequency [rad/s]")
    print(f"  {'':22} {'U_flutter':>10} {'omega_flutter':>14} {'k':>8} {'error U':>9} "
          f"{'error omega':>12}")
    rows = [("RFA -> ΣAE(U)", doc["rfa_flutter"], "flutter"), ("p-k on Q(ik)", doc["pk"], "pk")]
    if doc["reference"]:
        rows.append(("published", {"airspeed_m_s": doc["reference"]["airspeed_m_s"],
                                   "omega_rad_s": doc["reference"]["omega_rad_s"], "k": None},
                     None))
    for name, b, key in rows:
        if b is None:
            print(f"  {name:22} {'none in range':>10}")
            continue
        e = (doc["relative_errors"] or {}).get(key) if key else None
        err = (f"{100 * e['airspeed']:+8.2f}% {100 * e['omega']:+11.2f}%" if e else "")
        k = "" if b["k"] is None else f"{b['k']:.4f}"
        print(f"  {name:22} {b['airspeed_m_s']:10.2f} {b['omega_rad_s']:14.2f} {k:>8} {err}")
    return print_notes(doc)


def run(args) -> int:
    """Handler: run the route, print or write JSON, save the figure."""
    from ...data import FamilyFile
    from ...errors import ConfigError
    from ...truth import GAFProblem, WingProblem, load_problem, parse_sets, problem_label
    from ._flutter_family import run_family

    fig_path = None                  # figures only where asked, checked before the work
    if args.figure is not None and args.figure.lower() != "none":
        fig_path = str(check_figure_path(args.figure, what="--figure"))
    changes = parse_sets(args.sets)
    truth = load_problem(args.problem, changes)
    label = problem_label(args.problem)
    if isinstance(truth, FamilyFile):
        return run_family(args, truth, label, fig_path)
    if isinstance(truth, GAFProblem):
        return _run_gaf(args, truth, label, fig_path)
    if isinstance(truth, WingProblem):
        raise ConfigError(f"{args.problem} is a wing file with records (kind = \"wing\"): "
                          "its flutter speed comes from `casflutter run` with a run "
                          "configuration whose [problem] name is the file (e.g. "
                          "problems/example_wing/run.toml, stages = [] for flutter only)")
    from ...pipeline import flutter_config, run as run_config

    label = problem_label(args.problem)
    if args.truth_only or _without_rom_route(args.problem):
        return _run_truth_only(args, truth, label, fig_path)
    _, from_unit, vunit = _speed_conv(truth)
    updates = {"problem.set": changes}
    if args.vrange is not None:
        lo, hi = args.vrange
        updates["flutter.V_range"] = [from_unit(lo), from_unit(hi)]
    if args.v0 is not None:
        updates["data.V0"] = from_unit(args.v0)
    if args.convective:
        updates["rom.convective"] = True
    cfg = flutter_config(args.problem, updates=updates)
    if args.no_parametric:
        cfg = replace(cfg, stages=tuple(s for s in cfg.stages if s != "parametric"))
    result = run_config(cfg, quiet=True, write=False)
    doc = summarize(result, label)
    doc["figure"] = fig_path
    if fig_path is not None:
        _figure(truth, _panels(result), fig_path, float(truth.modal_structure().omega.max()))
    if args.json:
        print_json(doc)
        return 0
    u = doc["units"]
    vu = "m/s" if u["V_flutter"] == "m/s" else "index"
    print(f"{label}: flutter speed ({u['V_flutter']}), frequency ({u['omega_flutter']})")
    v0 = f"{doc['rom_V0']:.4g}" + (" m/s" if vu == "m/s" else "")
    rom_label = ("scaled " if result.config.rom.convective else "") + f"ROM at V0={v0}"
    w = max(20, len(rom_label))
    print(f"  {'':{w}} {f'V_flutter [{vu}]':>18} {'omega_flutter':>14} {'mode':>12} "
          f"{f'V_divergence [{vu}]':>20}")
    for key, label in (("truth", "truth"), ("rom", rom_label),
                       ("frozen_aero_truth", "frozen-aero truth"),
                       ("parametric_rom", "parametric ROM")):
        b = doc[key]
        if b is None:
            continue
        print(f"  {label:{w}} {_fmt(b['V_flutter']):>18} {_fmt(b['omega_flutter']):>14} "
              f"{str(b['mode']):>12} {_fmt(b['V_divergence']):>20}")
    print(f"  {doc['explanation']}")
    return print_notes(doc)
