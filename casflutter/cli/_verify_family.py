"""``casflutter verify FAMILY CONTROLLER``: a controller on a plant family over a speed range.

The first file says what is verified: a ``.json`` plant is the single-speed LFT route of
:mod:`casflutter.cli.commands.verify`; anything else is a plant family:

* a family file (TOML ``kind = "plant_family"``, a folder holding one, or a problem name
  such as ``goland_4flaps``: :func:`casflutter.aeroelastic.load_family`);
* a ROM loop kept in an ``.npz`` (:func:`casflutter.aeroelastic.load_rom_loop`, the frozen
  loop of eq. 8, e.g. ``problems/seed_wing_rom/rom_loop_seed0.npz``), with ``--servo OMEGA`` for
  the flap behind a second-order servo (damping 0.7), in its speed index.

It prints (or writes as JSON with ``--json``) what :func:`casflutter.verify.verify_family`
finds: ``stable_interval`` (certified), ``absolute_flutter_speed``, ``robust_flutter_speed``
(``--margins GM_DB PM_DEG``, default 6 dB / 45°; ``--disk`` adds the multi-loop disk
margins), the margins per loop and per speed at the plant inputs and outputs, and the
closed-loop crossings, in the family's units.  ``--figure PATH`` saves the margins and the
closed-loop damping against the speed (its missing folders are created).

The verdict is the exit code: 1 when the closed loop is not stable just above the range's
start, or, with ``--require-v LO HI``, when the certified stable interval does not cover
``[LO, HI]`` or a margin falls below its threshold (``--margins``, and with ``--disk`` the
disk margins) at a speed below HI: the robust flutter speed, counted from the start of the
verified range (``--range``, default the family's), must be above HI.  The last line
(``verdict`` in the JSON) says which.
"""

from __future__ import annotations

import math
from pathlib import Path

from .._outputs import check_figure_path, print_json, save_figure
from ..errors import ConfigError

__all__ = ["add_arguments", "is_family", "load_plant_family", "run", "verify_command",
           "verdict"]

#: options of the single-plant route that a family does not take
_LFT_ONLY = ("nmeas", "ncon", "vf", "n_delta")


def add_arguments(parser) -> None:
    """The family route's options of ``casflutter verify``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The ``verify`` sub-parser.
    """
    g = parser.add_argument_group(
        "plant family (FAMILY.toml, a family folder or problem name, or a ROM loop .npz)")
    g.add_argument("--range", nargs=2, type=float, default=None, metavar=("LO", "HI"),
                   dest="speed_range",
                   help="speed range to verify, in the family's unit (default: the family's; "
                        "needed for a loop family, whose speeds are unbounded)")
    g.add_argument("--margins", nargs=2, type=float, default=(6.0, 45.0),
                   metavar=("GM_DB", "PM_DEG"),
                   help="gain (dB) and phase (deg) margin thresholds of the robust flutter "
                        "speed (default 6 45)")
    g.add_argument("--disk", action="store_true",
                   help="also hold the multi-loop disk margins (inputs and outputs) to the "
                        "thresholds (slower)")
    g.add_argument("--servo", type=float, default=None, metavar="OMEGA",
                   help="ROM loop .npz only: the flap behind a second-order servo of this "
                        "natural frequency (rad per time unit, damping 0.7)")
    g.add_argument("--figure", default=None, metavar="PATH",
                   help="save the margins and closed-loop damping against the speed "
                        "(.png, .pdf, .svg ...; checked before the work)")


def is_family(path: str) -> bool:
    """True unless ``path`` is a ``.json`` plant (the single-plant LFT route).

    Parameters
    ----------
    path : str
        The first file of ``casflutter verify``.

    Returns
    -------
    bool
    """
    return Path(path).suffix.lower() != ".json"


def load_plant_family(source: str, servo: float | None = None):
    """The plant family a command-line argument names (module docstring).

    Parameters
    ----------
    source : str
        A ROM loop ``.npz``, or a family file / folder / problem name.
    servo : float, optional
        Servo natural frequency for a ROM loop.

    Returns
    -------
    casflutter.aeroelastic.PlantFamily

    Raises
    ------
    ConfigError
        ``--servo`` with a family file.
    DataError
        A file that cannot be read.
    """
    from ..aeroelastic import load_family, load_rom_loop

    if Path(source).suffix.lower() == ".npz":
        system, _ = load_rom_loop(source)
        return system if servo is None else system.with_servo(float(servo))
    if servo is not None:
        raise ConfigError(f"--servo is for a ROM loop kept in an .npz; {source} is a family "
                          "file, whose plant already holds its actuators")
    return load_family(source)


def verdict(result, require_v=None) -> dict:
    """The pass/fail verdict of a :class:`~casflutter.verify.FamilyVerification`.

    Parameters
    ----------
    result : FamilyVerification
    require_v : (float, float), optional
        Speeds ``(LO, HI)`` the certified interval must cover; the margins must hold their
        thresholds from the verified range's start up to HI (the robust flutter speed above
        HI, :meth:`~casflutter.verify.FamilyVerification.robust_over`).

    Returns
    -------
    dict
        ``required_V``, ``covered`` and ``robust`` (``None`` without ``require_v``),
        ``passed`` and ``reason`` (one sentence).
    """
    u = result.speed_unit
    out = {"required_V": None, "covered": None, "robust": None}
    if result.stable_interval is None:
        out.update(passed=False, reason="not stable: the closed loop is not stable just above "
                                        "the range's start")
        return out
    if require_v is None:
        out.update(passed=True, reason="stable at the range's start (no speed range required: "
                                       "pass --require-v LO HI to check one)")
        return out
    lo, hi = (float(x) for x in require_v)
    out["required_V"] = [lo, hi]
    out["covered"] = result.covers(lo, hi)
    out["robust"] = result.robust_over(lo, hi)
    lb, ub = result.stable_interval
    if not out["covered"]:
        iv = result.interval
        where = (f"{'[' if iv.stable_at_start else '('}{lb:.6g}, {ub:.6g}"
                 f"{']' if iv.holds_range else ')'} {u}")
        why = ("" if result.absolute_flutter_speed is None else
               f" (absolute flutter speed {result.absolute_flutter_speed:.6g} {u})")
        reason = (f"not covered: certified stable only on {where}{why}, which does not cover "
                  f"the required [{lo:.6g}, {hi:.6g}]")
    elif not out["robust"]:
        rfs = result.robust_flutter_speed
        below = (f"not robust: margins below {result.gain_margin_db:g} dB / "
                 f"{result.phase_margin_deg:g} deg from {rfs:.6g} {u}")
        if rfs >= lo:
            reason = (f"{below}, inside the required [{lo:.6g}, {hi:.6g}] "
                      f"({result.robust_reason})")
        else:   # the margins are held from the verified range's start, not from LO
            reason = (f"{below} ({result.robust_reason}), below the required [{lo:.6g}, "
                      f"{hi:.6g}]: the margins must hold from the verified range's start, "
                      f"{result.speed_range[0]:.6g} {u}, up to {hi:.6g}")
    else:
        reason = (f"certified stable and robust over [{lo:.6g}, {hi:.6g}] {u}")
    out.update(passed=bool(out["covered"] and out["robust"]), reason=reason)
    return out


def _check_range(family, speed_range=None) -> tuple[float, float]:
    """The speeds ``--range`` asks to verify, checked before any work.

    The library's own checks (:func:`casflutter.verify.verify_family`) name its keyword
    ``speed_range``; these name the option.

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The family.
    speed_range : (float, float), optional
        ``--range LO HI`` (default: the family's own range).

    Returns
    -------
    (float, float)
        The range verified.

    Raises
    ------
    ConfigError
        ``--range`` is not two finite speeds ``LO < HI`` inside the family's range
        (:meth:`~casflutter.aeroelastic.PlantFamily.check_speed`), or it is not given and
        the family's range is unbounded (a loop family).
    """
    u = family.speed_unit
    if speed_range is None:
        lo, hi = (float(v) for v in family.speed_range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ConfigError(f"{family.name}: its speed range [{lo:g}, {hi:g}] {u} is not a "
                              "finite interval; pass --range LO HI (the speeds to verify)")
        return lo, hi
    lo, hi = (float(v) for v in speed_range)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ConfigError(f"--range {lo:g} {hi:g}: give two finite speeds LO < HI ({u})")
    if not lo < hi:
        fix = f"--range {hi:g} {lo:g}" if hi < lo else "two different speeds"
        raise ConfigError(f"--range {lo:g} {hi:g}: LO must be below HI; give {fix}")
    return family.check_speed(lo, "--range LO"), family.check_speed(hi, "--range HI")


def verify_command(family, controller, *, speed_range=None, require_v=None,
                   margins=(6.0, 45.0), disk: bool = False, figure=None,
                   json_out: bool = False) -> int:
    """Verify, print and return the exit code (the testable body of :func:`run`).

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The family.
    controller : str, path-like or dict
        The controller file (or document).
    speed_range, require_v : (float, float), optional
        The range verified and the one required.
    margins : (float, float)
        Thresholds (dB, degrees).
    disk : bool
        Multi-loop disk margins too.
    figure : str, optional
        Where to save the figure.
    json_out : bool
        JSON on stdout instead of text.

    Returns
    -------
    int
        0 when the verdict passes, 1 otherwise.
    """
    from ..verify import verify_family

    if figure is not None:
        check_figure_path(figure)
    rng = _check_range(family, speed_range)
    if require_v is not None:
        lo, hi = require_v
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ConfigError(f"--require-v {lo!r} {hi!r}: give two finite speeds LO <= HI")
        if lo < rng[0] or hi > rng[1]:
            raise ConfigError(f"--require-v [{lo:g}, {hi:g}] reaches outside the speeds "
                              f"verified [{rng[0]:g}, {rng[1]:g}] {family.speed_unit}; "
                              "widen --range")
    result = verify_family(family, controller, speed_range=speed_range, margins=margins,
                           disk=disk)
    v = verdict(result, require_v)
    if figure is not None:
        import matplotlib.pyplot as plt

        from ..report import plot_family_verification

        fig = plot_family_verification(result)
        save_figure(fig, figure, dpi=120)
        plt.close(fig)
    if json_out:
        print_json({**result.to_dict(), "verdict": v})
    else:
        print(result.format())
        print(f"  verdict: {'PASSED' if v['passed'] else 'FAILED'}, {v['reason']}")
    return 0 if v["passed"] else 1


def run(args) -> int:
    """Handler of ``casflutter verify FAMILY CONTROLLER``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit code (:func:`verify_command`).
    """
    given = [f"--{k.replace('_', '-')}" for k in _LFT_ONLY if getattr(args, k, None) is not None]
    if given:
        raise ConfigError(f"{', '.join(given)} belong to a single LFT plant (.json); a plant "
                          "family names its own controls and measurements")
    family = load_plant_family(args.plant, args.servo)
    return verify_command(family, args.controller, speed_range=args.speed_range,
                          require_v=args.require_v, margins=tuple(args.margins),
                          disk=args.disk, figure=args.figure, json_out=args.json)
