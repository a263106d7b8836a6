"""``casflutter bench sweep``: sweep throughput on 1 and 2 local workers and on Dask.

The study is a Latin hypercube of ``--points`` points over the typical section (elastic
axis, frequency ratio, mass ratio, damping) with the ``truth_flutter`` evaluator: the flutter
search plus the LCO amplitude of the nonlinear truth (cubic hardening pitch spring) at
1.1 Vf.  Each configuration runs ``--repeats`` times on a fresh store; the JSON holds the
median wall times, the speed-up ``wall(1) / wall(2)`` and the overhead beyond the work
itself: ``(workers · wall − Σ work) / Σ work`` with ``work`` each point's evaluator time
measured in the worker (start-up of the worker processes reported separately).
"""

from __future__ import annotations

import json
import logging
import math
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

from ..._outputs import check_output_path
from ...errors import CasflutterError, ConfigError

__all__ = ["register", "run", "bench_study"]

_log = logging.getLogger(__name__)


def bench_study(points: int, lco_time: float, seed: int = 0):
    """The benchmark :class:`~casflutter.study.Study` (typical section, LHS)."""
    from ...study import Study
    from ...study._spec import Parameter

    return Study(
        name="bench_sweep", evaluator="truth_flutter", design="lhs", samples=int(points),
        seed=seed,
        parameters=(Parameter("a", low=-0.4, high=0.0), Parameter("sigma", low=0.3, high=0.6),
                    Parameter("mu", low=10.0, high=40.0, scale="log"),
                    Parameter("zeta", low=0.0, high=0.02)),
        settings={"problem": "typical_section", "kappa2": 20.0, "lco_speed_ratio": 1.1,
                  "lco_time": float(lco_time), "lco_samples": int(10 * lco_time) + 1})


def register(subparsers) -> None:
    """Add the ``bench sweep`` benchmark."""
    p = subparsers.add_parser(
        "sweep", help="sweep wall time on 1 and 2 local workers and a 2-worker Dask cluster",
        description=__doc__.split("\n\n")[1])
    p.add_argument("--points", type=int, default=64, help="points of the study (default 64)")
    p.add_argument("--repeats", type=int, default=3, help="runs per configuration (median)")
    p.add_argument("--lco-time", type=float, default=600.0,
                   help="LCO simulation length per point (sets the work per point)")
    p.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster runs")
    p.add_argument("--out", default="bench_sweep.json", help="JSON output file")
    p.set_defaults(func=run)


def _one(study, store_dir: Path, tag: str, i: int, **kw) -> dict:
    from ...study import run_sweep

    store = store_dir / f"{tag}_{i}.jsonl"
    res = run_sweep(study, store=store, progress=False, **kw)
    if res.n_left:
        raise CasflutterError(f"bench sweep, {tag}: {res.n_left} points were not computed; rerun "
                          "(a worker or the cluster was lost)")
    workers = kw.get("workers") or 2
    work = res.work_time
    return {"wall_time": res.wall_time, "startup_time": res.startup_time, "work_time": work,
            "failed": res.n_failed, "executor": res.executor,
            "overhead_percent": 100.0 * (workers * res.wall_time - work) / work,
            "overhead_percent_with_startup":
                100.0 * (workers * (res.wall_time + res.startup_time) - work) / work}


def _summary(runs: list[dict], workers: int, points: int) -> dict:
    med = {k: statistics.median(r[k] for r in runs)
           for k in ("wall_time", "startup_time", "work_time", "overhead_percent",
                     "overhead_percent_with_startup")}
    med["overhead_per_point_ms"] = 1e3 * (workers * med["wall_time"] - med["work_time"]) / points
    med["work_per_point_ms"] = 1e3 * med["work_time"] / points
    med["workers"] = workers
    med["executor"] = runs[0]["executor"]
    med["failed"] = runs[0]["failed"]
    med["runs"] = runs
    return med


def run(args) -> int:
    """Handler: run the benchmark and write the JSON (the output file is checked first)."""
    for name, value in (("--points", args.points), ("--repeats", args.repeats)):
        if value < 1:
            raise ConfigError(f"{name} {value}: give a positive number")
    if not (math.isfinite(args.lco_time) and args.lco_time > 0):
        raise ConfigError(f"--lco-time {args.lco_time}: give a positive number of time units")
    check_output_path(args.out, what="--out", suffixes=(".json",))
    study = bench_study(args.points, args.lco_time)
    out: dict = {"benchmark": "sweep", "points": args.points, "repeats": args.repeats,
                 "study": "typical_section LHS (a, sigma, mu, zeta), truth_flutter + LCO at 1.1 Vf",
                 "lco_time": args.lco_time, "cpu_count": os.cpu_count(),
                 "python": platform.python_version(),
                 "definition": {
                     "wall_time": "first submission to last stored record, worker start-up excluded",
                     "overhead_percent": "(workers * wall_time - sum of per-point work) / sum of work",
                     "speedup": "wall_time(1 worker) / wall_time(2 workers)"}}
    with tempfile.TemporaryDirectory(prefix="casflutter_bench_sweep_") as tmp:
        tmp = Path(tmp)
        for w in (1, 2):
            runs = [_one(study, tmp, f"local{w}", i, workers=w) for i in range(args.repeats)]
            out[f"local_{w}_workers"] = _summary(runs, w, args.points)
            _log.info("local, %d worker(s): wall %.2f s, overhead %.2f %%", w,
                      out[f"local_{w}_workers"]["wall_time"],
                      out[f"local_{w}_workers"]["overhead_percent"])
        out["speedup_2_vs_1"] = (out["local_1_workers"]["wall_time"]
                                 / out["local_2_workers"]["wall_time"])
        if not args.no_dask:
            from distributed import Client, LocalCluster

            t0 = time.perf_counter()
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                              host="127.0.0.1", dashboard_address=None) as cluster, \
                    Client(cluster) as client:
                cluster_start = time.perf_counter() - t0
                runs = [_one(study, tmp, "dask2", i, scheduler=client, workers=2)
                        for i in range(args.repeats)]
            out["dask_2_workers"] = _summary(runs, 2, args.points)
            out["dask_2_workers"]["cluster_start_time"] = cluster_start
            out["speedup_dask2_vs_1"] = (out["local_1_workers"]["wall_time"]
                                         / out["dask_2_workers"]["wall_time"])
            _log.info("dask, 2 workers: wall %.2f s, overhead %.2f %%",
                      out["dask_2_workers"]["wall_time"], out["dask_2_workers"]["overhead_percent"])
    print(f"speed-up 2 vs 1 local workers: {out['speedup_2_vs_1']:.2f}")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(out, fh, indent=2)
    print(f"wrote {args.out}")
    return 0
