"""The ``sweep``, ``sensitivity`` and ``bench sweep`` commands."""

import json

import numpy as np
import pytest

from casflutter.cli import main
from casflutter.study import flutter_sensitivity

STUDY = """
[study]
name = "cli_grid"
evaluator = "truth_flutter"
design = "grid"
outputs = ["flutter_status", "Vf", "omega_f"]

[settings]
problem = "typical_section"

[parameters]
mu = [15.0, 20.0]
zeta = [0.0, 0.01]
"""


def test_sweep_command_runs_writes_and_resumes(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(STUDY)
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--workers", "0", "--out", str(out), "--max-points", "3"]) == 1
    first = capsys.readouterr()
    assert "3 computed, 0 resumed" in first.out and "resume" in first.out
    assert "left" in first.err  # progress line
    assert main(["sweep", str(f), "--workers", "0", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["computed"], summary["resumed"], summary["failed"], summary["left"]) == (1, 3, 0, 0)
    assert (out / "cli_grid.csv").is_file() and (out / "cli_grid.png").is_file()
    lines = (out / "cli_grid.csv").read_text().splitlines()
    assert lines[0].startswith("key,status,mu,zeta,flutter_status,Vf,omega_f") and len(lines) == 5
    assert all(",ok," in ln and ",flutter," in ln for ln in lines[1:])


def test_sweep_command_lists_evaluators_and_rejects_bad_files(tmp_path, capsys):
    assert main(["sweep", "--list"]) == 0
    listing = capsys.readouterr().out
    assert "truth_flutter" in listing and "truth_hopf" in listing
    bad = tmp_path / "bad.toml"
    bad.write_text('[study]\nevaluator = "nope"\n[parameters]\nx = [1.0]\n')
    assert main(["sweep", str(bad), "--workers", "0", "--out", str(tmp_path)]) == 1
    assert "unknown evaluator 'nope'" in capsys.readouterr().err


def test_sensitivity_command_ranks_and_checks(tmp_path, capsys):
    f = tmp_path / "c.toml"
    f.write_text('[sensitivity]\nproblem = "typical_section"\n'
                 'parameters = ["a", "mu", "sigma"]\n[params]\nzeta = 0.01\n')
    assert main(["sensitivity", str(f), "--json", "--check"]) == 0
    data = json.loads(capsys.readouterr().out)
    ref = flutter_sensitivity("typical_section", ["a", "mu", "sigma"], params={"zeta": 0.01})
    assert [r["name"] for r in data["sensitivities"]] == [s.name for s in ref.ranked()]
    for row in data["sensitivities"]:
        np.testing.assert_allclose(row["dVf_dp"], ref[row["name"]].dVf_dp, rtol=1e-12)
        np.testing.assert_allclose(row["dVf_dp"], row["dVf_dp_fd"], rtol=2e-6)
    assert main(["sensitivity", str(f), "--method", "nlp"]) == 0
    table = capsys.readouterr().out
    assert "parametric NLP" in table and table.splitlines()[2].split()[1] == ref.ranked()[0].name


@pytest.mark.slow
def test_bench_sweep_writes_json(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["bench", "sweep", "--points", "4", "--repeats", "1", "--lco-time", "50",
                 "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    for key in ("local_1_workers", "local_2_workers", "dask_2_workers"):
        assert data[key]["failed"] == 0 and data[key]["wall_time"] > 0
        assert data[key]["work_time"] > 0
    np.testing.assert_allclose(data["speedup_2_vs_1"], data["local_1_workers"]["wall_time"]
                               / data["local_2_workers"]["wall_time"])


def test_sensitivity_example_config_runs(capsys):
    from pathlib import Path

    cfg = Path(__file__).resolve().parents[2] / "problems" / "studies" / "sensitivity_hp1.toml"
    assert main(["sensitivity", str(cfg), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["params"]["zeta"] == 0.01 and len(data["sensitivities"]) == 7


def test_sensitivity_command_gamma_table(tmp_path, capsys):
    from . import _evals
    from .test_gamma import gamma_star

    f = tmp_path / "g.toml"
    f.write_text(f'[gamma]\nplant = "{_evals.__name__}:first_order_plant"\nnmeas = 1\n'
                 'ncon = 1\norder = 0\nstarts = 2\nseed = 1\ntol = 1e-12\n'
                 '[params]\na = -1.0\nrho = 0.7\n')
    assert main(["sensitivity", str(f), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(data["gamma"], gamma_star(-1.0, 0.7), rtol=1e-6)
    h = 1e-5
    fd = {"a": (gamma_star(-1 + h, 0.7) - gamma_star(-1 - h, 0.7)) / (2 * h),
          "rho": (gamma_star(-1, 0.7 + h) - gamma_star(-1, 0.7 - h)) / (2 * h)}
    assert [r["name"] for r in data["sensitivities"]] == ["rho", "a"]
    for r in data["sensitivities"]:
        np.testing.assert_allclose(r["dgamma_dp"], fd[r["name"]], rtol=1e-6)
    assert main(["sensitivity", str(f)]) == 0
    assert "gamma* = 0.573462 " in capsys.readouterr().out      # 6 significant digits
