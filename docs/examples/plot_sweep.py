"""
A resumable parameter sweep (``casflutter sweep``)
==================================================

A study file names an evaluator, the settings held fixed and the swept parameters
(format: :func:`casflutter.study.load_study`).  ``problems/studies/typical_section_grid.toml``
sweeps the mass ratio ``mu`` and the structural damping ``zeta`` of the HP-1 typical section
and collects the flutter speed and frequency of the truth.

:func:`casflutter.study.run_sweep` runs the points on local worker processes (or on a Dask
cluster given a scheduler address) and appends every finished point to a JSON-lines store at
once, so an interrupted sweep resumes where it stopped.  Here the first run is stopped after
five points (``max_points``, as a Ctrl-C would), and the second run computes only the rest.
The worker processes are started with the ``spawn`` method, which imports the main module:
a script that starts a sweep keeps its work under ``if __name__ == "__main__":``.
"""

import os
import tempfile
from dataclasses import replace
from pathlib import Path

import matplotlib.pyplot as plt

from casflutter.pipeline import default_config_path
from casflutter.study import load_study, plot_sweep, run_sweep, sweep_table, write_table

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

studies = default_config_path().parents[1] / "studies"   # the shipped problems/ folder
study = load_study(studies / "typical_section_grid.toml")
if not QUICK:   # a finer mass-ratio grid at full size
    study = replace(study, parameters=tuple(replace(p, num=8) if p.name == "mu" else p
                                            for p in study.parameters))

if __name__ == "__main__":   # worker processes start by importing this file (spawn)
    print(study.name, "evaluator", study.evaluator, "settings", dict(study.settings))
    print("parameters:", study.parameter_names, "points:", len(study.points()))
    folder = Path(tempfile.mkdtemp(prefix="casflutter-sweep-"))
    store = folder / f"{study.name}.jsonl"
    first = run_sweep(study, store=store, workers=2, progress=False, max_points=5)
    print(f"first run:  {first.n_computed} computed, interrupted={first.interrupted}, "
          f"{first.n_left} left")
    second = run_sweep(study, store=store, workers=2, progress=False)
    print(f"second run: {second.n_resumed} resumed from the store, {second.n_computed} computed, "
          f"{second.n_failed} failed, executor {second.executor}; "
          f"worker start-up {second.startup_time:.1f} s, wall {second.wall_time:.2f} s, "
          f"work {second.work_time:.2f} s")

# %%
# The tidy table (one row per point; CSV, and Parquet where pyarrow is installed).
if __name__ == "__main__":
    rows = sweep_table(study, store)
    written = write_table(rows, folder / study.name)
    print("written:", [Path(p).name for p in (written if isinstance(written, (list, tuple))
                                              else [written])])
    print(f"{'mu':>8} {'zeta':>6} {'Vf':>8} {'f [1/t]':>9}  status")
    for r in rows:
        print(f"{r['mu']:8.3f} {r['zeta']:6.3f} {r['Vf']:8.4f} {r['frequency_hz']:9.4f}  {r['status']}")

# %%
# The flutter speed against the mass ratio for each damping value.
if __name__ == "__main__":
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for zeta in sorted({r["zeta"] for r in rows}):
        sel = sorted((r["mu"], r["Vf"]) for r in rows if r["zeta"] == zeta and r["status"] == "ok")
        ax.plot(*zip(*sel), "o-", label=f"zeta = {zeta}")
    ax.set_xscale("log")
    ax.set_xlabel("mass ratio mu")
    ax.set_ylabel("flutter speed index V_f")
    ax.legend(fontsize=8)
    fig.tight_layout()

# %%
# The summary figure of ``casflutter sweep``: every output against every parameter.
if __name__ == "__main__":
    fig = plot_sweep(rows, study.parameter_names, ["Vf", "frequency_hz"])
