"""``casflutter bench interval``: how far one controller holds the seed wing's ROM loop stable.

The question of issue-size: can a single linear controller keep ΣAE(V) (eq. 8-9) stable over
the paper's interval V ∈ (0.05, 2.4)?  Two continuations bracket the answer
(:func:`casflutter.design.stabilize_interval`):

* from the low end: the paper's design at Vf of each ``--orders`` (the run configuration's
  controller settings), its upper end pushed towards the target;
* from the high end (``--full-order``): an LQG controller of the loop's own order designed at
  the target's upper end, its lower end pushed down;
* random starts of a given order (``--random-orders``): ``--random-starts`` seeded random
  controllers of each order at each end of ``--random-ends``
  (:func:`casflutter.design.search_random_starts`), the one that reaches farthest recorded
  with the far ends of all that held their anchor (``--random-stable``: controllers that are
  stable themselves).  From both ends this brackets what one controller of that order
  holds, and whether two, one from each end, overlap (the summary's ``by_order``).

Every controller's exact stable interval is then certified by the independent verification
layer (:func:`casflutter.verify.verify_controller`, guardian map on the LFT at Vf).  Every
run's record holds its controller (:func:`casflutter.verify.controller_from_json` reads
``runs[i]["controller"]``).

``--start FILE`` (repeatable) continues a saved controller (a verification-layer JSON,
``v = K zm``) from the low end as well: whether a controller that holds one model, e.g. the
wing, can be carried over the interval on another (a start that does not hold this model's
low end is recorded with the reason).  ``--servo W`` puts the ROM loop's flap
behind the servo (:class:`casflutter.aeroelastic.ServoSystem`) for the continuations and their
certificates, as on the wing; the paper's design at Vf stays the LFT's (eq. 14-16), and the
loop with the servo is certified by :func:`casflutter.verify.speed_family_interval`.

With ``--model truth`` the same question is asked of the wing itself: the truth's own
full-order linearisation with the flap behind a servo (:class:`casflutter.aeroelastic.TruthLoop`),
continued from the high end by a full-order LQG start and from the low end by ``--orders``
controllers (balanced truncations of the high-end result), each certified on the truth by
:func:`casflutter.verify.speed_family_interval` (guardian map of the loop, quadratic in V).  The JSON
also lists, per accelerometer channel, the speeds at which a complex zero pair of
``v → zm_j`` crosses into the right half-plane near the flutter frequency, and the flutter
mode's grip (``flutter_mode_grip``: how far its residues in the flap-to-sensor loop turn over
the interval and, where the mode is unstable, the speed of the flap's weakest grip): the plant
properties the continuations stall at.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg

__all__ = ["register"]

_log = logging.getLogger(__name__)


def _rhp_zero_crossings(system, lo: float, hi: float, band: tuple[float, float],
                        n: int = 236) -> list[dict[str, Any]]:
    """Speeds where a complex zero pair of ``v → zm_j`` with frequency in ``band`` enters the
    right half-plane, per sensor ``j`` (zeros: finite generalised eigenvalues of the
    Rosenbrock pencil)."""
    out: list[dict[str, Any]] = []
    grid = np.linspace(lo, hi, n)
    m = system.loop(lo).C2.shape[0]
    for j in range(m):
        prev = None
        for V in grid:
            lp = system.loop(float(V))
            N = lp.A.shape[0]
            M = np.block([[lp.A, lp.B2[:, None]], [lp.C2[j:j + 1], lp.D22[j:j + 1, None]]])
            E = np.zeros_like(M)
            E[:N, :N] = np.eye(N)
            z = scipy.linalg.eigvals(M, E)
            z = z[np.isfinite(z)]
            inband = z[(z.imag > band[0]) & (z.imag < band[1]) & (z.real > 0)]
            if prev is not None and inband.size > prev:
                zz = inband[np.argmin(inband.real)]
                out.append({"sensor": j, "V": float(V), "zero": [float(zz.real),
                                                                 float(zz.imag)]})
            prev = inband.size
    return out


def _flutter_mode_grip(family, lo: float, hi: float, n: int = 120) -> dict[str, Any]:
    """The flutter mode's residues over ``[lo, hi]`` (:func:`casflutter.aeroelastic.mode_residues`):
    how far they turn and, where the mode is unstable, the speed of the flap's weakest grip."""
    from ...aeroelastic import mode_residues  # noqa: PLC0415

    res = mode_residues(family, np.linspace(lo, hi, n))
    grip = res.grip
    rec: dict[str, Any] = {"phase_swing_deg": res.phase_swing_deg.tolist(),
                           "worst_overlap": res.worst_overlap,
                           "eigenvalue_at_hi": [float(res.eigenvalue[-1].real),
                                                float(res.eigenvalue[-1].imag)]}
    k = res.weakest_index(unstable_only=True)
    if k is not None:
        onset = int(np.flatnonzero(res.eigenvalue.real > 0)[0])
        rec.update({"weakest_unstable_V": float(res.V[k]),
                    "growth_rate_there": float(res.eigenvalue[k].real),
                    "frequency_there": float(res.eigenvalue[k].imag),
                    "grip_there": float(grip[k]), "grip_at_onset": float(grip[onset])})
    return rec


def _verified(system, nominal: float, K) -> dict[str, Any]:
    """The verification layer's exact stable interval of ΣAE(V) closed by ``K``, on the LFT
    built at ``nominal`` (eq. 10-15 hold around any nominal speed, not only Vf)."""
    from ...aeroelastic import build_lft  # noqa: PLC0415
    from ...verify import verify_controller  # noqa: PLC0415

    lft = build_lft(system, nominal)
    ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=nominal, n_delta=lft.n_delta)
    ex = ver.exact_V
    return {"nominal": nominal, "stable_at_nominal": bool(ver.stable),
            "gamma": float(ver.gamma) if np.isfinite(ver.gamma) else None,
            "exact_interval": [float(ex[0]), float(ex[1])] if ex is not None else None}


def _verified_family(family, nominal: float, K) -> dict[str, Any]:
    """The verification layer's exact stable interval of a loop family that is polynomial in
    V (a truth's linearisation), python-control closing the loop."""
    from ...verify import speed_family_interval  # noqa: PLC0415

    r = speed_family_interval(lambda V: family.loop(V).flap_to_sensors(), K, nominal)
    return {"nominal": nominal, "stable_at_nominal": True, "gamma": None,
            "exact_interval": [float(r.lower), float(r.upper)]}


def _add_run(doc, write, label: str, kind: str, order: int, reach, verified: dict,
             t0: float, **extra) -> None:
    """Record one continuation (with its certified interval), report it and rewrite the JSON."""
    rec = _reach_record(kind, order, reach, verified, time.perf_counter() - t0)
    rec.update(extra)
    doc["runs"].append(rec)
    print(f"{label}: reached {reach.reached}, verified {rec['verified_exact_interval']}",
          file=sys.stderr, flush=True)
    write()


def _add_failed(doc, write, kind: str, order: int, anchor: str, error: str, t0: float,
                **extra) -> None:
    """Record a continuation that could not start (``reached`` None: the summary skips it)."""
    doc["runs"].append({"start": kind, "order": order, "anchor": anchor, "reached": None,
                        "met": False, "error": error, **extra,
                        "wall_time_s": time.perf_counter() - t0})
    write()


def _continue(family, K, lo: float, hi: float, anchor: str, label: str, kind: str,
              certify, doc, write, t0: float | None = None, **extra):
    """Continue ``K`` from its ``anchor`` end towards the other and record the reach with the
    verification layer's certificate (``certify(reach)``); a ``K`` that does not hold that end
    is recorded with the reason instead (``reached`` None).  Returns the reach or None."""
    from ...design import stabilize_interval  # noqa: PLC0415
    from ...errors import ConfigError  # noqa: PLC0415

    t0 = time.perf_counter() if t0 is None else t0
    try:
        reach = stabilize_interval(family, K, (lo, hi), anchor=anchor)
    except ConfigError as exc:     # it does not hold this end of the model
        _log.warning("%s: %s", label, exc)
        _add_failed(doc, write, kind, K.nstates, anchor, str(exc), t0, **extra)
        return None
    _add_run(doc, write, label, kind, K.nstates, reach, certify(reach), t0, **extra)
    return reach


def _from_high_end(family, lo: float, hi: float, label: str, kind: str, certify, doc, write):
    """An LQG controller of the loop's own order at ``hi``, its lower end pushed to ``lo``."""
    from ...design import full_order_start  # noqa: PLC0415

    t0 = time.perf_counter()
    K0 = full_order_start(family, hi)
    return _continue(family, K0, lo, hi, "high", f"{label}, full order {K0.nstates} from the "
                     "high end", kind, certify, doc, write, t0)


def _midpoint(verify):
    """``verify(nominal, K)`` as a certificate of a reach, built at its interval's midpoint."""
    return lambda reach: verify(0.5 * sum(reach.reached), reach.controller)


def _start_runs(family, lo: float, hi: float, starts, verify, doc, write) -> None:
    """Each saved controller of ``starts`` (path, controller) continued from the low end."""
    for path, K in starts:
        _continue(family, K, lo, hi, "low", f"{path}, order {K.nstates} from the low end",
                  f"file {path}", _midpoint(verify), doc, write)


def _random_runs(family, lo: float, hi: float, orders, ends, starts: int, seed: int,
                 stable: bool, verify, doc, write) -> None:
    """For each of ``orders`` and each anchor of ``ends``, ``starts`` seeded random
    controllers continued from that end (:func:`casflutter.design.search_random_starts`,
    kept stable themselves when ``stable``); the one that reached farthest is certified and
    recorded with the far ends of all."""
    from ...design import search_random_starts  # noqa: PLC0415

    for order in orders:
        for anchor in ends:
            t0 = time.perf_counter()
            search = search_random_starts(family, (lo, hi), order, anchor=anchor,
                                          starts=starts, seed=seed, stable_controller=stable)
            far = 0 if anchor == "high" else 1
            extra = {"random_starts": starts, "stable_controller": stable,
                     "held_the_anchor": len(search.reaches),
                     "far_ends": [r.reached[far] for r in search.reaches],
                     "frequency_band": list(search.frequency_band)}
            best = search.best
            V = hi if anchor == "high" else lo
            kind = f"random order-{order} starts at V = {V:g} (seed {seed})"
            if best is None:
                _log.warning("order %d: none of %d random starts held the %s end", order,
                             starts, anchor)
                _add_failed(doc, write, kind, order, anchor,
                            f"no start decayed at the {anchor} end", t0, **extra)
                continue
            _add_run(doc, write, f"order {order} from the {anchor} end ({len(search.reaches)} "
                                 f"of {starts} random starts held it)", kind, order, best,
                     _midpoint(verify)(best), t0, **extra)


def _truth_runs(family, lo: float, hi: float, orders, doc, write) -> None:
    """Full order from the high end, then its balanced truncations to ``orders`` from the low
    end, on the truth loop; a truncation that does not hold the low end is recorded so."""
    import control  # noqa: PLC0415

    certify = _midpoint(lambda nominal, K: _verified_family(family, nominal, K))
    high = _from_high_end(family, lo, hi, "truth",
                          f"LQG at V = {hi:g} (truth, servo {family.servo_omega:g} rad/s)",
                          certify, doc, write)
    if high is None:
        return
    for order in orders:
        Kr = control.balred(high.controller, order, method="truncate")
        Kr = control.ss(Kr.A, Kr.B, Kr.C, np.zeros_like(np.asarray(Kr.D)))
        _continue(family, Kr, lo, hi, "low", f"truth, order {order} from the low end",
                  "balanced truncation of the full-order truth controller", certify, doc,
                  write)


def _reach_record(kind: str, order: int, reach, verified: dict, wall: float) -> dict:
    """One continuation's record, with its controller (``controller_from_json`` reads it)."""
    from ..._linalg import spectral_abscissa  # noqa: PLC0415
    from ...verify import controller_to_json  # noqa: PLC0415

    return {"start": kind, "order": order, "anchor": reach.anchor,
            "reached": list(reach.reached), "met": reach.met,
            "controller": controller_to_json(reach.controller),
            # > 0: the controller itself is unstable (the loop then needs the plant to hold)
            "controller_spectral_abscissa": spectral_abscissa(reach.controller.A),
            "worst_abscissa": reach.worst_abscissa, **{f"verified_{k}": v
                                                        for k, v in verified.items()},
            "history": [list(h) for h in reach.history], "wall_time_s": wall}


def _handler(args: argparse.Namespace) -> int:
    from ...design import SynthesisOptions, design_flutter_controller  # noqa: PLC0415
    from ...aeroelastic import TruthLoop, load_rom_loop  # noqa: PLC0415
    from ..._resources import problems_dir  # noqa: PLC0415
    from ...errors import CasflutterError, ConfigError  # noqa: PLC0415
    from ...pipeline import load_config  # noqa: PLC0415
    from ...truth import AeroelasticTruth  # noqa: PLC0415
    from ...verify import load_controller  # noqa: PLC0415
    from ..._outputs import check_output_path  # noqa: PLC0415
    from ..._settings import settings_as  # noqa: PLC0415

    try:
        lo, hi = (float(x) for x in str(args.interval).split(","))
        orders = [int(o) for o in str(args.orders).split(",") if o.strip()]
        random_orders = [int(o) for o in str(args.random_orders).split(",") if o.strip()]
    except ValueError:
        print("casflutter bench interval: --interval LO,HI, --orders K,K,... and "
              "--random-orders K,K,... (numbers)", file=sys.stderr)
        return 2
    if (not 0 <= lo < hi or any(k < 1 for k in orders + random_orders)
            or args.random_starts < 1 or args.seed < 0):
        print("casflutter bench interval: need 0 <= LO < HI, orders >= 1, "
              "--random-starts >= 1 and --seed >= 0", file=sys.stderr)
        return 2
    try:    # everything checked before any design work; nothing is written until a result
        out = check_output_path(args.out, what="--out", suffixes=(".json",))
        cfg = load_config(args.config)
        starts = [(path, load_controller(path)) for path in args.start]
        if args.model == "truth":
            truth = cfg.problem.load()
            if not isinstance(truth, AeroelasticTruth):
                raise ConfigError(f"--model truth: problem {cfg.problem.name!r} has no "
                                  "simulator to linearise; use a problem with a truth")
            family = TruthLoop(truth, float(cfg.controller.flap_rate_bandwidth
                                            if args.servo is None else args.servo))
        else:
            rom = (problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz" if args.rom is None
                   else Path(args.rom))
            system, Vf = load_rom_loop(rom)
            family = system if args.servo is None else system.with_servo(float(args.servo))
        sensors = family.loop(hi).C2.shape[0]
        for path, K in starts:
            if K.nstates == 0:
                raise ConfigError(f"--start {path}: a static gain; the continuation moves a "
                                  "dynamic controller's (A, B, C), so give one of order >= 1")
            if K.ninputs != sensors or K.noutputs != 1:
                raise ConfigError(f"--start {path}: a controller with {K.ninputs} inputs and "
                                  f"{K.noutputs} outputs; this loop needs v = K zm, {sensors} "
                                  "sensors in and the flap command out")
    except (OSError, CasflutterError) as exc:
        print(f"casflutter bench interval: {exc}", file=sys.stderr)
        return 2
    c = cfg.controller
    options = replace(settings_as(c, SynthesisOptions), ipopt={**cfg.solver.ipopt, **c.ipopt})
    doc: dict[str, Any] = ({"model": "rom", "rom": str(rom), "Vf": Vf,
                            "servo_omega": args.servo}
                           if args.model == "rom" else
                           {"model": "truth", "problem": cfg.problem.name,
                            "servo_omega": family.servo_omega, "servo_zeta": family.servo_zeta})
    doc.update({"target": [lo, hi], "runs": []})

    def write():
        runs = [r for r in doc["runs"] if r["reached"] is not None]    # not: a start refused
        reached_low = [r["reached"][1] for r in runs if r["anchor"] == "low"]
        reached_high = [r["reached"][0] for r in runs if r["anchor"] == "high"]
        doc["summary"] = {
            "highest_upper_end_from_low": max(reached_low, default=None),
            "lowest_lower_end_from_high": min(reached_high, default=None),
            # per controller order (JSON keys are strings): the bracket of each order
            "by_order": {str(k): {
                "highest_upper_end_from_low": max((r["reached"][1] for r in runs
                                                   if r["anchor"] == "low" and r["order"] == k),
                                                  default=None),
                "lowest_lower_end_from_high": min((r["reached"][0] for r in runs
                                                   if r["anchor"] == "high" and r["order"] == k),
                                                  default=None)}
                for k in sorted({r["order"] for r in runs})},
            "met_by_any": any(r["met"] for r in doc["runs"]),
            "target_certified_by_any": any(
                r["verified_exact_interval"] is not None
                and r["verified_exact_interval"][0] <= lo
                and r["verified_exact_interval"][1] >= hi for r in runs),
            "machine": {"cpus": os.cpu_count(), "load_average": list(os.getloadavg())
                        if hasattr(os, "getloadavg") else None}}
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(out.name + ".tmp")
        tmp.write_text(json.dumps(doc, indent=1, default=float))
        tmp.replace(out)

    if args.model == "truth" or args.servo is not None:
        def verify(nominal, K):
            return _verified_family(family, nominal, K)
    else:
        def verify(nominal, K):
            return _verified(system, nominal, K)
    _start_runs(family, lo, hi, starts, verify, doc, write)
    ends = ("low", "high") if args.random_ends == "both" else (args.random_ends,)
    _random_runs(family, lo, hi, random_orders, ends, args.random_starts, args.seed,
                 args.random_stable, verify, doc, write)
    if args.model == "truth":
        _truth_runs(family, lo, hi, orders, doc, write)
    else:
        for order in orders:
            t0 = time.perf_counter()
            design = design_flutter_controller(
                system, Vf, order, starts=c.starts, seed=args.seed, options=options,
                flap_rate_weight=c.flap_rate_weight, flap_rate_bandwidth=c.flap_rate_bandwidth)
            _continue(family, design.controller, lo, hi, "low", f"order {order} from the low "
                      "end", f"paper design at Vf (seed {args.seed})",
                      lambda reach: verify(Vf, reach.controller), doc, write, t0,
                      verified_start=_verified(system, Vf, design.controller))   # γ at Vf
        if args.full_order:
            _from_high_end(family, lo, hi, "ROM", f"LQG at V = {hi:g}",
                           lambda reach: verify(hi, reach.controller), doc, write)
    doc["rhp_zero_crossings"] = _rhp_zero_crossings(family, lo, hi, tuple(args.zero_band))
    doc["flutter_mode_grip"] = _flutter_mode_grip(family, lo, hi)
    write()
    print(f"wrote {out}", file=sys.stderr)
    return 0


def register(subparsers) -> None:
    """Add ``bench interval`` to the ``casflutter bench`` sub-commands."""
    p = subparsers.add_parser(
        "interval", help="how far one controller holds the ROM loop (or the truth) stable; "
                         "writes JSON",
        description=__doc__.split("\n\n")[1])
    p.add_argument("--model", choices=("rom", "truth"), default="rom",
                   help="the ROM loop (default) or the truth's own linearisation with the "
                        "flap behind a servo")
    p.add_argument("--servo", type=float, default=None,
                   help="servo natural frequency [rad/s] of the flap: --model truth (default: "
                        "the run configuration's controller.flap_rate_bandwidth), or the ROM "
                        "loop with the flap behind a servo (default: no servo)")
    p.add_argument("--rom", default=None,
                   help="ROM loop .npz (default: the seed wing's default run, seed 0: "
                        "problems/seed_wing_rom/rom_loop_seed0.npz)")
    p.add_argument("--config", default=None,
                   help="run configuration for the controller settings (default: the seed "
                        "wing's run.toml)")
    p.add_argument("--interval", default="0.05,2.4", help="target speed-index interval LO,HI")
    p.add_argument("--orders", default="3", help="orders of the low-end continuations")
    p.add_argument("--start", action="append", default=[], metavar="FILE",
                   help="a saved controller (verification JSON, v = K zm) to continue from "
                        "the low end as well; repeatable")
    p.add_argument("--random-orders", default="",
                   help="orders of seeded random starts continued from the ends of the "
                        "interval (default none)")
    p.add_argument("--random-ends", choices=("both", "low", "high"), default="both",
                   help="the ends the random starts are made at")
    p.add_argument("--random-starts", type=int, default=20,
                   help="random starts per order and end (seeded by --seed)")
    p.add_argument("--random-stable", action="store_true",
                   help="keep the random-start controllers stable themselves (their poles "
                        "join the objective)")
    p.add_argument("--full-order", action=argparse.BooleanOptionalAction, default=True,
                   help="also the full-order continuation from the high end")
    p.add_argument("--zero-band", type=float, nargs=2, default=(20.0, 80.0),
                   metavar=("W_LO", "W_HI"),
                   help="frequency band [rad/s] of the zero crossings reported")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the paper design's starts and of the random starts")
    p.add_argument("--out", required=True, help="output JSON file")
    p.set_defaults(func=_handler)
