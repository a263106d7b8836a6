"""``casflutter sweep STUDY.toml``: run or resume a parameter study (grid or Latin hypercube).

Local worker processes by default; ``--scheduler tcp://HOST:PORT`` (or ``scheduler`` in the
study file) sends the same study to an existing Dask distributed cluster.  Every finished
point is stored at once in ``OUT/NAME.jsonl``; running the command again resumes (and
computes the failed points again, unless ``--keep-failed``).  The tidy table goes to
``OUT/NAME.csv`` (and ``.parquet`` where pyarrow is installed), the summary plot to
``OUT/NAME.png``.

Exit code: 0 when every point finished without failure; 1 when points failed or are left
(the summary line says how many) or on an error; 130 after Ctrl-C, 143 after SIGTERM (the
worker processes are stopped; run the same command again to resume).  A second sweep on the
same store refuses to start while the first runs.
"""

from __future__ import annotations

import argparse
import json
import logging

from ..._interrupt import Terminated
from ..._outputs import check_output_path

__all__ = ["register", "run"]

_log = logging.getLogger(__name__)


def register(subparsers) -> None:
    """Add the ``sweep`` sub-command."""
    p = subparsers.add_parser(
        "sweep", help="run or resume a parameter study (local processes or Dask)",
        description="Run a study file (grid or Latin hypercube over named parameters, an "
                    "evaluator, outputs to collect). Finished points are stored as they "
                    "complete: run the same command again to resume after Ctrl-C or a "
                    "crash. Failed points are recorded with their error.")
    p.add_argument("study", nargs="?", help="study TOML file (see problems/studies/)")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: the study's, else 2; 0: in-process)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="run on an existing Dask distributed scheduler")
    p.add_argument("--out", default="sweeps", help="output folder (default ./sweeps)")
    p.add_argument("--keep-failed", action="store_true",
                   help="do not compute the points stored as failed again (they count as "
                        "done)")
    p.add_argument("--retry-failed", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--max-points", type=int, default=None,
                   help="stop after this many points (resume later; 0 computes nothing)")
    p.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    p.add_argument("--no-plot", action="store_true", help="skip the summary figure")
    p.add_argument("--list", action="store_true", help="list the registered evaluators")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler: 0 when every point finished without failure, 1 when points failed or are
    left, 130 after Ctrl-C, 143 after SIGTERM."""
    from ...errors import ConfigError
    from ...study import (evaluator_names, get_evaluator, load_study, plot_sweep, run_sweep,
                          sweep_table, write_table)

    if args.list:
        for name in evaluator_names():
            ev = get_evaluator(name)
            print(f"{name:<16} {ev.description}")
            if ev.outputs:
                print(f"{'':<16} outputs: {', '.join(ev.outputs)}")
        return 0
    if not args.study:
        raise ConfigError("give a study file: casflutter sweep STUDY.toml (or --list)")
    study = load_study(args.study)
    out = check_output_path(args.out, what="--out", kind="dir")
    store = out / f"{study.name}.jsonl"
    try:
        res = run_sweep(study, store=store, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.no_progress, retry_failed=not args.keep_failed,
                        max_points=args.max_points)
    except KeyboardInterrupt as exc:
        what = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
        _log.warning("%s: the worker processes are stopped and the finished points are in "
                     "%s; run the same command again to resume", what, store)
        return 143 if isinstance(exc, Terminated) else 130
    rows = sweep_table(study, store)
    files = write_table(rows, out / study.name) if rows else []
    if rows and not args.no_plot:
        outputs = list(study.outputs) or [c for c in rows[0] if c not in
                                          (*study.parameter_names, "key", "status", "error",
                                           "work_time", "worker")]
        fig = plot_sweep(rows, study.parameter_names, outputs)
        fig.savefig(out / f"{study.name}.png", dpi=110)
        files.append(out / f"{study.name}.png")
    summary = {"study": study.name, "evaluator": study.evaluator, "design": study.design,
               "executor": res.executor, "points": res.n_points, "resumed": res.n_resumed,
               "computed": res.n_computed, "failed": res.n_failed, "left": res.n_left,
               "wall_time": res.wall_time, "startup_time": res.startup_time,
               "work_time": res.work_time, "store": str(store),
               "files": [str(f) for f in files]}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{study.name}: {res.n_points} points ({study.design}) on {res.executor}: "
              f"{res.n_computed} computed, {res.n_resumed} resumed, {res.n_failed} failed, "
              f"{res.n_left} left; wall {res.wall_time:.2f} s (+ {res.startup_time:.2f} s "
              "worker start-up)")
        for f in [store, *files]:
            print(f"  {f}")
        if res.n_failed:
            print(f"  {res.n_failed} point(s) failed (their error is in the 'error' column); "
                  "running the same command again computes them again"
                  + (" (without --keep-failed)" if args.keep_failed else ""))
        if res.n_left:
            print("  run the same command again to resume")
    return 0 if res.n_left == 0 and res.n_failed == 0 else 1
