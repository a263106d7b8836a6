"""``casflutter identify``: ``--dt`` takes the sampling time in seconds or, for a MATLAB
file, the name of the variable holding it (as the error of a .mat file without one says);
``--nf`` is a positive integer or ``auto``, 0 refused before the work."""

import json

import numpy as np
import pytest
from scipy.io import savemat

import casflutter.ident as ident
from casflutter.cli import main
from casflutter.ident import random_hwl_model, synthetic_data

ORDERS = "2,1,1,1,2,2"


@pytest.fixture(scope="module")
def records():
    truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1)
    return synthetic_data(truth, 1200, seed=2, noise=0.0)


@pytest.fixture()
def mat(records, tmp_path):
    rec = records.records[0]
    path = tmp_path / "rec.mat"
    savemat(path, {"y": rec.y, "u": rec.u, "Ts": records.dt})
    return path


def _no_identify(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("identify ran although an argument was invalid")
    monkeypatch.setattr(ident, "identify", boom)


def test_a_mat_file_without_dt_says_how_to_give_it(mat, capsys, monkeypatch):
    _no_identify(monkeypatch)
    assert main(["identify", str(mat), "--y", "y", "--u", "u", "--orders", ORDERS]) == 1
    err = capsys.readouterr().err
    assert "--dt" in err and "variable" in err


def test_dt_names_the_variable_of_a_mat_file(mat, records, capsys):
    assert main(["identify", str(mat), "--y", "y", "--u", "u", "--dt", "Ts", "--orders",
                 ORDERS, "--json"]) == 0
    by_name = json.loads(capsys.readouterr().out)
    assert main(["identify", str(mat), "--y", "y", "--u", "u", "--dt", str(records.dt),
                 "--orders", ORDERS, "--json"]) == 0
    by_value = json.loads(capsys.readouterr().out)
    assert by_name["success"] and by_name["nf"] == by_value["nf"]
    assert by_name["fit_error_percent"] == by_value["fit_error_percent"]


def test_dt_a_name_for_another_format_is_refused(tmp_path, records, capsys, monkeypatch):
    _no_identify(monkeypatch)
    path = tmp_path / "rec.npz"
    records.to_npz(path)
    assert main(["identify", str(path), "--dt", "Ts", "--orders", ORDERS]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--dt 'Ts'" in err[0] and "seconds" in err[0]


@pytest.mark.parametrize("nf", ["0", "-2", "x", "1.5"])
def test_nf_zero_or_not_a_positive_integer_is_refused(tmp_path, records, nf, capsys,
                                                       monkeypatch):
    _no_identify(monkeypatch)
    path = tmp_path / "rec.npz"
    records.to_npz(path)
    assert main(["identify", str(path), "--orders", ORDERS, f"--nf={nf}"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--nf" in err[0] and "--nf auto" in err[0]


@pytest.mark.parametrize("nf, expected", [("auto", None), ("3", 3)])
def test_nf_auto_or_an_order(tmp_path, records, nf, expected, capsys):
    path = tmp_path / "rec.npz"
    records.to_npz(path)
    assert main(["identify", str(path), "--orders", ORDERS, "--nf", nf, "--json"]) == 0
    order = json.loads(capsys.readouterr().out)["nf"]
    assert order == expected if expected is not None else order >= 1
    assert np.isfinite(order)
