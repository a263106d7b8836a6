"""``[controller] start``: a design that starts from a controller file.

Truth used: the controller file's own transfer matrix, evaluated here with python-control at
test frequencies and placed by hand into the family's channels with the family's sign
convention (independent of :func:`casflutter.pipeline.start_controller`'s realisation), and
the controller the first run wrote.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.aeroelastic import load_family
from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.pipeline import load_config, run, start_controller


WITNESS = Path(__file__).resolve().parents[1] / "witnesses" / \
    "truth_interval_controller_order4.json"


def test_a_missing_start_file_is_refused_before_any_work():
    with pytest.raises(ConfigError, match=r"controller.start = 'no_such_K.json': .*not found"
                                          r".*give a controller file"):
        load_config(updates={"controller.start": "no_such_K.json"})


def test_a_start_of_higher_order_than_asked_is_refused_before_any_work():
    with pytest.raises(ConfigError, match=r"has order 4 > controller.order = 3"):
        load_config(updates={"controller.start": str(WITNESS), "controller.order": 3})


def test_a_start_that_is_not_a_string_is_refused():
    with pytest.raises(ConfigError, match=r"controller.start: expected a string"):
        load_config(updates={"controller.start": 3})


def test_a_relative_start_is_read_beside_the_configuration(tmp_path):
    shutil.copy(WITNESS, tmp_path / "K.json")
    cfg_file = tmp_path / "run.toml"
    cfg_file.write_text('[controller]\norder = 4\nstart = "K.json"\n')
    cfg = load_config(cfg_file)
    assert Path(cfg.controller.start) == tmp_path / "K.json"


def test_the_start_is_placed_in_the_familys_channels_with_its_convention(tmp_path):
    """A controller that reads two of the eight sensors and drives two of the four flaps,
    named in another order and written with positive feedback, becomes the 4 x 8 controller
    of the family's negative convention: -K in the named places, zero elsewhere."""
    family = load_family("goland_4flaps")
    sig = family.signals
    rng = np.random.default_rng(3)
    n = 3
    A = -np.diag([5.0, 20.0, 60.0]) + 0.5 * rng.standard_normal((n, n))
    B, C, D = (rng.standard_normal(shape) for shape in ((n, 2), (2, n), (2, 2)))
    ins, outs = ["acc_rear_100", "gyro_50"], ["flap_3", "flap_1"]
    doc = {"A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "D": D.tolist(),
           "inputs": ins, "outputs": outs, "feedback": "positive"}
    (tmp_path / "K.json").write_text(json.dumps(doc))
    cfg = load_config(updates={"problem.name": "goland_4flaps", "controller.order": 3,
                               "controller.start": str(tmp_path / "K.json")})
    K0 = start_controller(cfg, family)
    assert (K0.ninputs, K0.noutputs, K0.nstates) == (8, 4, 3)
    assert list(K0.input_labels) == list(sig.measurements)
    assert list(K0.output_labels) == list(sig.controls)
    K = control.ss(A, B, C, D)
    rows = [list(sig.controls).index(o) for o in outs]
    cols = [list(sig.measurements).index(i) for i in ins]
    for w in (0.0, 3.0, 70.0):
        want = np.zeros((4, 8), complex)
        want[np.ix_(rows, cols)] = -np.asarray(K(1j * w))   # u = +K y is u = -(-K) y
        assert np.asarray(K0(1j * w)) == pytest.approx(want, rel=1e-10, abs=1e-12)
    # asked in the positive convention (the paper's LFT), the sign stays the file's
    Kp = start_controller(cfg, family, "positive")
    want = np.zeros((4, 8), complex)
    want[np.ix_(rows, cols)] = np.asarray(K(2j))
    assert np.asarray(Kp(2j)) == pytest.approx(want, rel=1e-10, abs=1e-12)


def test_names_that_match_nothing_are_named(tmp_path):
    family = load_family("goland_4flaps")
    doc = {"A": [[-1.0]], "B": [[1.0]], "C": [[1.0]], "D": [[0.0]],
           "inputs": ["gyro_05"], "outputs": ["flap_1"]}
    (tmp_path / "K.json").write_text(json.dumps(doc))
    cfg = load_config(updates={"problem.name": "goland_4flaps",
                               "controller.start": str(tmp_path / "K.json")})
    with pytest.raises(ConfigError, match="gyro_05"):
        start_controller(cfg, family)


@pytest.mark.parametrize("what, match", [
    ("start", r"inputs\[0\] \('gyro_05'\) matches no measurement"),
    ("interval",
     r"controller.interval = \[60, 400\] leaves the speed range \[.*\] m/s of goland_4flaps"),
])
def test_a_run_refuses_what_the_design_would_before_any_work(tmp_path, monkeypatch, what,
                                                             match, goland_family_run_toml):
    """A start whose names match no signal and an interval outside the family's speeds are
    refused before the family's flutter analysis, not by the design after it."""
    doc = {"A": [[-1.0]], "B": [[1.0]], "C": [[1.0]], "D": [[0.0]],
           "inputs": ["gyro_05"], "outputs": ["flap_1"]}
    (tmp_path / "K.json").write_text(json.dumps(doc))
    (tmp_path / "run.toml").write_text(goland_family_run_toml)
    updates = ({"controller.start": str(tmp_path / "K.json")} if what == "start"
               else {"controller.interval": [60.0, 400.0]})
    cfg = load_config(tmp_path / "run.toml", updates=updates)

    def no_work(*args, **kwargs):
        raise AssertionError("the flutter analysis ran before the refusal")

    monkeypatch.setattr("casflutter.pipeline._model.family_flutter", no_work)
    with pytest.raises(ConfigError, match=match):
        run(cfg, quiet=True)


def test_a_run_continues_the_start_first(tmp_path, goland_family_run, goland_family_run_toml):
    """The controller of a first run (tests/conftest.py), written again in the other
    convention with its sensors in another order, starts a second run: it holds the interval
    from the start, and with no H-infinity phase nothing is left to change."""
    first, _ = goland_family_run
    doc = json.loads((first / "controller.json").read_text())
    assert doc["feedback"] == "negative"
    K1 = control.ss(*(np.array(doc[k], dtype=float) for k in "ABCD"))
    names = [i["name"] for i in doc["inputs"]]
    perm = list(reversed(range(len(names))))
    flipped = {"A": doc["A"], "B": np.array(doc["B"])[:, perm].tolist(),
               "C": (-np.array(doc["C"])).tolist(),
               "D": (-np.array(doc["D"])[:, perm]).tolist(),
               "inputs": [names[j] for j in perm],
               "outputs": [o["name"] for o in doc["outputs"]], "feedback": "positive"}
    (tmp_path / "K1.json").write_text(json.dumps(flipped))
    cfg2 = tmp_path / "run2.toml"
    cfg2.write_text(goland_family_run_toml + 'start = "K1.json"\n')
    assert main(["run", str(cfg2), "--out", str(tmp_path / "second"), "--quiet"]) == 0
    s = json.loads((tmp_path / "second" / "summary.json").read_text())["controller"]
    assert s["start"] == str(tmp_path / "K1.json")
    assert s["design_starts"][0] == {"kind": "given", "order": 2, "reached": [60.0, 150.0]}
    assert s["held"] is True
    doc2 = json.loads((tmp_path / "second" / "controller.json").read_text())
    K2 = control.ss(*(np.array(doc2[k], dtype=float) for k in "ABCD"))
    for w in (0.5, 20.0, 70.0):
        assert np.asarray(K2(1j * w)) == pytest.approx(np.asarray(K1(1j * w)), rel=1e-8)
