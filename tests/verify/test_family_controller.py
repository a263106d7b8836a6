"""Controllers matched to a plant family's measurements and controls by name, and refused
(with the reason and the fix) before any work when they do not fit."""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from casflutter.aeroelastic import TruthLoop
from casflutter.errors import ConfigError, DimensionError
from casflutter.truth import SeedWing
from casflutter.verify import controller_to_json, match_controller

from family_helpers import SERVO, WITNESSES, random_family


def _doc(K, inputs=None, outputs=None, **extra):
    d = controller_to_json(K)
    if inputs is not None:
        d["inputs"] = inputs
    if outputs is not None:
        d["outputs"] = outputs
    d.update(extra)
    return d


@pytest.fixture
def fam():
    return random_family(0, n_in=3, n_out=4)        # inputs u0..u2, outputs y0..y3


K21 = control.ss([[-1.0]], [[1.0, 2.0]], [[3.0], [4.0]], np.zeros((2, 2)))   # 2 in, 2 out


def test_names_in_any_order_and_subset(fam):
    d = _doc(K21, [{"name": "y3"}, {"signal": "y1", "name": "rate"}],
             [{"name": "u2", "unit": "rad"}, "u0"])
    fc = match_controller(fam, d)
    assert fc.measurements == ("y3", "y1") and fc.controls == ("u2", "u0")
    assert fc.feedback == "negative" and fc.sign == -1.0 and fc.notes == ()
    assert list(fc.K.input_labels) == ["y3", "y1"]


def test_the_file_may_set_the_convention_and_the_caller_overrides_it(fam):
    d = _doc(K21, ["y0", "y1"], ["u0", "u1"], feedback="positive")
    fc = match_controller(fam, d)
    assert fc.feedback == "positive" and "from the controller file" in fc.notes[0]
    assert match_controller(fam, d, feedback="negative").feedback == "negative"


def test_a_file_on_disk(fam, tmp_path):
    path = tmp_path / "K.json"
    path.write_text(json.dumps(_doc(K21, ["y2", "y0"], ["u1", "u2"])))
    fc = match_controller(fam, path)
    assert fc.measurements == ("y2", "y0") and fc.controls == ("u1", "u2")


@pytest.mark.parametrize("inputs, outputs, message", [
    (["y0", "acc9"], ["u0", "u1"], r"inputs\[1\] \('acc9'\) matches no measurement"),
    (["y0", "yy1"], ["u0", "u1"], r"close: 'y1'"),
    (["y0", "y1"], ["u0", "y2"], r"outputs\[1\] 'y2' is a signal of .* but not one of its "
                                 r"controls"),
    (["y0", "y0"], ["u0", "u1"], r"name \['y0'\] more than once"),
])
def test_names_that_do_not_match_are_named(fam, inputs, outputs, message):
    with pytest.raises(ConfigError, match=message):
        match_controller(fam, _doc(K21, inputs, outputs))


def test_sizes_and_conventions_that_do_not_fit(fam):
    with pytest.raises(DimensionError, match="3 entries but the controller has 2 inputs"):
        match_controller(fam, _doc(K21, ["y0", "y1", "y2"], ["u0", "u1"]))
    with pytest.raises(DimensionError, match="2 inputs and no names, but .* has 4 "
                                             "measurements"):
        match_controller(fam, _doc(K21))
    with pytest.raises(ConfigError, match="feedback.*'sideways'"):
        match_controller(fam, _doc(K21, ["y0", "y1"], ["u0", "u1"], feedback="sideways"))
    with pytest.raises(ConfigError, match="discrete time"):
        match_controller(fam, _doc(K21, ["y0", "y1"], ["u0", "u1"],
                                   time_base={"domain": "discrete", "dt": 0.01}))
    with pytest.raises(ConfigError, match="time unit is 'ms'"):
        match_controller(fam, _doc(K21, ["y0", "y1"], ["u0", "u1"],
                                   time_base={"domain": "continuous", "time_unit": "ms"}))


def test_an_unnamed_controller_of_the_family_size_takes_its_order(fam):
    K = control.ss([[-1.0]], [[1.0, 2.0, 3.0, 4.0]], [[1.0], [2.0], [3.0]], np.zeros((3, 4)))
    fc = match_controller(fam, _doc(K))
    assert fc.measurements == ("y0", "y1", "y2", "y3") and fc.controls == ("u0", "u1", "u2")
    assert any("unnamed" in n and "order" in n for n in fc.notes)


def test_a_python_control_system_with_labels(fam):
    K = control.ss(K21.A, K21.B, K21.C, K21.D, inputs=["y1", "y0"], outputs=["u0", "u2"])
    fc = match_controller(fam, K)
    assert fc.measurements == ("y1", "y0") and fc.controls == ("u0", "u2")


def test_the_seed_wing_witness_and_a_run_export_match_the_loop_family():
    """An old witness file without names (sizes equal: order assumed) and a run's export
    (sensor names, ``"signal": "v"`` for the flap command) both fit the wing's loop family."""
    fam = TruthLoop(SeedWing(), SERVO)
    path = WITNESSES / "truth_interval_controller_order4.json"
    old = match_controller(fam, path)
    assert old.controls == ("v",) and old.measurements == fam.signals.measurements
    assert old.feedback == "positive" and old.notes
    doc = json.loads(path.read_text())
    doc["inputs"] = [{"name": n, "signal": f"zm[{j}]"}
                     for j, n in enumerate(fam.signals.measurements)][::-1]
    doc["outputs"] = [{"name": "flap deflection command", "signal": "v"}]
    doc["B"] = [row[::-1] for row in doc["B"]]
    new = match_controller(fam, doc)
    assert new.measurements == fam.signals.measurements[::-1] and new.notes == ()
