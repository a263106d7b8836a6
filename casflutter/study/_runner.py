"""Run a study: local worker processes (default) or a Dask distributed cluster, resumable.

Every finished point is appended to the :class:`PointStore` the moment its result arrives,
so an interrupted sweep (Ctrl-C, SIGTERM, a killed driver or worker) resumes without
recomputing or losing a point.  An evaluator that raises gives a ``"failed"`` record with
the error text and the sweep goes on (the next run computes the failed points again unless
told not to); when a worker process dies, a fresh pool retries the lost points, and if a
worker dies again the remaining points run one at a time, so that the point that kills its
worker is identified and recorded as failed.

Ctrl-C and SIGTERM stop the worker processes (none is left running) and re-raise
:class:`KeyboardInterrupt`; a sweep holds its store's lock, so a second sweep on the same
store refuses to start.  Progress goes to the logger ``casflutter.study._runner``.
"""

from __future__ import annotations

import logging
import numbers
import os
import socket
import sys
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Mapping

from .._format import result_repr
from .._interrupt import sigterm_raises
from .._logging import PROGRESS, PROGRESS_END
from .._processes import ignore_interrupts, stop_pool
from ..errors import ConfigError
from ._spec import Study
from ._store import PointStore

_log = logging.getLogger(__name__)

__all__ = ["SweepResult", "Progress", "run_sweep", "evaluate_point"]


def evaluate_point(evaluator: str, params: Mapping[str, Any], settings: Mapping[str, Any],
                   key: str) -> dict[str, Any]:
    """Evaluate one point and return its record (never raises for an evaluator error).

    Runs in the worker (process pool or Dask).  ``work_time`` is the evaluator's own wall
    time, the reference for the runner's overhead figures.
    """
    from ._evaluators import get_evaluator  # noqa: PLC0415

    started = time.time()
    t0 = time.perf_counter()
    rec: dict[str, Any] = {"key": key, "params": dict(params),
                           "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        outputs = get_evaluator(evaluator).function(dict(params), dict(settings))
        if not isinstance(outputs, Mapping):
            raise TypeError(f"evaluator {evaluator!r} returned {type(outputs).__name__}, "
                            "not a dict of outputs")
        rec.update(status="ok", outputs=dict(outputs), error=None)
    except Exception as exc:  # noqa: BLE001 - a failed point is data, not a crash
        tb = traceback.format_exception(type(exc), exc, exc.__traceback__)
        rec.update(status="failed", outputs={}, error=f"{type(exc).__name__}: {exc}",
                   traceback="".join(tb[-3:]))
    rec["work_time"] = time.perf_counter() - t0
    rec["started"] = started
    rec["finished"] = time.time()
    return rec


def _preflight(study: Study, todo: Mapping[str, Mapping[str, Any]]) -> None:
    """Run the evaluator's pre-flight check (:attr:`Evaluator.check`) on every point about
    to be submitted; the first invalid one stops the study before anything runs.

    Raises
    ------
    ConfigError
        Names the point (its number in the design and its values) and the evaluator's
        message (the key and what is allowed).
    """
    from ._evaluators import get_evaluator  # noqa: PLC0415

    ev = get_evaluator(study.evaluator)
    if ev.outputs and study.outputs:
        unknown = [o for o in study.outputs if not _known_output(o, ev.outputs)]
        if unknown:
            raise ConfigError(f"study {study.name!r}: outputs {unknown} are not outputs of the "
                              f"evaluator {study.evaluator!r} (it returns "
                              f"{', '.join(ev.outputs)}); fix [study] outputs -- no point "
                              "was run")
    if ev.check is None or not todo:
        return
    settings = study.resolved_settings()
    points = study.points()
    for i, p in enumerate(points):
        if study.key(p) not in todo:
            continue
        try:
            ev.check_point(p, settings)
        except Exception as exc:  # noqa: BLE001 - any failure of the check is a bad point
            values = ", ".join(f"{k} = {v!r}" for k, v in p.items())
            raise ConfigError(f"study {study.name!r}, point {i + 1} of {len(points)} "
                              f"({values}): {type(exc).__name__}: {exc}; no point was run, fix "
                              "the study file ([parameters] / [settings])") from None


def _known_output(name: str, declared) -> bool:
    """A declared output, or one of a declared family (``lco_amplitude_<coordinate>``,
    ``time_<stage>``)."""
    return name in declared or any(name.startswith(d + "_") for d in declared) \
        or name.startswith("time_")


def _warm(evaluator: str) -> None:
    """Worker initializer: import the evaluator's modules before the first point."""
    from ._evaluators import get_evaluator  # noqa: PLC0415

    get_evaluator(evaluator).warm_up()


def _worker_init(evaluator: str) -> None:
    """Initializer of a local worker process: Ctrl-C in the terminal reaches the whole
    process group, but only the driver acts on it (it stops the workers); then warm up."""
    ignore_interrupts()
    _warm(evaluator)


def _ready(_: int = 0) -> int:
    time.sleep(0.02)
    return os.getpid()


def _start_workers(ex: ProcessPoolExecutor, workers: int, timeout: float = 120.0) -> None:
    """Block until every worker process has started and run its initializer."""
    seen: set[int] = set()
    t0 = time.perf_counter()
    while len(seen) < workers and time.perf_counter() - t0 < timeout:
        seen.update(ex.map(_ready, range(2 * workers)))


class Progress:
    """A one-line progress report: points done, failed, left, elapsed, ETA.

    The line goes to the logger ``casflutter.study._runner`` (INFO, marked as progress so
    that the command line redraws it in place on a terminal), at most every ``interval``
    seconds and once at the end; with ``stream`` it is written there instead.
    """

    def __init__(self, total: int, *, skipped: int = 0, enabled: bool = True,
                 stream=None, interval: float | None = None) -> None:
        self.total, self.skipped = total, skipped
        self.done = self.failed = 0
        self.enabled = enabled
        self.stream = stream
        if interval is None:  # redraw often on a terminal, rarely into a log file
            interval = 0.2 if bool(getattr(sys.stderr, "isatty", lambda: False)()) else 2.0
        self.interval = interval
        self.t0 = time.perf_counter()
        self._last = -1e300
        self._t_first: float | None = None

    @property
    def left(self) -> int:
        """Points not yet finished."""
        return self.total - self.skipped - self.done

    def line(self) -> str:
        """The current progress line."""
        now = time.perf_counter()
        el = now - self.t0
        # rate from the first finished point on (worker start-up excluded)
        span = now - self._t_first if self._t_first is not None else 0.0
        rate = (self.done - 1) / span if self.done >= 2 and span > 0 else 0.0
        eta = f", ETA {self.left / rate:.0f} s" if rate > 0 and self.left else ""
        width = 24
        frac = (self.skipped + self.done) / self.total if self.total else 1.0
        bar = "#" * int(round(frac * width))
        return (f"[{bar:<{width}}] {self.skipped + self.done}/{self.total} done "
                f"({self.skipped} resumed), {self.failed} failed, {self.left} left, "
                f"{el:.1f} s{eta}")

    def _emit(self, final: bool) -> None:
        if self.stream is not None:
            self.stream.write(self.line() + "\n")
            self.stream.flush()
        elif _log.isEnabledFor(logging.INFO):
            _log.info(self.line(), extra=PROGRESS_END if final else PROGRESS)

    def update(self, record: Mapping[str, Any] | None = None, *, force: bool = False) -> None:
        """Count one finished record and report (at most every ``interval`` seconds)."""
        if record is not None:
            if self._t_first is None:
                self._t_first = time.perf_counter()
            self.done += 1
            self.failed += record.get("status") != "ok"
        if not self.enabled:
            return
        now = time.perf_counter()
        if force or now - self._last >= self.interval:
            self._emit(final=False)
            self._last = now

    def close(self) -> None:
        """Final line."""
        if self.enabled:
            self._emit(final=True)


@dataclass(frozen=True)
class SweepResult:
    """Outcome of :func:`run_sweep`.

    Attributes
    ----------
    study : Study
        The study that was run.
    store : Path
        The JSON-lines store holding every finished point.
    n_points : int
        Points in the design.
    n_resumed : int
        Points already in the store before this run (not recomputed).
    n_computed : int
        Points finished in this run.
    n_failed : int
        Failed points in the store after this run (all runs).
    n_left : int
        Points still missing (non-zero only after an interruption).
    interrupted : bool
        True when the run stopped early (Ctrl-C, ``max_points``); resume by running again.
    executor : str
        ``"inline"``, ``"processes(N)"`` or ``"dask(ADDRESS)"``.
    wall_time : float
        Seconds from the first submission to the last record (excluding worker start-up).
    startup_time : float
        Seconds to start and warm the workers.
    work_time : float
        Sum of the evaluators' own times of the points computed in this run.
    worker_restarts : int
        Local worker pools replaced after a worker process died.
    """

    __repr__ = result_repr

    study: Study
    store: Path
    n_points: int
    n_resumed: int
    n_computed: int
    n_failed: int
    n_left: int
    interrupted: bool
    executor: str
    wall_time: float
    startup_time: float
    work_time: float
    worker_restarts: int

    @property
    def success(self) -> bool:
        """Every point finished without failure."""
        return self.n_left == 0 and self.n_failed == 0

    def records(self) -> dict[str, dict]:
        """Newest stored record per key."""
        return PointStore(self.store).records()


def default_store_path(study: Study, out_dir: str | Path | None = None) -> Path:
    """``OUT_DIR/NAME.jsonl`` (``OUT_DIR`` defaults to ``sweeps/`` in the working directory)."""
    return Path(out_dir if out_dir is not None else "sweeps") / f"{study.name}.jsonl"


def _failed_record(key: str, params: Mapping[str, Any], error: str) -> dict:
    """The record of a point whose evaluation never returned (the worker was lost)."""
    return {"key": key, "params": dict(params), "status": "failed", "outputs": {},
            "error": error, "work_time": None, "worker": None, "started": None,
            "finished": time.time()}


def _dead_worker_record(key: str, params: Mapping[str, Any], err: BaseException) -> dict:
    return _failed_record(key, params,
                          f"worker process died while computing this point "
                          f"({type(err).__name__}: {err}); it died again when retried alone")


def _finish(rec: dict, store, progress, state: dict, max_points: int | None) -> bool:
    """Store a finished point, show it, count its work; True when ``max_points`` points
    have been computed in this call (the sweep then stops as if interrupted)."""
    store.append(rec)
    progress.update(rec)
    state["work"] += rec.get("work_time") or 0.0
    state["computed"] += 1
    if max_points is not None and state["computed"] >= max_points:
        state["interrupted"] = True
        return True
    return False


def _run_local(study, todo, store, progress, workers, max_points, state) -> None:
    """Process pool; a broken pool is replaced once, then the lost points run one by one."""
    settings = study.resolved_settings()
    ctx = get_context("spawn")
    remaining = dict(todo)
    while remaining:
        t_start = time.perf_counter()
        ex = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_init,
                                 initargs=(study.evaluator,))
        stopped = False
        try:
            # start and warm every worker before timing the work
            _start_workers(ex, workers)
            state["startup"] += time.perf_counter() - t_start
            t_work = time.perf_counter()
            futs = {ex.submit(evaluate_point, study.evaluator, p, settings, k): k
                    for k, p in remaining.items()}
            broken = False
            for fut in as_completed(futs):
                k = futs[fut]
                try:
                    rec = fut.result()
                except BrokenProcessPool:
                    broken = True
                    continue
                remaining.pop(k)
                if _finish(rec, store, progress, state, max_points):
                    stop_pool(ex)  # max_points reached: the running points are not waited for
                    stopped = True
                    break
            state["wall"] += time.perf_counter() - t_work
        except KeyboardInterrupt:  # Ctrl-C or SIGTERM: no worker may outlive the driver
            state["interrupted"] = True
            stop_pool(ex)
            stopped = True
            raise
        finally:
            if not stopped:
                ex.shutdown(wait=True, cancel_futures=True)
        if state["interrupted"] or not broken:
            break
        state["restarts"] += 1
        if state["restarts"] < 2:
            continue  # a worker died: a fresh pool retries the lost points once
        # it died again: one point at a time in a single worker finds the culprit(s)
        _run_one_by_one(study, remaining, store, progress, settings, ctx, max_points, state)
        break


def _run_one_by_one(study, remaining, store, progress, settings, ctx, max_points,
                    state) -> None:
    """Points one at a time in a single worker process (replaced when it dies, and then
    the point it was computing is recorded as failed)."""
    t0 = time.perf_counter()
    ex = None
    try:
        for k, p in list(remaining.items()):
            if ex is None:
                ex = ProcessPoolExecutor(max_workers=1, mp_context=ctx,
                                         initializer=_worker_init, initargs=(study.evaluator,))
            try:
                rec = ex.submit(evaluate_point, study.evaluator, p, settings, k).result()
            except BrokenProcessPool as exc:
                rec = _dead_worker_record(k, p, exc)
                ex.shutdown(wait=True)
                ex = None
            remaining.pop(k)
            if _finish(rec, store, progress, state, max_points):
                return
    except KeyboardInterrupt:
        state["interrupted"] = True
        if ex is not None:
            stop_pool(ex)
            ex = None
        raise
    finally:
        if ex is not None:
            ex.shutdown(wait=True)
        state["wall"] += time.perf_counter() - t0


def _run_dask(study, todo, store, progress, scheduler, max_points, state) -> None:
    """Submit every point to a Dask distributed cluster (an address or a ``Client``)."""
    try:
        from distributed import Client, as_completed as dask_completed  # noqa: PLC0415
    except ImportError:
        raise ConfigError("a Dask scheduler was given but 'distributed' is not installed: "
                          "pip install 'dask[distributed]' (extra 'dask')") from None
    settings = study.resolved_settings()
    t0 = time.perf_counter()
    own = not isinstance(scheduler, Client)
    client = Client(scheduler, timeout=30) if own else scheduler
    try:
        client.run(_warm, study.evaluator)
        state["startup"] += time.perf_counter() - t0
        t_work = time.perf_counter()
        futs = {client.submit(evaluate_point, study.evaluator, p, settings, k, pure=False,
                              key=f"casflutter-point-{k}-{time.time_ns()}"): (k, p)
                for k, p in todo.items()}
        by_key = {f.key: kp for f, kp in futs.items()}
        try:
            for fut in dask_completed(list(futs)):
                k, p = by_key[fut.key]
                try:
                    rec = fut.result()
                except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker after retries
                    rec = _failed_record(k, p, f"{type(exc).__name__}: {exc}")
                if _finish(rec, store, progress, state, max_points):
                    client.cancel(list(futs))
                    break
        except KeyboardInterrupt:
            state["interrupted"] = True
            client.cancel(list(futs))
            raise
        state["wall"] += time.perf_counter() - t_work
    finally:
        if own:
            client.close()


def _check_counts(workers, max_points) -> None:
    if workers is not None and (isinstance(workers, bool)
                                or not isinstance(workers, numbers.Integral) or workers < 0):
        raise ConfigError(f"workers = {workers!r}: give 0 (run in this process) or a positive "
                          "number of worker processes")
    if max_points is not None and (isinstance(max_points, bool)
                                   or not isinstance(max_points, numbers.Integral)
                                   or max_points < 0):
        raise ConfigError(f"max_points = {max_points!r}: give a number of points >= 0 (0 "
                          "computes nothing), or leave it out for all")


def run_sweep(study: Study, *, store: str | Path | None = None, workers: int | None = None,
              scheduler=None, progress: bool = True, retry_failed: bool = True,
              max_points: int | None = None) -> SweepResult:
    """Run (or resume) a study and store every finished point.

    Parameters
    ----------
    study : Study
        The study (:func:`load_study`).
    store : str or Path, optional
        JSON-lines store (default ``sweeps/NAME.jsonl``); points already in it are skipped.
    workers : int, optional
        Local worker processes (default ``study.workers``); ``0`` runs in this process.
    scheduler : str or distributed.Client, optional
        Dask scheduler address ``tcp://HOST:PORT`` (or a client); default
        ``study.scheduler``.  When given, ``workers`` is ignored.
    progress : bool
        Report progress (logger ``casflutter.study._runner``, INFO).
    retry_failed : bool
        Compute the points stored as failed again (default); ``False`` keeps their failed
        records and counts them as done.
    max_points : int, optional
        Stop after this many points (the run is then ``interrupted``; run again to resume);
        ``0`` computes nothing.

    Returns
    -------
    SweepResult

    Raises
    ------
    ConfigError
        ``workers`` or ``max_points`` that is not a non-negative integer; study outputs that
        the evaluator does not return; a point that the evaluator's pre-flight check
        (:attr:`Evaluator.check`, e.g. the ``pipeline`` evaluator's configuration
        validation) rejects: every point is checked before any is submitted, and nothing
        runs.
    StoreLockedError
        Another sweep is running on the same store.
    KeyboardInterrupt
        Re-raised after Ctrl-C or SIGTERM (:class:`casflutter._interrupt.Terminated`, when
        the application has not set its own SIGTERM handler); the worker processes are
        stopped and every point finished before it is stored.

    Notes
    -----
    Local workers are *spawned* processes that import the calling script: a script that
    calls :func:`run_sweep` with ``workers >= 1`` must guard its top level with
    ``if __name__ == "__main__":`` (otherwise every worker runs the sweep again and
    Python stops it with a ``RuntimeError`` about bootstrapping).
    """
    _check_counts(workers, max_points)
    store_path = Path(store) if store is not None else default_store_path(study)
    pstore = PointStore(store_path)
    with pstore.lock(), sigterm_raises(only_if_default=True):
        return _run_locked(study, pstore, workers, scheduler, progress, retry_failed,
                           max_points)


def _run_locked(study, pstore, workers, scheduler, progress, retry_failed,
                max_points) -> SweepResult:
    points = study.points()
    keyed = {study.key(p): p for p in points}
    finished = pstore.finished_keys(include_failed=not retry_failed)
    if pstore.skipped_lines:
        _log.warning("store %s: %d line(s) that are not readable records were skipped (torn "
                     "by a kill, or not UTF-8 JSON); their points, if any, are computed again",
                     pstore.path, pstore.skipped_lines)
    todo = {k: p for k, p in keyed.items() if k not in finished}
    n_resumed = len(keyed) - len(todo)
    _preflight(study, todo)
    if max_points == 0:
        todo = {}
    prog = Progress(len(keyed), skipped=n_resumed, enabled=progress)
    state = {"startup": 0.0, "wall": 0.0, "work": 0.0, "computed": 0, "restarts": 0,
             "interrupted": False}
    scheduler = scheduler if scheduler is not None else study.scheduler
    workers = study.workers if workers is None else int(workers)
    if scheduler is not None:
        address = scheduler if isinstance(scheduler, str) else getattr(
            getattr(scheduler, "scheduler", None), "address", repr(scheduler))
        executor = f"dask({address})"
    elif workers == 0:
        executor = "inline"
    else:
        executor = f"processes({workers})"
    prog.update(force=True)
    try:
        if not todo:
            pass
        elif scheduler is not None:
            _run_dask(study, todo, pstore, prog, scheduler, max_points, state)
        elif workers == 0:
            settings = study.resolved_settings()
            t0 = time.perf_counter()
            _warm(study.evaluator)
            state["startup"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            for k, p in todo.items():
                rec = evaluate_point(study.evaluator, p, settings, k)
                if _finish(rec, pstore, prog, state, max_points):
                    break
            state["wall"] = time.perf_counter() - t0
        else:
            _run_local(study, todo, pstore, prog, workers, max_points, state)
    finally:
        prog.close()
    recs = pstore.records()
    in_design = [recs[k] for k in keyed if k in recs]
    n_left = len(keyed) - len(in_design)
    n_failed = sum(r.get("status") != "ok" for r in in_design)
    if n_failed:
        _log.debug("study %s: %d failed point(s) in %s", study.name, n_failed, pstore.path)
    return SweepResult(
        study=study, store=pstore.path, n_points=len(keyed), n_resumed=n_resumed,
        n_computed=state["computed"], n_failed=n_failed,
        n_left=n_left, interrupted=bool(state["interrupted"] or n_left > 0), executor=executor,
        wall_time=state["wall"], startup_time=state["startup"], work_time=state["work"],
        worker_restarts=state["restarts"])
