"""``casflutter run`` on a plant family file: the multi-speed design on state-space models at
a grid of speeds (``problems/goland_4flaps``: 50 states, 4 flaps, 8 sensors, 41 airspeeds).

Truth used: the closed-loop eigenvalues of the family's own interpolated plant closed here by
python-control's ``feedback`` with the family's negative sign (independent of the design and
of the verification's certificate), and ``casflutter verify`` on the files the run wrote.
"""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from casflutter.aeroelastic import load_family
from casflutter.cli import main

@pytest.fixture(scope="module")
def family_run(goland_family_run):
    """The order-2 design over [60, 150] m/s (tests/conftest.py)."""
    return goland_family_run


def test_the_design_holds_the_interval_and_is_certified(family_run):
    _, s = family_run
    c = s["controller"]
    assert s["route"] == "family" and c["method"] == "multispeed" and c["order"] == 2
    assert c["held"] is True and c["interval"] == [60.0, 150.0]
    lo, hi = c["stable_interval"]
    assert lo <= 60.0 and hi >= 150.0          # the verification layer's certificate
    # the open family flutters inside the interval: the controller is doing the work
    assert 60.0 < s["flutter"]["V"] < 150.0
    fam = s["family"]
    assert fam["status"] == "flutter" and fam["unstable_at_start"] is False
    assert fam["spectral_abscissa_start"] < 0


def test_the_closed_loop_is_stable_where_certified_by_an_independent_computation(family_run):
    out, s = family_run
    family = load_family("goland_4flaps")
    doc = json.loads((out / "controller.json").read_text())
    assert doc["feedback"] == "negative"
    assert [i["name"] for i in doc["inputs"]] == list(family.signals.measurements)
    assert [o["name"] for o in doc["outputs"]] == list(family.signals.controls)
    K = control.ss(*(np.array(doc[k], dtype=float) for k in "ABCD"))
    sig = family.signals
    meas, ctrl = sig.output_index(), sig.input_index()
    hi = s["controller"]["stable_interval"][1]
    for V in np.linspace(60.0, 0.99 * hi, 9):
        G = family.plant(V)
        G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                       np.asarray(G.D)[np.ix_(meas, ctrl)])
        assert np.max(control.feedback(G, K, sign=-1).poles().real) < 0, V
    if hi < family.speed_range[1]:
        G = family.plant(min(1.02 * hi, family.speed_range[1]))
        G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                       np.asarray(G.D)[np.ix_(meas, ctrl)])
        assert np.max(control.feedback(G, K, sign=-1).poles().real) > 0


def test_verify_accepts_the_run_controller_and_repeats_its_certificate(family_run, capsys):
    out, s = family_run
    rc = main(["verify", "goland_4flaps", str(out / "controller.json"), "--json"])
    assert rc == 0
    v = json.loads(capsys.readouterr().out)
    iv = v["stable_interval"]
    assert [iv["lower"], iv["upper"]] == pytest.approx(s["controller"]["stable_interval"],
                                                       rel=1e-9)
    assert v["absolute_flutter_speed"] == pytest.approx(
        s["controller"]["absolute_flutter_speed"], rel=1e-9)


def test_the_runs_margin_verdict_is_verifys_and_can_be_required(family_run, goland_family_run_toml,
                                                             tmp_path, capsys):
    """``verification.robust_ok`` is the verdict of ``casflutter verify --require-v`` on the
    same family, controller and interval (the margins 6 dB / 45 deg held from the range's
    start to its top, the interval covered); with ``verify.require_margins = true`` the run's
    exit status follows it (3 when they do not hold), else it is only reported."""
    out, s = family_run
    ver = s["verification"]
    assert ver["margins"] == [6.0, 45.0] and ver["require_margins"] is False
    assert ver["interval_ok"] is True and ver["success"] is True
    capsys.readouterr()
    rc = main(["verify", "goland_4flaps", str(out / "controller.json"), "--require-v", "60",
               "150", "--json"])
    v = json.loads(capsys.readouterr().out)["verdict"]
    assert v["covered"] is True
    assert ver["robust_ok"] is v["robust"] is v["passed"] is (rc == 0)
    cfg = tmp_path / "run.toml"
    cfg.write_text(goland_family_run_toml + "[verify]\nrequire_margins = true\n")
    again = tmp_path / "out"
    rc_run = main(["run", str(cfg), "--out", str(again), "--quiet"])
    s2 = json.loads((again / "summary.json").read_text())
    assert s2["verification"]["robust_ok"] is ver["robust_ok"]         # the same controller
    assert rc_run == (0 if ver["robust_ok"] else 3)
    assert s2["verification"]["success"] is ver["robust_ok"]
