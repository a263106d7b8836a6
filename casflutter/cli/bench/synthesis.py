"""``casflutter bench synthesis``: fixed-order H∞ synthesis on COMPleib-format plants.

Writes one JSON record per plant and controller order with the *verified* γ (exact norm of
the closed loop, never the gridded value), γ* when the plant file (or a ``reference.json``
beside it) has it, stability, status, starts and wall time.  Orders are solved in increasing
order and each order starts (among others) from the best controller of the previous one,
so γ cannot increase with the order.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["register", "run_plant"]


def _plant_files(items: list[str]) -> list[Path]:
    files: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            files += sorted(f for f in p.glob("*.json") if f.name != "reference.json")
        elif p.is_file():
            files.append(p)
        else:
            raise FileNotFoundError(f"no plant file or directory {item!r}")
    return files


def _hinfsyn_gamma(P, nmeas: int, ncon: int, timeout: float) -> float | None:
    """python-control's full-order ``hinfsyn`` γ in a child process with a time limit
    (it refuses singular problems and may hang on them); ``None`` when it does not answer."""
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()

    def work():
        try:
            import control  # noqa: PLC0415
            _, _, gam, _ = control.hinfsyn(P, nmeas, ncon)
            q.put(float(gam))
        except Exception:  # noqa: BLE001 - any refusal means "not applicable"
            q.put(None)

    proc = ctx.Process(target=work)
    proc.start()
    proc.join(timeout)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None
    try:
        return q.get(timeout=1.0)
    except Exception:  # noqa: BLE001
        return None


def run_plant(path: Path, orders: list[int], starts: int, seed: int, time_limit: float | None,
              hinfsyn_timeout: float) -> list[dict[str, Any]]:
    """All records of one plant file (orders solved in increasing order, warm-started)."""
    from ...design import SynthesisOptions, load_compleib, synthesize  # noqa: PLC0415
    from ...errors import SynthesisError  # noqa: PLC0415

    P, nmeas, ncon, meta = load_compleib(path)
    gstar = meta.get("gamma_full_order_lmi", meta.get("gamma_lower_bound"))
    full = _hinfsyn_gamma(P, nmeas, ncon, hinfsyn_timeout) if hinfsyn_timeout > 0 else None
    records, previous = [], None
    for order in sorted(orders):
        t0 = time.perf_counter()
        rec: dict[str, Any] = {"plant": meta.get("name", path.stem), "order": order,
                               "gamma_lower_bound": gstar, "hinfsyn_full_order_gamma": full,
                               "published_static": meta.get("published_static") or None}
        try:
            res = synthesize(P, nmeas, ncon, order, starts=starts, seed=seed,
                             initial=previous,
                             options=SynthesisOptions(time_limit=time_limit))
            previous = res.controller
            rec.update(gamma=res.gamma, stable=bool(res.spectral_abscissa < 0),
                       status="converged" if res.converged else "stopped",
                       spectral_abscissa=res.spectral_abscissa, omega_peak=res.omega_peaks[0],
                       delta_bound=res.delta_bound, best_start=res.best_start,
                       norm_method=res.norm_method,
                       starts=[{"kind": s.kind, "stabilized": s.stabilized,
                                "gamma": s.gamma if np.isfinite(s.gamma) else None,
                                "outer_iterations": s.outer_iterations,
                                "converged": s.converged, "grid_gap": s.grid_gap
                                if np.isfinite(s.grid_gap) else None,
                                "last_ipopt_status": s.statuses[-1] if s.statuses else None,
                                "wall_time_s": s.wall_time} for s in res.starts])
        except SynthesisError as exc:
            rec.update(gamma=None, stable=False, status=f"SynthesisError: {exc}",
                       spectral_abscissa=exc.best_spectral_abscissa, starts=[])
        rec["wall_time_s"] = time.perf_counter() - t0
        if rec["gamma"] is not None and gstar:
            rec["ratio_to_lower_bound"] = rec["gamma"] / gstar
        records.append(rec)
        print(f"{rec['plant']:>8s} k={order} gamma={rec['gamma']} gamma*={gstar} "
              f"t={rec['wall_time_s']:.1f}s {rec['status'][:40]}", file=sys.stderr, flush=True)
    return records


def _handler(args: argparse.Namespace) -> int:
    orders = [int(o) for o in str(args.orders).split(",") if o.strip()]
    if any(o < 0 for o in orders):
        print("casflutter bench synthesis: orders must be >= 0", file=sys.stderr)
        return 2
    files = _plant_files(args.plants)
    jobs = [(f, orders, args.starts, args.seed, args.time_limit, args.hinfsyn_timeout)
            for f in files]
    if args.jobs > 1:
        # non-daemonic workers: each may start the time-limited hinfsyn child process
        with ProcessPoolExecutor(args.jobs, mp_context=multiprocessing.get_context("spawn")) \
                as pool:
            chunks = list(pool.map(run_plant, *zip(*jobs)))
    else:
        chunks = [run_plant(*j) for j in jobs]
    records = [r for c in chunks for r in c]
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(records, indent=1, default=float))
    print(f"wrote {len(records)} records to {out}", file=sys.stderr)
    return 0


def register(subparsers) -> None:
    """Add ``bench synthesis`` to the ``casflutter bench`` sub-commands."""
    p = subparsers.add_parser("synthesis", help="fixed-order H-infinity synthesis on COMPleib "
                                                "plants; writes JSON")
    p.add_argument("--plants", nargs="+", required=True, metavar="FILE_OR_DIR",
                   help="plant JSON files (COMPleib format) or directories of them")
    p.add_argument("--orders", default="0,1,2,3", help="comma-separated controller orders")
    p.add_argument("--out", required=True, help="output JSON file")
    p.add_argument("--starts", type=int, default=3, help="starts per order (besides the "
                                                         "previous order's controller)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random starts")
    p.add_argument("--time-limit", type=float, default=120.0,
                   help="wall-time budget per plant and order in seconds")
    p.add_argument("--hinfsyn-timeout", type=float, default=10.0,
                   help="seconds allowed to control.hinfsyn for the full-order comparison "
                        "(0: skip)")
    p.add_argument("--jobs", type=int, default=1, help="plants solved in parallel")
    p.set_defaults(func=_handler)
