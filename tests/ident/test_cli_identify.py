"""``casflutter identify`` and ``casflutter bench identify``: arguments checked before the
work, one-line errors, valid JSON, non-zero exit on failure, --search."""

import json
import math

import numpy as np
import pytest

import casflutter.ident as ident
from casflutter.cli import main
from casflutter.cli.commands.identify import _finite
from casflutter.data import IOData
from casflutter.errors import ConvergenceError
from casflutter.ident import random_hwl_model, synthetic_data


@pytest.fixture(scope="module")
def npz(tmp_path_factory):
    truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1)
    path = tmp_path_factory.mktemp("data") / "rec.npz"
    synthetic_data(truth, 1500, seed=2, noise=0.02).to_npz(path)
    return path


def _no_identify(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("identify ran although an argument was invalid")
    monkeypatch.setattr(ident, "identify", boom)
    monkeypatch.setattr(ident, "select_orders", boom)


@pytest.mark.parametrize("value", ["-1", "nan", "inf", "abc"])
def test_bad_regularization_one_line_error(npz, value, capsys, monkeypatch):
    _no_identify(monkeypatch)
    assert main(["identify", str(npz), f"--regularization={value}"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--regularization" in err[0] and ">= 0" in err[0]


@pytest.mark.parametrize("orders", ["3,1,1", "3,1,1,1,2,nan", "3,1,1,1,2,2.5", "a,b,c,d,e,f"])
def test_bad_orders_one_line_error(npz, orders, capsys, monkeypatch):
    _no_identify(monkeypatch)
    assert main(["identify", str(npz), "--orders", orders]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "order" in err[0]


def test_out_checked_before_the_work(npz, tmp_path, capsys, monkeypatch):
    _no_identify(monkeypatch)
    afile = tmp_path / "afile"
    afile.write_text("x")
    for out, msg in [(afile / "sub" / "m.npz", "is a file, not a folder"),
                     (tmp_path, "is a folder")]:
        assert main(["identify", str(npz), "--out", str(out)]) == 1
        err = capsys.readouterr().err
        assert "--out" in err and msg in err


def test_out_folder_is_created(npz, tmp_path, capsys):
    """As every other command's --out: a missing folder is created when the model is
    written, not refused after the path check."""
    out = tmp_path / "new" / "deeper" / "m.npz"
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--out", str(out)]) == 0
    assert ident.HWLModel.load(out).orders.as_tuple() == (2, 1, 1, 1, 2, 2)


def test_json_is_valid_and_out_written(npz, tmp_path, capsys):
    out = tmp_path / "model.npz"
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--criterion",
                 "simulation", "--json", "--out", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "Solve_Succeeded" and doc["success"] is True
    assert doc["solver"] == "gauss-newton"
    assert all(0 < e < 5 for e in doc["fit_error_percent"])
    assert ident.HWLModel.load(out).orders.as_tuple() == (2, 1, 1, 1, 2, 2)


def test_out_is_never_left_half_written(npz, tmp_path, capsys, monkeypatch):
    """The model is written under a temporary name and renamed: a failure while writing
    leaves the previous file as it was and no temporary file behind."""
    out = tmp_path / "model.npz"
    out.write_bytes(b"previous model")
    real_save = ident.HWLModel.save

    def fails_midway(self, fh):
        fh.write(b"PK\x03\x04 half a zip")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ident.HWLModel, "save", fails_midway)
    args = ["identify", str(npz), "--orders", "2,1,1,1,2,2", "--json", "--out", str(out)]
    assert main(args) == 1
    assert "No space left on device" in capsys.readouterr().err
    assert out.read_bytes() == b"previous model" and sorted(tmp_path.iterdir()) == [out]
    monkeypatch.setattr(ident.HWLModel, "save", real_save)
    stem = tmp_path / "rom"                    # numpy's rule: savez adds .npz
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--out", str(stem)]) == 0
    assert f"model written to {stem}.npz" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.npz", "rom.npz"]
    assert ident.HWLModel.load(tmp_path / "rom.npz").orders.as_tuple() == (2, 1, 1, 1, 2, 2)


def test_json_null_for_non_finite():
    assert _finite([1.0, math.nan, math.inf]) == [1.0, None, None]
    assert json.dumps({"x": _finite(np.float64("nan"))}, allow_nan=False) == '{"x": null}'


def test_unstable_fit_exits_non_zero(npz, capsys, monkeypatch):
    """A fit whose free run diverges is a failure: exit 1 and one line, never exit 0."""
    real = ident.identify

    def unstable(data, orders, **kw):
        truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1)
        c = truth.coefficients()
        c["A"] = 8 * c["A"]
        bad = ident.HWLModel.from_coefficients(truth.orders, dt=data.dt, **c)
        return real(data, orders, initial=bad, refine=False)

    monkeypatch.setattr(ident, "identify", unstable)
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--json"]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert len(captured.err.strip().splitlines()) == 1 and "unstable" in captured.err


def test_search_prints_table_and_refits(npz, capsys):
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--criterion", "simulation",
                 "--search", "na=1,2 q=1,2"]) == 0
    out = capsys.readouterr().out
    assert "held-out" in out and out.count("Solve_Succeeded") >= 4
    assert "identifying (mu, na, nb, r, p, q) = (2, 1, 1, 1, 2, 2) on all the data" in out


def test_bench_identify_simulation_small(tmp_path, capsys):
    """The benchmark's JSON keys and its scipy reference on a small paper-structure case;
    the missing folder of --out is created."""
    out = tmp_path / "new" / "b.json"
    assert main(["bench", "identify", "--criterion", "simulation", "--samples", "600",
                 "--repeat", "1", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    for key in ("problem", "criterion", "n_params", "fit_error_percent", "t_stage1_s",
                "t_stage2_s", "t_total_s", "cost", "cost_initial", "ipopt_status",
                "ipopt_iterations", "repeats", "scipy_reference", "scipy_reduced_reference",
                "speedup_stage2_vs_scipy"):
        assert key in doc
    assert doc["criterion"] == "simulation" and doc["ipopt_status"] == "Solve_Succeeded"
    assert doc["cost"] <= doc["scipy_reference"]["cost"] * (1 + 1e-9)
    assert doc["cost"] <= doc["cost_initial"]


def test_bench_identify_out_checked_before_the_work(tmp_path, capsys, monkeypatch):
    from casflutter.cli.bench import identify as bench_identify

    monkeypatch.setattr(bench_identify, "run", lambda *a, **k: pytest.fail("ran"))
    assert main(["bench", "identify", "--out", str(tmp_path / "b.txt")]) == 1
    assert "--out" in capsys.readouterr().err


def test_max_time_exits_one_with_one_line(npz, capsys):
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--criterion", "simulation",
                 "--max-time", "1e-9"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert any("warning" in e and "max_time" in e for e in err)
    assert err[-1].startswith("casflutter: identification stopped at --max-time")


def test_nan_fit_is_a_failure(npz, capsys, monkeypatch):
    """A fit that cannot be scored (a NaN error, e.g. orders 10,5,5,5,5,5) is never reported
    as Solve_Succeeded with exit 0: identify raises, the CLI prints one line and exits 1."""
    import casflutter.ident._identify as core

    real_report = core.fit_report

    def nan_report(model, data, mode="simulation", skip=None):
        rep = real_report(model, data, mode, skip)
        if mode != "simulation":
            return rep
        pct = np.array(rep.error_percent, dtype=float)
        pct[-1] = math.nan
        return type(rep)(rep.mode, pct, rep.nrmse, rep.rms_error, rep.skip)

    monkeypatch.setattr(core, "fit_report", nan_report)
    data = IOData.from_npz(npz)
    with pytest.raises(ConvergenceError, match=r"not a finite number for output\(s\) y2") as exc:
        ident.identify(data, (2, 1, 1, 1, 2, 2), criterion="simulation")
    assert exc.value.result.success is False
    assert exc.value.result.return_status == "Non_Finite_Fit"
    assert main(["identify", str(npz), "--orders", "2,1,1,1,2,2", "--criterion",
                 "simulation", "--json"]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    errors = [ln for ln in captured.err.splitlines() if ln.startswith("casflutter: error")]
    assert len(errors) == 1 and "not a finite number" in errors[0]
    assert "Traceback" not in captured.err
