"""Append-only store of finished sweep points (JSON lines, one fsync per record).

Every finished point (success or failure) is one line ``{"key", "status", "params",
"outputs", "error", "work_time", ...}`` appended with ``flush`` + ``os.fsync`` as soon as it
completes, so a killed sweep loses at most the line being written; a torn last line is
ignored on reading.  Resuming skips every key already present; with ``retry_failed`` the
failed keys are computed again and the newest record of a key wins.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Iterator, Mapping

__all__ = ["PointStore"]


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
        self.path.parent.mkdir(parents=True, exist_ok=True)

    def __iter__(self) -> Iterator[dict]:
        """Every valid record in file order (torn or corrupt lines skipped)."""
        if not self.path.exists():
            return
        with open(self.path, encoding="utf-8") as fh:
            for line in fh:
                line = line.strip()
                if not line:
                    continue
                try:
                    rec = json.loads(line)
                except json.JSONDecodeError:
                    continue  # a line torn by a kill during the write
                if isinstance(rec, dict) and "key" in rec:
                    yield rec

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
