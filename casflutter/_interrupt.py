"""SIGTERM handled like Ctrl-C: long runs (sweeps, the command line) stop their worker
processes and leave their stores resumable instead of dying with orphaned workers."""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Iterator

__all__ = ["Terminated", "sigterm_raises"]


class Terminated(KeyboardInterrupt):
    """Raised in the main thread on SIGTERM (a :class:`KeyboardInterrupt`, so that every
    clean-up written for Ctrl-C runs)."""


def _raise_terminated(signum, frame):
    raise Terminated()


@contextlib.contextmanager
def sigterm_raises(*, only_if_default: bool = False) -> Iterator[bool]:
    """While the block runs, SIGTERM raises :class:`Terminated` in the main thread.

    Parameters
    ----------
    only_if_default : bool
        Leave an application's own SIGTERM handler in place (install only over the default
        action); library code passes True.

    Yields
    ------
    bool
        Whether the handler was installed (not outside the main thread, nor on platforms
        without SIGTERM).
    """
    if threading.current_thread() is not threading.main_thread() \
            or not hasattr(signal, "SIGTERM"):
        yield False
        return
    previous = signal.getsignal(signal.SIGTERM)
    if only_if_default and previous not in (signal.SIG_DFL, None):
        yield False
        return
    try:
        signal.signal(signal.SIGTERM, _raise_terminated)
    except (ValueError, OSError):
        yield False
        return
    try:
        yield True
    finally:
        try:
            signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)
        except (ValueError, OSError):
            pass
