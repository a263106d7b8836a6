"""The tidy result table of a sweep (CSV, and Parquet where pyarrow is present) and plots."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ._spec import Study
from ._store import PointStore

__all__ = ["sweep_table", "write_table", "plot_sweep"]

_META = ("key", "status", "error", "work_time", "worker")


def sweep_table(study: Study, store: str | Path) -> list[dict[str, Any]]:
    """One row per design point that has a record: ``key, status``, the parameters, the
    outputs (``study.outputs``, or all of them; one named like another column is prefixed
    ``out_``), ``error, work_time, worker``.  ``status`` is ``"ok"`` or ``"failed"``.

    Rows follow the design order; points without a record yet are left out.
    """
    recs = PointStore(store).records()
    rows = []
    out_names: list[str] = list(study.outputs)
    seen = set(out_names)
    for p in study.points():
        rec = recs.get(study.key(p))
        if rec is None:
            continue
        if not study.outputs:
            for name in rec.get("outputs", {}):
                if name not in seen:
                    seen.add(name)
                    out_names.append(name)
        rows.append((p, rec))
    table = []
    for p, rec in rows:
        row: dict[str, Any] = {"key": rec["key"], "status": rec.get("status")}
        row.update(p)
        outs = rec.get("outputs", {}) or {}
        for name in out_names:  # an output named like a column of its own gets "out_"
            col = f"out_{name}" if name in row or name in _META else name
            row[col] = outs.get(name)
        row.update(error=rec.get("error"), work_time=rec.get("work_time"),
                   worker=rec.get("worker"))
        table.append(row)
    return table


def write_table(rows: Sequence[Mapping[str, Any]], path: str | Path) -> list[Path]:
    """Write ``rows`` to ``PATH.csv`` and, when pyarrow is importable, ``PATH.parquet``.

    ``path`` may carry either suffix or none.  Returns the files written.
    """
    path = Path(path)
    base = path.with_suffix("") if path.suffix in (".csv", ".parquet") else path
    base.parent.mkdir(parents=True, exist_ok=True)
    cols: list[str] = []
    for r in rows:
        cols += [c for c in r if c not in cols]
    written = []
    csv_path = base.with_suffix(".csv")
    with open(csv_path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow({c: "" if r.get(c) is None else r.get(c) for c in cols})
    written.append(csv_path)
    try:
        import pyarrow as pa  # noqa: PLC0415
        import pyarrow.parquet as pq  # noqa: PLC0415
    except ImportError:
        return written
    pq_path = base.with_suffix(".parquet")
    pq.write_table(pa.Table.from_pylist([{c: r.get(c) for c in cols} for r in rows]), pq_path)
    written.append(pq_path)
    return written


def _numeric(values) -> np.ndarray:
    out = np.full(len(values), np.nan)
    for i, v in enumerate(values):
        if isinstance(v, bool):
            out[i] = float(v)
        elif isinstance(v, (int, float)) and math.isfinite(v):
            out[i] = float(v)
    return out


def _categories(values) -> list[str] | None:
    """Labels of a parameter's values when any is not a number (lists such as
    ``rom.orders``, strings such as ``"auto"``), in order of first appearance; ``None``
    when every value is a number (plotted on a numeric axis)."""
    def is_number(v):
        return v is None or (isinstance(v, (bool, int, float, np.number)))

    if all(is_number(v) for v in values):
        return None
    labels: list[str] = []
    for v in values:
        if v is not None and _label(v) not in labels:
            labels.append(_label(v))
    return labels


def _label(value) -> str:
    """Tick label of a categorical value (JSON for lists and tables)."""
    if isinstance(value, str):
        return value
    try:
        return json.dumps(value)
    except TypeError:
        return str(value)


def _tick_labels(labels: list[str], width: int = 22) -> list[str]:
    """Labels cut to ``width`` characters; a cut one is numbered (``"2: [[0.1, ...…"``)
    so that the ticks stay distinct."""
    return [lab if len(lab) <= width else f"{k + 1}: {lab[:width - 4]}…"
            for k, lab in enumerate(labels)]


def _positions(values, labels: list[str] | None) -> np.ndarray:
    if labels is None:
        return _numeric(values)
    index = {lab: k for k, lab in enumerate(labels)}
    return np.array([np.nan if v is None else float(index[_label(v)]) for v in values])


def plot_sweep(rows: Sequence[Mapping[str, Any]], parameters: Sequence[str],
               outputs: Sequence[str]):
    """Summary figure: every numeric output against every swept parameter.

    Successful points are dots; failed points are red crosses on the lower edge of each
    panel (their outputs are missing).  A parameter with values that are not numbers
    (list-valued such as ``rom.orders`` or ``sensors.rows``, strings such as ``rom.nf =
    "auto"``) gets a categorical axis: one tick per distinct value, labelled with it.

    Parameters
    ----------
    rows : sequence of mapping
        The table of :func:`sweep_table`.
    parameters : sequence of str
        The swept parameters (columns of the panels).
    outputs : sequence of str
        The outputs (rows of the panels); those with no finite number are left out.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # noqa: PLC0415

    outs = [o for o in outputs if np.isfinite(_numeric([r.get(o) for r in rows])).any()]
    if not outs:
        outs = ["work_time"]
    params = list(parameters)
    fig, axes = plt.subplots(len(outs), len(params), squeeze=False,
                             figsize=(3.2 * len(params) + 0.6, 2.4 * len(outs) + 0.6))
    failed = [r for r in rows if r.get("status") != "ok"]
    ok = [r for r in rows if r.get("status") == "ok"]
    cats = {p: _categories([r.get(p) for r in rows]) for p in params}
    for i, o in enumerate(outs):
        y = _numeric([r.get(o) for r in ok])
        for j, p in enumerate(params):
            ax = axes[i, j]
            x = _positions([r.get(p) for r in ok], cats[p])
            ax.plot(x, y, "o", ms=3.5, alpha=0.8)
            if failed:
                xf = _positions([r.get(p) for r in failed], cats[p])
                ylo = np.nanmin(y) if np.isfinite(y).any() else 0.0
                ax.plot(xf, np.full(xf.size, ylo), "x", color="tab:red", ms=6,
                        label=f"failed ({len(failed)})")
                if i == 0 and j == 0:
                    ax.legend(fontsize="small")
            if cats[p] is not None:
                labels = _tick_labels(cats[p])
                ax.set_xticks(np.arange(len(labels)))
                long = max(len(lab) for lab in labels) > 8
                ax.set_xticklabels(labels, rotation=30 if long else 0,
                                   ha="right" if long else "center", fontsize="small")
                ax.set_xlim(-0.5, len(labels) - 0.5)
            if i == len(outs) - 1:
                ax.set_xlabel(p)
            if j == 0:
                ax.set_ylabel(o)
            ax.grid(True, alpha=0.3)
    fig.suptitle(f"{len(ok)} points ok, {len(failed)} failed")
    fig.tight_layout()
    return fig
