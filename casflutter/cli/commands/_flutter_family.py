"""``casflutter flutter FAMILY.toml``: every open-loop crossing of a gridded plant family.

The route of :mod:`.flutter` for a problem file ``kind = "plant_family"``: the family is
loaded (:func:`casflutter.aeroelastic.load_family`), its crossings found by
:func:`casflutter.aeroelastic.family_flutter` on the grid's own speeds (interpolated between
them, each located to 1e-10 of the speed), printed in the family's units or written as JSON
(key ``flutter``: every crossing, lowest speed first), and, with ``--figure``, the V–g / V–f
figure drawn by :func:`casflutter.report.plot_family_vg_vf`.
"""

from __future__ import annotations

import math
import time

from ..._outputs import print_json, save_figure

__all__ = ["print_notes", "run_family", "summarize_family"]


def summarize_family(family, result, problem: str, *, seconds: float | None = None) -> dict:
    """The JSON document of ``casflutter flutter`` on a plant family.

    Parameters
    ----------
    family : PlantFamily
        The family (its name, units and description).
    result : FlutterResult
        :func:`casflutter.aeroelastic.family_flutter` of it.
    problem : str
        The problem's label.
    seconds : float, optional
        Wall time of the search.

    Returns
    -------
    dict
        ``flutter``: every crossing ``{speed, omega_rad_s, freq_hz, branch, kind,
        direction}``, lowest speed first (frequencies in rad and cycles per the family's
        time unit); ``flutter_speed`` / ``flutter_omega_rad_s`` / ``flutter_freq_hz``: the
        first destabilizing flutter crossing (``None`` without one); units, the speed range
        searched, the family's description and warnings.
    """
    tr = result.tracking
    tu = family.time_unit
    crossings = [{"speed": c.V, "omega_rad_s": c.omega, "freq_hz": c.frequency_hz,
                  "branch": int(c.branch), "kind": c.kind, "direction": c.direction,
                  "converged": bool(c.converged)} for c in result.crossings]
    warnings = []
    if result.unstable_at_start:
        warnings.append(f"unstable already at {tr.V[0]:g} {family.speed_unit} (spectral "
                        f"abscissa {result.spectral_abscissa_start:.3g}): crossings are not "
                        "instability onsets")
    if tr.n_unresolved or any(not c["converged"] for c in crossings):
        warnings.append(result.message)
    return {
        "problem": problem, "kind": "plant_family", "family": family.describe(),
        "status": result.status,
        "flutter": crossings,
        "flutter_speed": result.Vf, "flutter_omega_rad_s": result.omega_f,
        "flutter_freq_hz": result.frequency_hz,
        "unstable_at_start": bool(result.unstable_at_start),
        "speed_range": [float(tr.V[0]), float(tr.V[-1])],
        "speeds_evaluated": int(tr.V.size), "bisections": int(tr.n_refined),
        "speed_unit": family.speed_unit, "time_unit": tu,
        "units": {"speed": family.speed_unit, "omega_rad_s": f"rad/{tu}",
                  "freq_hz": "Hz" if tu == "s" else f"1/{tu}"},
        "timings": {"flutter": seconds},
        "warnings": warnings,
    }


def _fmt(x, spec: str = ".6g") -> str:
    return "none" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def run_family(args, record, label: str, fig_path) -> int:
    """Handler of ``casflutter flutter`` for a plant-family file.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments (``--vrange`` restricts the search; the ROM options do not
        apply and are refused).
    record : casflutter.data.FamilyFile
        The file, as :func:`casflutter.truth.load_problem` read it.
    label : str
        The problem's label.
    fig_path : str or None
        Where to save the V–g / V–f figure (checked already).

    Returns
    -------
    int
        0.
    """
    from ...aeroelastic import family_flutter, load_family
    from ...errors import ConfigError

    where = record.path if record.path is not None else label
    for flag, given in (("--v0", args.v0 is not None), ("--convective", args.convective),
                        ("--no-parametric", args.no_parametric), ("--set", bool(args.sets))):
        if given:
            raise ConfigError(f"{flag} does not apply to the plant family {where}: it is a "
                              "grid of linear models, with no ROM to identify or parameter "
                              "to change")
    family = load_family(record)
    speeds = None
    if args.vrange is not None:
        lo, hi = (family.check_speed(v, "--vrange") for v in args.vrange)
        if not lo < hi:
            raise ConfigError(f"--vrange {lo:g} {hi:g}: give LO < HI ({family.speed_unit})")
        speeds = family.speed_grid(2, lo, hi)
    t0 = time.perf_counter()
    result = family_flutter(family, speeds=speeds)
    doc = summarize_family(family, result, label, seconds=time.perf_counter() - t0)
    doc["figure"] = fig_path
    if fig_path is not None:
        import matplotlib.pyplot as plt

        from ...report import plot_family_vg_vf

        fig = plot_family_vg_vf(result, family)
        save_figure(fig, fig_path, dpi=110)
        plt.close(fig)
    if args.json:
        print_json(doc)
        return 0
    u = doc["units"]
    lo, hi = doc["speed_range"]
    print(f"{label}: open-loop crossings for speeds in [{lo:g}, {hi:g}] {u['speed']} "
          f"({family.n_states} states, {doc['speeds_evaluated']} speeds evaluated)")
    if not doc["flutter"]:
        print("  none: no eigenvalue crosses the imaginary axis in the range")
    else:
        print(f"  {'speed [' + u['speed'] + ']':>16} {'omega [' + u['omega_rad_s'] + ']':>16} "
              f"{'freq [' + u['freq_hz'] + ']':>12} {'branch':>7}  kind")
        for c in doc["flutter"]:
            print(f"  {c['speed']:16.8g} {c['omega_rad_s']:16.6g} {c['freq_hz']:12.5g} "
                  f"{c['branch']:7d}  {c['kind']}, {c['direction']}")
    print(f"  flutter speed: {_fmt(doc['flutter_speed'], '.6g')} {u['speed']}, "
          f"{_fmt(doc['flutter_freq_hz'], '.4g')} {u['freq_hz']}")
    return print_notes(doc)


def print_notes(doc: dict) -> int:
    """Print the warnings of a ``casflutter flutter`` document and its figure's path (the
    lines under every route's table); return the handler's exit code, 0."""
    for w in doc["warnings"]:
        print(f"  warning: {w}")
    if doc["figure"]:
        print(f"  V-g/V-f figure: {doc['figure']}")
    return 0
