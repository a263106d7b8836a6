"""``casflutter bench synthesis``: fixed-order H∞ synthesis on COMPleib-format plants.

Writes one JSON record per plant and controller order with the exact γ of the closed loop,
γ* when the plant file (or a ``reference.json`` beside it) has it, the state dimension
``nx``, stability, status, starts and wall time, and a ``summary`` with the medians and the
exponent ``p`` of the fit ``time ≈ c · nx^p``.  Orders are solved in increasing order and
each order starts (among others) from the best controller of the previous one, so γ cannot
increase with the order.  The file is rewritten after every plant and order, so a run that
is stopped keeps what it finished; ``--out`` is checked to be writable before any work.
Each record of an order below ``ncon`` (or ``nmeas``) gets the certified static-direction
bound for that order (:func:`casflutter.design.static_direction_bound` at ω = 0 and ∞, both
sides where the plant allows, proven in exact arithmetic up to 60 states; not counted in
``wall_time_s``)
and ``ratio_to_certified_bound``; the summary gives each plant's order-3 γ against the best
lower bound known, ``max(γ*, certificate)``.
With ``--relaxation-starts N`` such records also get the rank relaxation
(:func:`casflutter.design.order_relaxation` at ω = 0 and ∞, ``N`` seeded starts): its best
local minimum, a lower bound when it is the global one.

A plant that fails (a file that cannot be read, a plant the synthesis refuses, no start that
stabilises it, or an internal error) gets a record per order with ``gamma`` null,
``stable`` false and ``error`` (``class`` and ``message``); the benchmark goes on with the
next order and plant, and the exit status is 1 when a plant could not be run at all (its
file, or an internal error) or an order got no stabilising controller, 0 otherwise.  Bad
arguments (orders, starts, a plant that is not a JSON file) are refused before any work.

``hinfsyn_full_order_gamma`` is the H∞ norm that python-control's full-order ``hinfsyn``
controller achieves on the plant, recomputed from its closed loop; the γ ``hinfsyn``
reports is kept as ``hinfsyn_reported_gamma`` (on COMPleib's EB1 it reports 2.43 for a
controller whose loop has norm 3.25, below the true optimum 3.10).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from ..._outputs import atomic_file, check_output_path
from ...errors import ConfigError

__all__ = ["register", "run_plant"]


def _plant_files(items: list[str]) -> list[Path]:
    files: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            files += sorted(f for f in p.glob("*.json") if f.name != "reference.json")
        elif p.is_file() and p.suffix.lower() == ".json":
            files.append(p)
        elif p.is_file():
            raise ConfigError(f"--plants {item}: a {p.suffix or 'suffix-less'} file; the plants "
                              "are COMPleib-format JSON files (A, B1, B, C1, C, D11, D12, D21; "
                              "see problems/compleib/README.md)")
        else:
            raise ConfigError(f"--plants {item}: no such plant file or folder")
    if not files:
        raise ConfigError(f"--plants {' '.join(items)}: no plant JSON files there")
    return files


def _hinfsyn_gamma(P, nmeas: int, ncon: int, timeout: float
                   ) -> tuple[float | None, float | None]:
    """python-control's full-order ``hinfsyn`` in a child process with a time limit (it
    refuses singular problems and may hang on them): ``(reported, achieved)``, the γ it
    reports and the H∞ norm of the closed loop its controller gives (``None`` where that
    loop is unstable), or ``(None, None)`` when it does not answer.  Only the achieved norm
    is a fair comparison: on some plants (COMPleib's EB1) the reported γ lies below what the
    controller achieves and below the true optimum."""
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()

    def work():
        try:
            import control  # noqa: PLC0415
            _, cl, gam, _ = control.hinfsyn(P, nmeas, ncon)
            stable = bool(np.max(np.linalg.eigvals(np.asarray(cl.A)).real) < 0)
            q.put((float(gam), float(control.norm(cl, "inf")) if stable else None))
        except Exception:  # noqa: BLE001 - any refusal means "not applicable"
            q.put((None, None))

    proc = ctx.Process(target=work)
    proc.start()
    proc.join(timeout)
    if proc.is_alive():
        # SIGKILL: the child inherits the command's Python SIGTERM handler, which cannot run
        # while slycot's Fortran holds the thread, so terminate() left join() waiting forever
        proc.kill()
        proc.join()
        return None, None
    try:
        return q.get(timeout=1.0)
    except Exception:  # noqa: BLE001
        return None, None


def _error(exc: BaseException) -> dict[str, str]:
    """The ``error`` entry of a record: the exception's class and one-line message."""
    return {"class": type(exc).__name__, "message": " ".join(str(exc).split())}


def _failed_plant(path: Path, orders: list[int], exc: BaseException, on_record
                  ) -> list[dict[str, Any]]:
    """One record per order for a plant that could not be run at all."""
    records = []
    for order in sorted(orders):
        rec = {"plant": path.stem, "order": order, "nx": None, "gamma": None, "stable": False,
               "status": f"error: {type(exc).__name__}", "error": _error(exc),
               "starts": [], "wall_time_s": 0.0}
        records.append(rec)
        if on_record is not None:
            on_record(rec)
    print(f"{path.stem:>8s} failed: {type(exc).__name__}: {_error(exc)['message'][:120]}",
          file=sys.stderr, flush=True)
    return records


def run_plant(path: Path, orders: list[int], starts: int, seed: int, time_limit: float | None,
              hinfsyn_timeout: float, relaxation_starts: int = 0,
              on_record=None) -> list[dict[str, Any]]:
    """All records of one plant file (orders solved in increasing order, warm-started);
    ``on_record(record)`` is called after each order.  A failure is recorded (module
    docstring), never raised."""
    from ...design import load_compleib  # noqa: PLC0415
    from ...errors import CasflutterError  # noqa: PLC0415

    try:
        P, nmeas, ncon, meta = load_compleib(path)
    except CasflutterError as exc:
        return _failed_plant(path, orders, exc, on_record)
    return _run_orders(P, nmeas, ncon, meta, path, orders, starts, seed, time_limit,
                       hinfsyn_timeout, relaxation_starts, on_record)


def _run_orders(P, nmeas: int, ncon: int, meta: dict, path: Path, orders: list[int],
                starts: int, seed: int, time_limit: float | None, hinfsyn_timeout: float,
                relaxation_starts: int, on_record) -> list[dict[str, Any]]:
    from ...design import SynthesisOptions, synthesize  # noqa: PLC0415
    from ...errors import CasflutterError, SynthesisError  # noqa: PLC0415

    gstar = meta.get("gamma_full_order_lmi", meta.get("gamma_lower_bound"))
    reported, full = (_hinfsyn_gamma(P, nmeas, ncon, hinfsyn_timeout) if hinfsyn_timeout > 0
                      else (None, None))
    nx = int(np.asarray(P.A).shape[0])
    records, previous = [], None
    for order in sorted(orders):
        t0 = time.perf_counter()
        rec: dict[str, Any] = {"plant": meta.get("name", path.stem), "order": order, "nx": nx,
                               "gamma_lower_bound": gstar, "hinfsyn_full_order_gamma": full,
                               "hinfsyn_reported_gamma": reported,
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
                                "stab_iterations": s.stab_iterations,
                                "outer_iterations": s.outer_iterations,
                                "converged": s.converged, "model_decrease": s.model_decrease
                                if np.isfinite(s.model_decrease) else None,
                                "last_qp_status": s.statuses[-1] if s.statuses else None,
                                "status": s.status, "reason": s.reason,
                                "wall_time_s": s.wall_time} for s in res.starts])
        except SynthesisError as exc:
            rec.update(gamma=None, stable=False, status=f"SynthesisError: {exc}",
                       spectral_abscissa=exc.best_spectral_abscissa, error=_error(exc),
                       starts=[{"kind": s.kind, "status": s.status, "reason": s.reason}
                               for s in exc.starts])
        except CasflutterError as exc:        # a plant the synthesis refuses (named entry)
            rec.update(gamma=None, stable=False, status=f"{type(exc).__name__}: {exc}",
                       error=_error(exc), starts=[])
        except Exception as exc:  # noqa: BLE001 - a bug on one plant must not end the run
            rec.update(gamma=None, stable=False, status=f"internal error: {type(exc).__name__}",
                       error=_error(exc), starts=[])
        rec["wall_time_s"] = time.perf_counter() - t0
        try:
            _bounds(rec, P, nmeas, ncon, order, gstar, seed, relaxation_starts)
        except Exception as exc:  # noqa: BLE001 - the bounds are extras of the record
            rec["bounds_error"] = _error(exc)
        records.append(rec)
        print(f"{rec['plant']:>8s} k={order} gamma={rec['gamma']} gamma*={gstar} "
              f"t={rec['wall_time_s']:.1f}s {rec['status'][:40]}", file=sys.stderr, flush=True)
        if on_record is not None:
            on_record(rec)
    return records


def _bounds(rec: dict[str, Any], P, nmeas: int, ncon: int, order: int, gstar, seed: int,
            relaxation_starts: int) -> None:
    """Add the relaxation, the static-direction certificates and the ratios to ``rec``."""
    from ...design import order_relaxation  # noqa: PLC0415

    if relaxation_starts > 0 and order < min(nmeas, ncon):
        rel = order_relaxation(P, nmeas, ncon, order, (0.0,), starts=relaxation_starts,
                               seed=seed)
        rec["static_direction_relaxation"] = {
            "value": rel.value, "start_values": list(rel.start_values),
            "sigma_at_zero": rel.sigma_at_frequencies[0],
            "sigma_at_infinity": rel.sigma_at_infinity}
    certificates = _certificates(P, nmeas, ncon, order)
    held = [c for c in certificates if "value" in c]
    if held:
        best = max(held, key=lambda c: c["value"])
        rec["certified_lower_bound"] = best
        if rec["gamma"] is not None and best["value"] > 0:
            rec["ratio_to_certified_bound"] = rec["gamma"] / best["value"]
    rec["static_direction_certificates"] = certificates
    if rec["gamma"] is not None and gstar:
        rec["ratio_to_lower_bound"] = rec["gamma"] / gstar


def _certificates(P, nmeas: int, ncon: int, order: int) -> list[dict[str, Any]]:
    """The static-direction certificate for ``order`` on each side that has static
    directions at that order, at ω = 0 and ∞, or why there is none."""
    from ...design import static_direction_bound  # noqa: PLC0415
    from ...errors import ConfigError  # noqa: PLC0415

    out: list[dict[str, Any]] = []
    exact = np.asarray(P.A).shape[0] <= 60      # exact rationals: seconds at this size
    for side, n_dir in (("control", ncon), ("measurement", nmeas)):
        if order >= n_dir:
            continue
        try:
            c = static_direction_bound(P, nmeas, ncon, order=order, side=side, exact=exact)
        except ConfigError as exc:
            out.append({"side": side, "unavailable": str(exc)})
            continue
        out.append({"side": side, "value": c.value, "exact": c.exact, "estimate": c.estimate,
                    "order": c.order, "directions": c.directions,
                    "frequencies": ["inf" if np.isinf(w) else w for w in c.frequencies],
                    "per_frequency_floor": max(c.per_frequency)})
    return out


def summarize(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians, γ3/γ*, monotonicity in the order and the time-vs-nx exponent of ``records``."""
    def med(v):
        v = [x for x in v if x is not None and np.isfinite(x)]
        return float(np.median(v)) if v else None

    times = [r["wall_time_s"] for r in records]
    ran = [r for r in records if r["nx"] is not None]      # not the plants that failed to load
    nx = np.array([r["nx"] for r in ran], dtype=float)
    t = np.array([r["wall_time_s"] for r in ran], dtype=float)
    fit = None
    if len(set(nx.tolist())) >= 2 and np.all(t > 0):
        p, logc = np.polyfit(np.log(nx), np.log(t), 1)
        fit = {"exponent": float(p), "coefficient_s": float(np.exp(logc)),
               "model": "wall_time_s = coefficient_s * nx ** exponent (least squares in logs)"}
    by_plant: dict[str, list[dict]] = {}
    for r in records:
        by_plant.setdefault(r["plant"], []).append(r)
    monotone = {}
    for name, recs in by_plant.items():
        g = [r["gamma"] for r in sorted(recs, key=lambda r: r["order"])]
        monotone[name] = all(a is not None and b is not None and b <= a * (1 + 1e-9)
                             for a, b in zip(g, g[1:]))
    r3 = [r.get("ratio_to_lower_bound") for r in records if r["order"] == 3]
    best3 = {}
    for r in records:
        if r["order"] == 3 and r["gamma"] is not None:
            bounds = [b for b in (r.get("gamma_lower_bound"),
                                  (r.get("certified_lower_bound") or {}).get("value")) if b]
            if bounds:
                best3[r["plant"]] = r["gamma"] / max(bounds)
    return {"n_records": len(records),
            "all_stable": all(r["stable"] for r in records),
            "failed": sorted({r["plant"] for r in records if "error" in r}),
            "median_wall_time_s": med(times),
            "median_ratio_order3": med(r3),
            "max_ratio_order3": max((x for x in r3 if x is not None), default=None),
            "order3_over_best_lower_bound": best3,
            "gamma_non_increasing": monotone,
            "time_vs_nx": fit,
            "machine": {"cpus": os.cpu_count(),
                        "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg")
                        else None}}


def _write(out: Path, records: list[dict[str, Any]]) -> None:
    with atomic_file(out, what="--out") as tmp:
        tmp.write_text(json.dumps({"records": records, "summary": summarize(records)},
                                  indent=1, default=float))


def _orders(text: str) -> list[int]:
    try:
        orders = [int(o) for o in str(text).split(",") if o.strip()]
    except ValueError:
        orders = []
    if not orders or any(o < 0 for o in orders):
        raise ConfigError(f"--orders {text!r}: give comma-separated integers >= 0, e.g. 0,1,2,3")
    return orders


def _handler(args: argparse.Namespace) -> int:
    orders = _orders(args.orders)
    for name, value in (("--starts", args.starts), ("--jobs", args.jobs)):
        if value < 1:     # the lowest order has no previous controller to start from
            raise ConfigError(f"{name} {value}: give an integer >= 1")
    files = _plant_files(args.plants)
    out = check_output_path(args.out, what="--out", suffixes=(".json",))
    _write(out, [])       # fail before any work when the result cannot be written
    time_limit = args.time_limit if args.time_limit and args.time_limit > 0 else None
    jobs = [(f, orders, args.starts, args.seed, time_limit, args.hinfsyn_timeout,
             max(int(args.relaxation_starts), 0)) for f in files]
    records: list[dict[str, Any]] = []
    if args.jobs > 1:
        # non-daemonic workers: each may start the time-limited hinfsyn child process
        with ProcessPoolExecutor(args.jobs, mp_context=multiprocessing.get_context("spawn")) \
                as pool:
            for chunk in pool.map(run_plant, *zip(*jobs)):
                records += chunk
                _write(out, records)
    else:
        def keep(rec):
            records.append(rec)
            _write(out, records)

        for j in jobs:
            run_plant(*j, on_record=keep)
    print(f"wrote {len(records)} records to {out}", file=sys.stderr)
    broken = sorted({r["plant"] for r in records
                     if r["nx"] is None or r["status"].startswith("internal error")})
    if broken:
        print(f"casflutter bench synthesis: could not run {', '.join(broken)} (see their "
              "records' error)", file=sys.stderr)
        return 1
    missing = [f"{r['plant']} order {r['order']}" for r in records if r["gamma"] is None]
    if missing:
        print(f"casflutter bench synthesis: no stabilising controller for {', '.join(missing)} "
              "(see their records' status)", file=sys.stderr)
        return 1
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
    p.add_argument("--time-limit", type=float, default=0.0,
                   help="optional wall-time budget per plant and order in seconds (0: none; "
                        "the budget is then counted in iterations and is reproducible)")
    p.add_argument("--hinfsyn-timeout", type=float, default=10.0,
                   help="seconds allowed to control.hinfsyn for the full-order comparison "
                        "(0: skip)")
    p.add_argument("--jobs", type=int, default=1, help="plants solved in parallel")
    p.add_argument("--relaxation-starts", type=int, default=0,
                   help="starts of the static-direction relaxation recorded for orders below "
                        "min(ncon, nmeas) (0: not computed)")
    p.set_defaults(func=_handler)
