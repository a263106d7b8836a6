"""Worker processes for independent pieces of work (a study's points, a run's LCO
simulations and tunnel runs).

Ctrl-C reaches the whole process group, but only the parent acts on it
(:func:`ignore_interrupts` in the workers, :func:`stop_pool` in the parent), so no worker is
left running.

:func:`map_in_processes` forks its workers, on the systems where forking is safe (Linux): a
spawned worker re-imports the ``__main__`` script, and a user's study script without an
``if __name__ == "__main__":`` guard would run again in every worker.  Elsewhere (macOS,
Windows) it runs the jobs in the calling process.  The study runner spawns its own workers
(its points import what they need).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Sequence

__all__ = ["available_cores", "ignore_interrupts", "stop_pool", "map_in_processes"]


def _can_fork() -> bool:
    """Forking is available and safe (not on macOS, whose system libraries may not be used
    in a forked child)."""
    return sys.platform.startswith("linux") and \
        "fork" in multiprocessing.get_all_start_methods()


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def ignore_interrupts() -> None:
    """Worker initializer: Ctrl-C is the parent's to act on."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def stop_pool(ex: ProcessPoolExecutor, timeout: float = 5.0) -> None:
    """Cancel what is queued and stop the worker processes now (what they are computing is
    lost); none is left running."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        try:
            proc.terminate()
        except (OSError, ValueError, AttributeError):
            pass
    deadline = time.monotonic() + timeout
    for proc in procs:
        try:
            proc.join(max(0.0, deadline - time.monotonic()))
            if proc.is_alive():
                proc.kill()
                proc.join(timeout)
        except (OSError, ValueError, AssertionError, AttributeError):
            pass


def map_in_processes(fn: Callable, jobs: Sequence, workers: int = 0) -> list:
    """``[fn(job) for job in jobs]``, in up to ``workers`` forked processes.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled by name); each job must be picklable, and so
        must its result.
    jobs : sequence
        The independent pieces of work.
    workers : int
        Processes at most; 0: one per job up to :func:`available_cores`.  One process (or
        one job, a process that may not have children, or a system without a safe fork)
        runs the jobs here, in order.

    Returns
    -------
    list
        The results in the order of ``jobs``: the same numbers wherever they were computed,
        since each job carries everything it depends on (its own seed among them).
    """
    n = min(len(jobs), workers or available_cores())
    if n <= 1 or multiprocessing.current_process().daemon or not _can_fork():
        return [fn(job) for job in jobs]
    ex = ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork"),
                             initializer=ignore_interrupts)
    try:
        out = list(ex.map(fn, jobs))
    except BaseException:
        stop_pool(ex)
        raise
    ex.shutdown(wait=True)
    return out
