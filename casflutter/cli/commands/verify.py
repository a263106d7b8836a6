"""``casflutter verify PLANT.json CONTROLLER.json``: independent check of a controller.

Prints the :class:`casflutter.verify.VerificationReport` (or its JSON with ``--json``):
closed-loop poles, exact H∞ norm and peak frequency, and for an LFT in ΔV (``--vf``,
``--n-delta`` or the plant file's ``Vf``/``n_delta``) the small-gain and the exact
speed-index intervals (Lum et al. 2016, eq. 10-16).

The verdict is the exit code: 0 when the nominal closed loop is stable and, with
``--require-v LO HI``, stays stable over that whole speed-index range (the LFT's exact
stability interval covers it; no gain or phase margin is checked on this route, so the
verdict says "stable", never "robust"); 1 otherwise, the last line (``verdict`` in the JSON)
saying which check failed.  A file of a run's output folder other than ``plant.json`` and
``controller.json`` (its ``summary.json``, ``config.json``, ``manifest.json``) is refused
with the file to pass instead.  A plant family (the first file not a ``.json``) is
verified by :mod:`casflutter.cli._verify_family`, whose ``--require-v`` also requires the
``--margins`` thresholds.
The JSON is strict: a non-finite number (the γ of an unstable loop, an unbounded interval
end) is ``null``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ...errors import ConfigError
from .. import _verify_family

__all__ = ["register", "run", "verdict"]


def register(subparsers) -> None:
    """Add the ``verify`` sub-command."""
    p = subparsers.add_parser(
        "verify", help="verify a controller on a plant: poles, H-inf norm, V intervals",
        description="Independent check of a controller on a plant: closed-loop poles, exact "
                    "H-inf norm and peak frequency, small-gain and exact speed-index intervals "
                    "(Lum et al. 2016, eq. 10-16).")
    p.add_argument("plant", help="plant JSON (casflutter format or COMPleib keys "
                                 "A, B1, B, C1, D11, D12, C, D21, D22)")
    p.add_argument("controller", help="controller JSON with A, B, C, D (only D for a static "
                                      "gain)")
    p.add_argument("--nmeas", type=int, default=None,
                   help="number of measurements (last plant outputs); default from the file")
    p.add_argument("--ncon", type=int, default=None,
                   help="number of controls (last plant inputs); default from the file")
    p.add_argument("--vf", type=float, default=None,
                   help="nominal speed index Vf (eq. 10); default from the file")
    p.add_argument("--n-delta", type=int, default=None, dest="n_delta",
                   help="size of the ΔV channel (first inputs/outputs); default from the file")
    p.add_argument("--method", choices=("auto", "slycot", "scipy"), default="auto",
                   help="H-inf norm implementation (default: slycot if installed)")
    p.add_argument("--require-v", nargs=2, type=float, default=None, metavar=("LO", "HI"),
                   dest="require_v",
                   help="speed range to require; not met -> exit code 1.  A .json plant "
                        "(LFT): the loop must stay stable over the speed indices [LO, HI] "
                        "(the exact interval, eq. 10-15, covers them; stability only, no "
                        "margins).  A plant family, in its speed unit: the certified stable "
                        "interval must cover [LO, HI], and the --margins thresholds (with "
                        "--disk the disk margins too) must hold from the start of the "
                        "verified range (--range, default the family's) up to HI")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    _verify_family.add_arguments(p)
    p.set_defaults(func=run)


def verdict(report, require_v=None) -> dict:
    """The pass/fail verdict of a :class:`~casflutter.verify.VerificationReport`.

    Parameters
    ----------
    report : VerificationReport
    require_v : (float, float), optional
        Speed-index range that the LFT's exact stability interval must cover (stability
        only: no margins are checked on a single plant).

    Returns
    -------
    dict
        ``stable``; ``required_V``; ``stable_over_required`` (the exact interval covers
        ``require_v``; ``None`` without it: not asked) and ``robust``, the same value under
        its older name (it asks no margins); ``small_gain_covers`` (whether the paper's
        small-gain interval alone certifies the range); ``passed``; ``reason`` (one
        sentence saying which test certified what).
    """
    out = {"stable": bool(report.stable), "required_V": None, "stable_over_required": None,
           "robust": None, "small_gain_covers": None}
    if require_v is not None:
        lo, hi = (float(x) for x in require_v)
        out["required_V"] = [lo, hi]
        ex = report.exact_V
        covered = bool(report.stable and ex is not None
                       and (ex[0] < lo or ex[0] == 0.0) and hi < ex[1])
        out["stable_over_required"] = out["robust"] = covered
        sg = report.small_gain_V
        out["small_gain_covers"] = bool(report.stable and sg is not None
                                        and (sg[0] < lo or sg[0] == 0.0) and hi < sg[1])
    if not report.stable and report.spectral_abscissa < 0:
        import numpy as np

        from ...verify._common import rounding_margin

        A = np.asarray(report.closed_loop.A)
        reason = (f"not stable: the slowest closed-loop pole (real part "
                  f"{report.spectral_abscissa:.6g}) lies within rounding, "
                  f"{rounding_margin(A):.3g} = 100 eps ||A_cl||, of the imaginary axis: with "
                  f"||A_cl|| = {np.linalg.norm(A):.3g} it cannot be told from a pole on the "
                  "axis (the controller's gains are far too large for the plant)")
    elif not report.stable:
        reason = (f"not stable: the nominal closed loop has a pole with real part "
                  f"{report.spectral_abscissa:.6g} >= 0")
    elif out["stable_over_required"] is False:
        ex, (lo, hi) = report.exact_V, out["required_V"]
        reason = (f"not stable over the required V in [{lo:.6g}, {hi:.6g}]: "
                  + ("the LFT's exact stability interval could not be computed"
                     if ex is None else
                     f"the LFT's exact stability interval (eq. 10-15) is only "
                     f"({ex[0]:.6g}, {ex[1]:.6g})"))
    elif out["stable_over_required"]:
        ex, sg, (lo, hi) = report.exact_V, report.small_gain_V, out["required_V"]
        reason = (f"stable at every V in [{lo:.6g}, {hi:.6g}]: the LFT's exact stability "
                  f"interval (eq. 10-15) ({ex[0]:.6g}, {ex[1]:.6g}) covers it, "
                  + ("and so does the small-gain interval (eq. 16)" if out["small_gain_covers"]
                     else "the small-gain interval (eq. 16)"
                     + ("" if sg is None else f" ({sg[0]:.6g}, {sg[1]:.6g})")
                     + " alone does not")
                  + "; stability only: no gain or phase margins are checked on a single "
                  "plant (casflutter verify FAMILY CONTROLLER --require-v checks them)")
    else:
        reason = "stable (no speed range required: pass --require-v LO HI to check one)"
    out["passed"] = bool(report.stable and out["robust"] is not False)
    out["reason"] = reason
    return out


def _strict(obj):
    """Non-finite floats to None, recursively (strict JSON)."""
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _peek(path: str) -> dict:
    """The JSON object of a file, or ``{}`` when it is not one (the loaders then say why)."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


#: keys only a plant file has (the partition, the ΔV channel, COMPleib's blocks)
_PLANT_KEYS = {"nmeas", "ncon", "n_delta", "Vf", "B1", "C1", "D11"}


#: a run's output files that are neither plant nor controller: what marks each
_RUN_FILES = {"summary.json": lambda d: {"route", "timings_s", "flutter"} <= set(d),
              "config.json": lambda d: {"problem", "data", "rom", "flutter"} <= set(d),
              "manifest.json": lambda d: str(d.get("format", "")).startswith(
                  "casflutter-output-manifest")}


def _check_run_file(path: str, doc: dict, role: str) -> None:
    """Refuse a run's ``summary.json``, ``config.json`` or ``manifest.json`` given as PLANT
    or CONTROLLER, naming the file of the same output folder to pass instead."""
    kind = next((name for name, marks in _RUN_FILES.items() if doc and marks(doc)), None)
    if kind is None:
        return
    folder = Path(path).parent
    plant, controller = folder / "plant.json", folder / "controller.json"
    head = (f"{role} {path} is the {kind} of a casflutter run (its output folder), not a "
            f"{role.lower()} file")
    if role == "CONTROLLER":
        if controller.is_file():
            raise ConfigError(f"{head}: pass {controller}, the controller the run wrote "
                              "beside it")
        raise ConfigError(f"{head}: a run writes controller.json only with its 'controller' "
                          f"stage, and {folder} has none")
    if plant.is_file():
        raise ConfigError(f"{head}: pass {plant}, the plant the run verified its controller "
                          f"on (the LFT at Vf): casflutter verify {plant} {controller}")
    problem = doc.get("problem")
    problem = problem.get("name") if isinstance(problem, dict) else problem
    route = doc.get("route")
    if route == "family" or (kind != "summary.json" and isinstance(problem, str)):
        raise ConfigError(f"{head}, and {folder} has no plant.json (a run writes it only "
                          "with a controller on a ROM loop): pass the run's problem, "
                          f"casflutter verify {problem} {controller} (a plant family is "
                          "verified over its speed range)")
    raise ConfigError(f"{head}, and {folder} has no plant.json: a run writes plant.json "
                      "(the LFT at Vf) beside controller.json only when its 'controller' "
                      "stage ran on a ROM loop with a flutter speed; pass such a run's "
                      "plant.json")


def _check_order(plant: str, controller: str, pdoc: dict, kdoc: dict) -> None:
    """Refuse a controller file given as PLANT (the two files swapped, or twice the same
    kind), before any work."""
    p_is_k = pdoc.get("format") == "casflutter-controller/1" or (
        pdoc and not _PLANT_KEYS & set(pdoc) and _PLANT_KEYS & set(kdoc))
    k_is_p = kdoc.get("format") == "casflutter-plant/1" or bool(_PLANT_KEYS & set(kdoc))
    if p_is_k and k_is_p:
        raise ConfigError(f"the two files look swapped: {plant} is a controller file and "
                          f"{controller} a plant file; give the plant first: casflutter "
                          f"verify {controller} {plant}")
    if p_is_k:
        what = pdoc.get("format") or "no partition nmeas/ncon"
        raise ConfigError(f"PLANT {plant} is a controller file ({what}); give the plant file "
                          "first (casflutter run writes plant.json beside controller.json)")


def _speed_scale(pdoc: dict) -> float | None:
    """Airspeed [m/s] per speed index from a plant file written by ``casflutter run``
    (its ``Vf_speeds``), else ``None``."""
    v = pdoc.get("Vf_speeds")
    if isinstance(v, dict):
        V, U = v.get("speed_index"), v.get("airspeed_m_s")
        if isinstance(V, (int, float)) and isinstance(U, (int, float)) and V > 0:
            return float(U) / float(V)
    return None


def run(args) -> int:
    """Handler of ``casflutter verify``: 0 when the verdict passes, 1 when the loop is not
    stable or not robust over ``--require-v``."""
    if _verify_family.is_family(args.plant):
        return _verify_family.run(args)
    given = [option for option, used in (
        ("--range", args.speed_range is not None), ("--disk", args.disk),
        ("--servo", args.servo is not None), ("--figure", args.figure is not None),
        ("--margins", tuple(args.margins) != (6.0, 45.0))) if used]
    if given:
        raise ConfigError(f"{', '.join(given)} belong to a plant family (FAMILY.toml, a "
                          f"family folder or problem name, a ROM loop .npz); {args.plant} is "
                          "a single LFT plant, verified at its nominal speed with the exact "
                          "speed interval of eq. 10-15: drop them")
    from ...verify import load_controller, load_plant, verify_controller

    pdoc, kdoc = _peek(args.plant), _peek(args.controller)
    _check_run_file(args.plant, pdoc, "PLANT")
    _check_run_file(args.controller, kdoc, "CONTROLLER")
    _check_order(args.plant, args.controller, pdoc, kdoc)
    plant = load_plant(args.plant)
    K = load_controller(args.controller)
    nmeas = args.nmeas if args.nmeas is not None else plant.nmeas
    ncon = args.ncon if args.ncon is not None else plant.ncon
    if nmeas is None or ncon is None:
        raise ConfigError(f"{args.plant} does not say how many measurements/controls the "
                          "plant has; pass --nmeas N --ncon N")
    Vf = args.vf if args.vf is not None else plant.Vf
    n_delta = args.n_delta if args.n_delta is not None else plant.n_delta
    if Vf is None or n_delta is None:
        if Vf is not None or n_delta is not None:
            raise ConfigError("the ΔV intervals need both Vf and n_delta: pass --vf and "
                              "--n-delta (or put Vf and n_delta in the plant file)")
    if Vf is not None and not (math.isfinite(Vf) and Vf >= 0):
        raise ConfigError(f"--vf {Vf!r}: the nominal speed index must be a finite number >= 0")
    if args.require_v is not None:
        lo, hi = args.require_v
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
            raise ConfigError(f"--require-v {lo!r} {hi!r}: give two finite speed indices "
                              "0 <= LO <= HI")
        if Vf is None:
            raise ConfigError("--require-v needs the ΔV channel: pass --vf and --n-delta (or "
                              "put Vf and n_delta in the plant file)")
    report = verify_controller(plant.sys, K, nmeas, ncon, Vf=Vf, n_delta=n_delta,
                               method=args.method)
    v = verdict(report, args.require_v)
    if args.json:
        doc = _strict({**report.to_dict(), "verdict": v})
        print(json.dumps(doc, indent=1, allow_nan=False))
    else:
        print(report.format(speed_scale=_speed_scale(pdoc)))
        print(f"  verdict: {'PASSED' if v['passed'] else 'FAILED'}, {v['reason']}")
    return 0 if v["passed"] else 1
