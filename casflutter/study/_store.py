"""Append-only store of finished sweep points (JSON lines, one fsync per record).

Every finished point (success or failure) is one line ``{"key", "status", "params",
"outputs", "error", "work_time", ...}`` appended with ``flush`` + ``os.fsync`` as soon as it
completes, so a killed sweep loses at most the line being written; a torn last line, and any
line that is not UTF-8 JSON (a stray byte, an editor's mess), is skipped on reading.
Resuming skips every key already present (failed keys are computed again unless asked not
to), and the newest record of a key wins.

A running sweep holds the store's lock (:meth:`PointStore.lock`, an ``fcntl`` lock on
``NAME.jsonl.lock``, released by the system when the process ends, however it ends), so a
second sweep on the same store refuses to start instead of computing every point twice.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import logging
import math
import os
import socket
from pathlib import Path
from typing import Any, Iterator, Mapping

from ..errors import OutputError, StoreLockedError

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows: no lock
    fcntl = None

__all__ = ["PointStore"]

_log = logging.getLogger(__name__)


def _clean(obj: Any) -> Any:
    """JSON-safe copy: non-finite floats become ``None`` (strict JSON), numpy to Python."""
    if isinstance(obj, Mapping):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if hasattr(obj, "item") and callable(obj.item) and getattr(obj, "ndim", 1) == 0:
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, (str, int, float, bool)) or obj is None:
        return obj
    return str(obj)


class PointStore:
    """JSON-lines store of finished points, keyed by :func:`point_key`.

    Parameters
    ----------
    path : str or Path
        The ``.jsonl`` file (created with its folder when missing).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(f"sweep store {self.path}: its folder cannot be created "
                              f"({exc.strerror or exc}); choose another output folder") from None
        #: Lines skipped by the last full read (torn, not UTF-8, not a JSON record).
        self.skipped_lines = 0

    @property
    def lock_path(self) -> Path:
        """The lock file beside the store (``NAME.jsonl.lock``)."""
        return self.path.with_name(self.path.name + ".lock")

    def __iter__(self) -> Iterator[dict]:
        """Every valid record in file order (torn, undecodable or corrupt lines skipped and
        counted in :attr:`skipped_lines`)."""
        if not self.path.exists():
            self.skipped_lines = 0
            return
        skipped = 0
        with open(self.path, "rb") as fh:
            for raw in fh:
                raw = raw.strip()
                if not raw:
                    continue
                try:
                    rec = json.loads(raw.decode("utf-8"))
                except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
                    skipped += 1  # a line torn by a kill during the write, or garbage
                    continue
                if isinstance(rec, dict) and isinstance(rec.get("key"), str):
                    yield rec
                else:
                    skipped += 1
        self.skipped_lines = skipped
        if skipped:
            _log.debug("store %s: %d unreadable line(s) skipped", self.path, skipped)

    def records(self) -> dict[str, dict]:
        """Newest record of every key."""
        out: dict[str, dict] = {}
        for rec in self:
            out[rec["key"]] = rec
        return out

    def finished_keys(self, *, include_failed: bool = True) -> set[str]:
        """Keys already finished (``include_failed=False``: successful ones only)."""
        return {k for k, r in self.records().items()
                if include_failed or r.get("status") == "ok"}

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the store's lock while the block runs (one sweep per store at a time).

        Raises
        ------
        StoreLockedError
            Another process holds it; the message names its pid, host and start time.
        """
        if fcntl is None:  # pragma: no cover
            _log.debug("no fcntl on this platform: store %s is not locked", self.path)
            yield
            return
        fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                try:
                    holder = os.pread(fd, 512, 0).decode("utf-8", "replace").strip()
                except OSError:
                    holder = ""
                raise StoreLockedError(
                    f"store {self.path} is in use by another sweep"
                    f"{' (' + holder + ')' if holder else ''}; wait for it to finish, or give "
                    "another output folder (--out) to run a separate copy") from None
            stamp = datetime.datetime.now().isoformat(timespec="seconds")
            info = f"pid {os.getpid()} on {socket.gethostname()}, since {stamp}"
            os.ftruncate(fd, 0)
            os.pwrite(fd, info.encode(), 0)
            try:
                yield
            finally:
                os.ftruncate(fd, 0)
                fcntl.flock(fd, fcntl.LOCK_UN)
        finally:
            os.close(fd)

    def append(self, record: Mapping[str, Any]) -> None:
        """Append one record durably (``flush`` and ``os.fsync`` before returning)."""
        if "key" not in record:
            raise ValueError("a stored record needs a 'key'")
        line = json.dumps(_clean(record), separators=(",", ":"), allow_nan=False)
        # a torn last line (killed during a write) must not glue onto this record
        needs_nl = False
        if self.path.exists() and self.path.stat().st_size > 0:
            with open(self.path, "rb") as fh:
                fh.seek(-1, os.SEEK_END)
                needs_nl = fh.read(1) != b"\n"
        with open(self.path, "a", encoding="utf-8") as fh:
            fh.write(("\n" if needs_nl else "") + line + "\n")
            fh.flush()
            os.fsync(fh.fileno())
