"""``casflutter lco``: the LCO branch of a problem from its flutter (Hopf) point.

Solves the periodic orbits of the nonlinear truth (or, with ``--rom``, the invariant circles
of the sampled-data loop of a saved HWL ROM with the problem's structure), continues them in
the speed, and prints (or writes as JSON) the Hopf point, its criticality, the branch with
its stability and the folds.  Speeds in the problem's unit (m/s for the wings and rig
sections, the speed index for the typical section).  No figure is written unless
``--figure PATH`` is given (checked before the work; its missing folders are created).
"""

from __future__ import annotations

from ..._outputs import check_figure_path, print_json, save_figure

__all__ = ["register", "run"]


def register(subparsers) -> None:
    """Add the ``lco`` sub-command."""
    p = subparsers.add_parser(
        "lco", help="LCO branch (bifurcation diagram) from the flutter point",
        description="Continue the limit cycles that leave the flutter (Hopf) point of a problem "
                    "in the speed: amplitude per mode and sensor, frequency, stability (Floquet "
                    "multipliers), folds, and whether the Hopf point is supercritical or "
                    "subcritical.  PROBLEM is a problem name (casflutter problems) or a rig TOML "
                    "file (kind = \"pitch_plunge\").  With --rom, the sampled-data loop of a "
                    "saved HWL ROM (the rom.npz of casflutter run) with the problem's structure "
                    "is analysed instead of the truth.  Speeds in the problem's unit.  No figure "
                    "is written unless --figure PATH is given.  Exit status 3: the continuation "
                    "failed part-way (the points up to the failure are reported).")
    p.add_argument("problem", help="problem name or rig TOML file")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="change a problem parameter (repeatable)")
    p.add_argument("--vrange", nargs=2, type=float, metavar=("LO", "HI"), default=None,
                   help="speed range in the problem's speed unit (default: the problem's [lco] "
                        "vrange, else its [rom] V_range)")
    p.add_argument("--rom", default=None, metavar="ROM.npz",
                   help="analyse the sampled-data loop of this saved HWL ROM (with the "
                        "problem's modes and sensor rows) instead of the truth")
    p.add_argument("--sensors", choices=("displacement", "acceleration"), default="displacement",
                   help="read the sensors as displacements (Hs u) or accelerations (Hs u'')")
    p.add_argument("--max-points", type=int, default=None, help="most branch points")
    p.add_argument("--figure", default=None, metavar="PATH",
                   help="write the bifurcation diagram to PATH (.png, .pdf, .svg ...; checked "
                        "before the work; 'none' or omitted: no figure)")
    p.add_argument("--json", action="store_true", help="write the result as JSON to stdout")
    p.set_defaults(func=run)


def _nonlinearity_hint(truth, problem: str) -> str:
    """How to give a problem with a polynomial pitch stiffness (``kappa1`` ... ``kappa4``, the
    typical section and rig sections) the cubic term that makes an LCO, when it has none."""
    params = getattr(truth, "params", None)
    kappas = [getattr(params, f"kappa{k}", None) for k in (1, 2, 3, 4)]
    if any(k is None for k in kappas) or any(kappas):
        return ""
    return (f"; {problem}'s pitch stiffness is linear (kappa1 = ... = kappa4 = 0): give it a "
            f"cubic restoring moment k(theta) theta = theta + kappa2 theta^3, e.g. casflutter "
            f"lco {problem} --set kappa2=3 (hardening: a supercritical branch of stable "
            "LCOs; kappa2 < 0 softening: subcritical)")


def _fmt_amp(amps: dict, names) -> str:
    return "  ".join(f"{amps[n]:10.4g}" for n in names)


def run(args) -> int:
    """Handler: compute the branch, print or write JSON, write the figure if asked."""
    from ...ident import HWLModel
    from ...lco import (LCOSettings, default_vrange, lco_branch, rom_lco_branch,
                        speed_convention)
    from ...truth import load_problem, problem_label
    from ...errors import ConfigError

    fig_path = None                  # figures only where asked, checked before the work
    if args.figure and args.figure.lower() != "none":
        fig_path = str(check_figure_path(args.figure, what="--figure"))
    truth = load_problem(args.problem, args.sets)
    label = problem_label(args.problem)
    scale, unit = speed_convention(truth)
    kw = {"sensor_kind": args.sensors}
    if args.max_points is not None:
        kw["max_points"] = args.max_points
    settings = LCOSettings(**kw)
    if args.vrange is not None:
        lo, hi = args.vrange
        vrange = (lo / scale, hi / scale)
    else:
        vrange = default_vrange(truth)
    if args.rom:
        try:
            rom = HWLModel.load(args.rom)
        except FileNotFoundError:
            raise ConfigError(f"--rom {args.rom}: the file does not exist") from None
        ms = truth.modal_structure()
        st = ms.with_sensors(kind="displacement")
        branch = rom_lco_branch(rom, st, vrange, settings, mode_names=ms.mode_names,
                                sensor_names=ms.sensor_names, problem=f"{label} (ROM loop)",
                                speed_scale=scale, speed_unit=unit, time_unit=ms.time_unit)
    else:
        try:
            branch = lco_branch(truth, vrange, settings, problem=label)
        except ConfigError as exc:
            if "degenerate" not in str(exc):
                raise
            raise ConfigError(f"{exc}{_nonlinearity_hint(truth, args.problem)}") from None
    doc = branch.to_dict()
    if fig_path:
        from ...report import plot_bifurcation
        import matplotlib.pyplot as plt

        fig = plot_bifurcation(branch)
        save_figure(fig, fig_path, dpi=110)
        plt.close(fig)
    doc["figure"] = fig_path
    if args.json:
        print_json(doc)
        return 0 if branch.completed else 3
    h = doc["hopf"]
    vunit = (doc["units"]["V"] if doc["units"]["V"] == "m/s"
             else f"(speed index {doc['units']['V']})")
    funit = "Hz" if branch.time_unit == "s" else f"cycles per time unit {branch.time_unit}"
    print(f"{label}: {doc['kind']} {'Neimark-Sacker' if branch.hopf.discrete else 'Hopf'} point "
          f"at V = {h['V']:.6g} {vunit}, {h['freq_hz']:.5g} {funit}")
    print(f"  first Lyapunov coefficient {h['lyapunov_coefficient']:.4g}; the branch leaves "
          f"towards {'higher' if h['branch_direction'] > 0 else 'lower'} speeds "
          f"({h['kind_from_branch']}; {'consistent' if h['consistent'] else 'INCONSISTENT'})")
    names = list(branch.outputs)
    print(f"  {'V':>10} {'freq':>9} {'stable':>6}  " + "  ".join(f"{n[:10]:>10}" for n in names))
    pts = branch.points
    step = max(1, len(pts) // 25)
    for i, p in enumerate(pts):
        if i % step and i != len(pts) - 1:
            continue
        print(f"  {branch.speed(p.V):10.5g} {p.freq_hz:9.5g} {'yes' if p.stable else 'no':>6}  "
              + _fmt_amp(p.amplitude, names))
    for f in branch.folds:
        print(f"  fold of cycles at V = {branch.speed(f.V):.6g} {doc['units']['V']}")
    stable = [p for p in pts if p.stable]
    if branch.kind == "subcritical" and stable:
        vmin = min(branch.speed(p.V) for p in stable)
        if vmin < h["V"]:
            print(f"  stable LCO from {vmin:.4g} {doc['units']['V']}, below the flutter speed "
                  f"{h['V']:.4g}: the LCO jumps in at flutter and persists down to the fold "
                  "(hysteresis)")
    print(f"  {'stopped' if branch.completed else 'FAILED'}: {branch.stop_reason}")
    if branch.settled is not None:
        print(f"  no stable cycle on this branch; {branch.settled.note}")
        pts = branch.settled.points
        step = max(1, len(pts) // 12)
        for i, p in enumerate(pts):
            if i % step == 0 or i == len(pts) - 1:
                print(f"  {branch.speed(p.V):10.5g} {p.freq_hz:9.5g} "
                      f"{'yes' if p.stable else 'no':>6}  " + _fmt_amp(p.amplitude, names))
        for f in branch.settled.folds:
            print(f"  fold of cycles at V = {branch.speed(f.V):.6g} {doc['units']['V']}")
    if fig_path:
        print(f"  bifurcation diagram: {fig_path}")
    return 0 if branch.completed else 3
