"""``casflutter run`` and ``casflutter verify`` on a family file with rigid-body positions.

The family: two flexible modes whose speed-dependent coupling flutters near V = 1.23, one
control, two sensors, 9 grid speeds, and two position states (each integrating a velocity
state, seen by no sensor, feeding nothing) whose pole at the origin stays in every closed
loop.  The run leaves them out when the file loads, designs on the rest and is certified.

Truth used: the FULL family's closed loop, built here from the file's arrays (interpolated
with numpy, closed by python-control's ``feedback`` with the file's negative sign), whose
eigenvalues are those of the loop without the positions plus the two at the origin, all the
others decaying; and ``casflutter verify`` on the files the run wrote.
"""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from casflutter.cli import main
from casflutter.data import FamilyFile, read_family_file

SPEEDS = np.linspace(0.8, 2.4, 9)
INTERVAL = (0.8, 1.8)

RUN = f"""
seed = 0
stages = ["controller"]
[problem]
name = "toy.toml"
[controller]
order = 2
interval = [{INTERVAL[0]}, {INTERVAL[1]}]
hinf_speeds = 0
"""


def write_family(path):
    """States q1, q2, q1', q2' of two modes coupled by ``0.5 V`` (coalescence flutter), then
    the positions x4 = ∫ q1' and x5 = ∫ q2'."""
    k = SPEEDS.size
    A, B = np.zeros((k, 6, 6)), np.zeros((k, 6, 1))
    C, D = np.zeros((k, 2, 6)), np.zeros((k, 2, 1))
    for s, V in enumerate(SPEEDS):
        A[s, :2, 2:4] = np.eye(2)
        A[s, 2:4, :2] = -np.array([[1.0, 0.5 * V], [-0.5 * V, 2.25]])
        A[s, 2:4, 2:4] = -np.diag([0.04, 0.06])
        A[s, 4, 2] = A[s, 5, 3] = 1.0
        B[s, 2:4, 0] = [0.3, 1.0]
        C[s, 0, 2] = 1.0
        C[s, 1, :4] = [0.2, 1.0, 0.0, 0.3]
    return FamilyFile(SPEEDS, A, B, C, D, speed_unit="m/s", feedback="negative",
                      name="toy", input_names=("flap",), output_names=("gyro", "strain")
                      ).write(path)


@pytest.fixture(scope="module")
def detached_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("detached")
    toml = write_family(folder / "toy.toml")
    cfg = folder / "run.toml"
    cfg.write_text(RUN)
    out = folder / "out"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 0
    return toml, out, json.loads((out / "summary.json").read_text())


def _plant(rec, V, states=slice(None)):
    """The file's plant at V, interpolated elementwise here (its ``states`` only)."""
    M = [np.array([[np.interp(V, rec.speeds, X[:, i, j]) for j in range(X.shape[2])]
                   for i in range(X.shape[1])]) for X in (rec.A, rec.B, rec.C, rec.D)]
    A, B, C, D = M
    return control.ss(A[states, states], B[states], C[:, states], D)


def test_the_run_leaves_the_positions_out_and_holds_the_interval(detached_run):
    _, _, s = detached_run
    fam = s["family"]
    assert fam["left_out_states"] == [4, 5]
    assert fam["n_states"] == 4 and fam["n_states_file"] == 6
    assert fam["status"] == "flutter"
    assert INTERVAL[0] < s["flutter"]["V"] < INTERVAL[1]      # the controller does the work
    c = s["controller"]
    assert c["held"] is True and c["interval"] == list(INTERVAL) and c["order"] == 2
    lo, hi = c["stable_interval"]
    assert lo <= INTERVAL[0] and hi >= INTERVAL[1]


def test_the_full_family_keeps_only_the_positions_at_the_origin(detached_run):
    toml, out, _ = detached_run
    rec = read_family_file(toml)
    doc = json.loads((out / "controller.json").read_text())
    assert doc["feedback"] == "negative"
    assert [i["name"] for i in doc["inputs"]] == ["gyro", "strain"]
    assert [o["name"] for o in doc["outputs"]] == ["flap"]
    K = control.ss(*(np.array(doc[k], dtype=float) for k in "ABCD"))
    for V in np.linspace(*INTERVAL, 7):
        full = control.feedback(_plant(rec, V), K, sign=-1).poles()
        kept = control.feedback(_plant(rec, V, slice(0, 4)), K, sign=-1).poles()
        origin = np.abs(full) < 1e-9
        assert origin.sum() == 2, (V, full)
        rest = list(full[~origin])
        for lam in kept:                        # the same multiset, matched one by one
            j = int(np.argmin(np.abs(np.array(rest) - lam)))
            assert abs(rest.pop(j) - lam) < 1e-8 * max(1.0, abs(lam)), (V, lam)
        assert not rest
        assert np.max(kept.real) < 0, V


def test_verify_certifies_the_run_controller_on_the_family_file(detached_run, capsys):
    toml, out, s = detached_run
    capsys.readouterr()
    assert main(["verify", str(toml), str(out / "controller.json"), "--json"]) == 0
    v = json.loads(capsys.readouterr().out)
    iv = v["stable_interval"]
    assert [iv["lower"], iv["upper"]] == pytest.approx(s["controller"]["stable_interval"],
                                                       rel=1e-9)
