"""``casflutter bench design``: the multi-speed fixed-order design on a plant family.

One JSON record per controller order and seed (:func:`casflutter.design.design_over_speeds`
over ``--interval``): ``problem``, ``nx``, ``n_inputs``, ``n_outputs``, ``order``, ``seed``,
``interval``, ``held`` (the design's dense scan finds the decay rate over the whole
interval), ``reach`` (the top of the interval it holds from ``lo``), ``decay`` (the rate
held: ``--decay``, or the one the design chose), ``worst_abscissa``,
``gamma``, ``wall_time_s`` and ``cpu_time_s``, and the verification layer's certificate of
the same controller on the family (``certified_interval``: the stable interval containing
the range's start, :func:`casflutter.verify.verify_family`), and a ``summary`` with the
medians per order.  The file is rewritten after every record, so a run that is stopped keeps
what it finished; ``--out`` is checked before any work (its missing folders are created
with the first record).

``--problem`` names a plant family (a ``kind = "plant_family"`` file or a folder of
``problems/`` holding one) or a run configuration (a ``problems/`` name with a ``run.toml``,
or a ``RUN.toml`` path), whose model stages build the family the run designs on (for the
seed wing: the ROM loop that follows the wing over speed, flap behind its servo).  A run
configuration's ``[controller]`` table gives the design's settings (starts, speeds, decay
rate, flap-rate weight, budgets), so the bench measures the design that ``casflutter run``
makes; its H∞ objective too, except the paper's LFT (``"lft"``), which needs the ROM loop's
flutter speed and is replaced by the family's own (``--objective auto``).  A family file
takes the ``[controller]`` defaults of a run configuration whose ``[problem]`` names it
(:func:`casflutter.pipeline.multispeed_settings`), which is what ``casflutter run`` designs
with on it.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..._outputs import atomic_file, check_output_path, plain_json, provenance
from ...errors import ConfigError

__all__ = ["register", "design_records"]


def _family(problem: str):
    """The family ``--problem`` names, its description, and the run configuration it comes
    from (``None`` for a family file)."""
    from ...aeroelastic import load_family
    from ...pipeline import config_path, design_family, load_config

    try:
        fam = load_family(problem)
        return fam, f"plant family {problem}", None
    except ConfigError as family_error:
        try:
            # a RUN.toml file, else a problems/ name with a run.toml
            path = problem if Path(problem).is_file() else config_path(problem, "run")
            cfg = load_config(path)
        except ConfigError:
            raise ConfigError(f"--problem {problem!r} is neither a plant family ({family_error}) "
                              "nor a run configuration (a problems/ name with a run.toml, or "
                              "a RUN.toml file)") from None
        return (design_family(cfg), f"the design family of the run configuration {problem}",
                cfg)


def _ints(text: str, what: str, low: int) -> list[int]:
    try:
        values = [int(v) for v in str(text).split(",") if v.strip()]
    except ValueError:
        raise ConfigError(f"--{what} = {text!r}: comma-separated integers, e.g. 2,3,4") from None
    if not values or any(v < low for v in values):
        raise ConfigError(f"--{what} = {text!r}: comma-separated integers >= {low}")
    return values


def design_records(family, interval, orders, seeds, *, problem: str = "",
                   decay: float | None = None, objective: str = "auto", settings=None,
                   on_record=None) -> list[dict[str, Any]]:
    """Design at every order and seed and certify each controller on the family.

    Parameters
    ----------
    family : PlantFamily
        The family.
    interval : (float, float)
        The speeds to hold.
    orders, seeds : sequence of int
        Controller orders and seeds.
    problem : str
        The name written in each record.
    decay : float, optional
        Decay rate required at every speed [rad per time unit] (default: the settings',
        else chosen by :class:`casflutter.design.MultiSpeedSettings`; each record says
        which).
    objective : {"auto", "sensors", "sensitivity"}
        The H∞ phase's channels (:class:`casflutter.design.MultiSpeedSettings`):
        the family's disturbances to its measurements, or the loop's output and input
        sensitivities (the per-loop margins); ``"auto"``: ``"sensors"`` when the family
        names disturbance inputs, else ``"sensitivity"``.
    settings : MultiSpeedSettings, optional
        The design's other settings (default: the class's defaults).
    on_record : callable, optional
        Called with each record as it is finished.

    Returns
    -------
    list of dict
    """
    from ...design import MultiSpeedSettings, default_objective, design_over_speeds
    from ...errors import SynthesisError
    from ...verify import verify_family

    sig, nx = family.signals, family.n_states
    if objective == "auto":
        objective = default_objective(family)
    base = MultiSpeedSettings() if settings is None else settings
    settings = replace(base, decay=base.decay if decay is None else decay,
                       sensitivity=objective == "sensitivity")
    records = []
    for order in orders:
        for seed in seeds:
            rec = {"problem": problem, "nx": nx, "n_inputs": len(sig.controls),
                   "n_outputs": len(sig.measurements), "order": order, "seed": seed,
                   "interval": list(interval), "objective": objective}
            t, c = time.perf_counter(), time.process_time()
            try:
                d = design_over_speeds(family, interval, order, settings=settings, seed=seed)
            except SynthesisError as exc:
                rec.update(held=False, reach=None, worst_abscissa=None, gamma=None,
                           certified_interval=None, robust_flutter_speed=None,
                           status=f"failed: {exc}",
                           wall_time_s=time.perf_counter() - t,
                           cpu_time_s=time.process_time() - c)
            else:
                rec.update(held=bool(d.held), reach=d.reached[1], decay=d.decay,
                           worst_abscissa=d.worst_abscissa, gamma=d.gamma,
                           wall_time_s=time.perf_counter() - t,
                           cpu_time_s=time.process_time() - c, status=d.message)
                lo, hi = family.speed_range
                check = verify_family(family, d.controller,
                                      speed_range=(lo, hi) if hi < float("inf")
                                      else (lo, interval[1]))
                rec["certified_interval"] = (None if check.stable_interval is None
                                             else list(check.stable_interval))
                rec["robust_flutter_speed"] = check.robust_flutter_speed
            records.append(plain_json(rec))
            if on_record is not None:
                on_record(records[-1])
    return records


def summarize(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per order: how many seeds held, the median reach and the median times.

    Parameters
    ----------
    records : list of dict
        The records of :func:`design_records`.

    Returns
    -------
    dict
    """
    out = {}
    for order in sorted({r["order"] for r in records}):
        rs = [r for r in records if r["order"] == order]
        reach = [r["reach"] for r in rs if r["reach"] is not None]
        out[str(order)] = {
            "held": sum(bool(r["held"]) for r in rs), "of": len(rs),
            "median_reach": statistics.median(reach) if reach else None,
            "median_wall_time_s": statistics.median(r["wall_time_s"] for r in rs),
            "median_cpu_time_s": statistics.median(r["cpu_time_s"] for r in rs)}
    return out


def _write(out: Path, records: list, meta: dict) -> None:
    with atomic_file(out, what="--out") as tmp:
        tmp.write_text(json.dumps({"records": records, "summary": summarize(records),
                                   **meta}, indent=1))


def _handler(args: argparse.Namespace) -> int:
    orders, seeds = _ints(args.orders, "orders", 0), _ints(args.seeds, "seeds", 0)
    lo, hi = args.interval
    if not lo < hi:
        raise ConfigError(f"--interval {lo} {hi}: need LO < HI")
    out = check_output_path(args.out, what="--out", suffixes=(".json",))
    family, about, cfg = _family(args.problem)
    from ...design import default_objective
    from ...pipeline import RunConfig, multispeed_settings

    # a family file: the [controller] defaults of a run that names it, so the bench
    # measures the design `casflutter run` makes
    objective, run_cfg = args.objective, RunConfig() if cfg is None else cfg
    ran = run_cfg.controller.hinf_objective
    if objective == "auto":
        objective = ran if ran in ("sensors", "sensitivity") else default_objective(family)
    settings = multispeed_settings(run_cfg, objective)
    meta = {"problem": args.problem, "family": about, "decay": args.decay,
            "objective": objective,
            "settings": "the run configuration's [controller]" if cfg is not None
            else "the [controller] defaults of a run configuration naming the family",
            "provenance": provenance()}
    records: list = []

    def keep(rec):
        records.append(rec)
        _write(out, records, meta)

    design_records(family, (lo, hi), orders, seeds, problem=args.problem, decay=args.decay,
                   objective=objective, settings=settings, on_record=keep)
    return 0


def register(subparsers) -> None:
    """Add ``bench design`` to the ``casflutter bench`` sub-commands."""
    p = subparsers.add_parser("design", help="the multi-speed fixed-order design on a plant "
                                             "family; writes JSON")
    p.add_argument("--problem", required=True, metavar="P_OR_FILE",
                   help="a plant family (file or problems/ name) or a run configuration "
                        "whose design family and [controller] settings are used (e.g. "
                        "seed_wing)")
    p.add_argument("--interval", nargs=2, type=float, required=True, metavar=("LO", "HI"),
                   help="the speeds to hold, in the family's speed unit")
    p.add_argument("--orders", default="2,3,4", help="comma-separated controller orders")
    p.add_argument("--seeds", default="0,1,2", help="comma-separated seeds")
    p.add_argument("--decay", type=float, default=None,
                   help="decay rate required at every speed [rad per time unit] (default: "
                        "0.05, or half the rate of the open loop's slowest decaying mode at "
                        "LO, or of the family's slowest mode that no controller moves, where "
                        "that is slower)")
    p.add_argument("--objective", choices=("auto", "sensors", "sensitivity"), default="auto",
                   help="H-infinity objective once the interval is held: the family's "
                        "disturbances to its sensors, or the loop's output and input "
                        "sensitivities (the per-loop margins); auto: sensors when the family "
                        "names disturbance inputs, else sensitivity")
    p.add_argument("--out", required=True, help="output JSON file")
    p.set_defaults(func=_handler)
