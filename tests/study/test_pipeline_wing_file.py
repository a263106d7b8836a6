"""The ``pipeline`` and ``rom_flutter`` evaluators on a wing file (the shipped
``problems/example_wing``): no truth simulator, so the truth's columns are missing values,
not a failed point."""

import json
from pathlib import Path

import pytest

from casflutter.cli import main
from casflutter.study import (Parameter, Study, flatten_summary, run_sweep, sweep_table)

ROOT = Path(__file__).resolve().parents[2] / "problems"
WING_RUN = ROOT / "example_wing" / "run.toml"

#: what ``summary.json`` holds for a wing file run with ``stages = []`` (abridged)
WING_SUMMARY = {
    "problem": "example_wing", "route": "wing", "V0": 0.69, "n_sensors": 2,
    "orders": [1, 2, 5, 0, 1, 1], "n_params": 260,
    "fit_error_percent": [0.11, 10.97, 0.17, 0.28, 0.23], "nf": 28, "ns": 10, "nae": 38,
    "flutter": {"V": 1.2382, "freq_hz": 9.2033, "mode": 2, "status": "flutter"},
    "flutter_truth": None, "lco": None, "controller": None, "suppression": None,
    "timings_s": {"data": 0.0, "rom": 0.02, "total": 0.5}, "seed": 0,
}


def test_flatten_summary_of_a_run_without_a_truth():
    row = flatten_summary(WING_SUMMARY)
    assert row["Vf_rom"] == 1.2382 and row["mode_rom"] == 2
    assert row["Vf_truth"] is None and row["freq_hz_truth"] is None and row["mode_truth"] is None
    assert row["lco_V"] is None and row["controller_order"] is None
    assert row["fit_error_max"] == 10.97 and row["nf"] == 28 and row["time_total"] == 0.5


def test_flatten_summary_of_a_route_without_an_identified_rom():
    # a GAF file: an RFA, no fit error, no HWL sizes
    gaf = {**WING_SUMMARY, "route": "gaf", "fit_error_percent": None, "n_params": None,
           "V0": None, "orders": None}
    row = flatten_summary(gaf)
    assert row["fit_error_max"] is None and row["n_params"] is None
    assert row["Vf_rom"] == 1.2382 and row["Vf_truth"] is None


def test_flatten_summary_keeps_a_diverged_fit_visible():
    # a ROM whose free run diverges has a NaN fit error: the largest is NaN, not the others'
    row = flatten_summary({**WING_SUMMARY, "fit_error_percent": [1.0, float("nan")]})
    assert row["fit_error_max"] != row["fit_error_max"]


def _study(evaluator: str) -> Study:
    return Study(name=f"wing_{evaluator}", evaluator=evaluator, design="grid",
                 parameters=(Parameter("flutter.n_grid", values=(61,)),),
                 settings={"config": str(WING_RUN), "stages": []})


@pytest.mark.parametrize("evaluator", ["pipeline", "rom_flutter"])
def test_a_sweep_on_a_wing_file_runs_every_point(tmp_path, evaluator):
    study = _study(evaluator)
    res = run_sweep(study, store=tmp_path / "s.jsonl", workers=0, progress=False)
    assert (res.n_failed, res.n_left) == (0, 0)
    row = sweep_table(study, res.store)[0]
    assert row["status"] == "ok", row.get("error")
    assert row["Vf_truth"] is None
    assert row["Vf_rom"] == pytest.approx(1.2382, abs=1e-3)


def test_the_sweep_command_on_a_wing_file_exits_zero(tmp_path, capsys):
    study = tmp_path / "wing.toml"
    study.write_text(f"""
[study]
name = "wing"
evaluator = "pipeline"
design = "grid"

[settings]
config = {json.dumps(str(WING_RUN))}
stages = []

[parameters]
"flutter.n_grid" = [61]
""")
    out = tmp_path / "out"
    rc = main(["sweep", str(study), "--workers", "0", "--out", str(out), "--no-progress",
               "--no-plot", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 0 and summary["failed"] == 0 and summary["computed"] == 1
    header = (out / "wing.csv").read_text().splitlines()[0].split(",")
    assert "Vf_rom" in header and "error" in header
