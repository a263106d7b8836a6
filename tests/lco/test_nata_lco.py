"""The NATA rig's LCO branch: subcritical flutter, a fold of cycles below the flutter speed
and the hysteresis a wind tunnel sees, checked against time simulations of the rig."""

from __future__ import annotations

import numpy as np
import pytest

from casflutter.lco import lco_branch
from casflutter.truth import load_problem
from casflutter.aeroelastic import find_flutter

from ._helpers import measure


@pytest.fixture(scope="module")
def nata():
    truth = load_problem("nata")
    return truth, lco_branch(truth)


def test_branch_shape(nata):
    truth, br = nata
    h = br.hopf
    assert h.V == pytest.approx(find_flutter(truth, (2.0, 25.0), n_grid=60).Vf, rel=1e-9)
    assert h.kind == "subcritical" and h.consistent and h.branch_direction == -1
    assert h.normal_form_agreement == pytest.approx(1.0, abs=0.01)
    assert br.outputs == ("heave", "pitch")
    assert br.output_units == ("m", "rad") and br.speed_unit == "m/s"
    assert len(br.folds) == 1 and br.folds[0].located
    assert abs(br.folds[0].max_multiplier - 1.0) < 1e-4
    assert 4.0 < br.folds[0].V < h.V
    assert br.completed and "left the speed range" in br.stop_reason
    doc = br.to_dict()
    assert doc["kind"] == "subcritical" and doc["hopf"]["V"] == pytest.approx(h.V)
    assert doc["folds"][0]["amplitude"]["pitch"] > 0


def test_stable_branch_against_simulation(nata):
    """Above the flutter speed the rig, released from a small pitch, settles on the stable
    LCO of the branch (amplitude and frequency within 2 %)."""
    truth, br = nata
    stable = [p for p in br.points if p.stable]
    p = min(stable, key=lambda q: abs(q.V - 14.0))
    t = np.arange(0.0, 60.0, 0.002)
    sim = truth.simulate(t, _release(truth, 0.01), p.V)
    pitch = sim.u @ truth.modal_structure().Hs[1]
    heave = sim.u @ truth.modal_structure().Hs[0]
    a_p, f_p = measure(t, pitch)
    a_h, _ = measure(t, heave)
    assert a_p == pytest.approx(p.amplitude["pitch"], rel=0.02)
    assert a_h == pytest.approx(p.amplitude["heave"], rel=0.02)
    assert f_p == pytest.approx(p.freq_hz, rel=0.02)


def test_hysteresis_below_the_flutter_speed(nata):
    """Between the fold and the flutter speed a small disturbance decays, while the rig
    started beyond the unstable cycle ends on the large stable one of the branch."""
    truth, br = nata
    i = br.folds[0].index
    pu = min(br.points[:i], key=lambda q: abs(q.V - 10.0))
    t = np.arange(0.0, 60.0, 0.002)
    rows = truth.modal_structure().Hs[1]
    small = truth.simulate(t, 0.9 * pu.state, pu.V)
    large = truth.simulate(t, 1.1 * pu.state, pu.V)
    assert np.max(np.abs(small.u[-5000:] @ rows)) < 0.1 * pu.amplitude["pitch"]
    amp, freq = measure(t, large.u @ rows)
    up = br.points[i + 1:]
    Vs = [q.V for q in up]
    assert amp == pytest.approx(np.interp(pu.V, Vs, [q.amplitude["pitch"] for q in up]), rel=0.02)
    assert freq == pytest.approx(np.interp(pu.V, Vs, [q.freq_hz for q in up]), rel=0.02)


def _release(truth, pitch):
    """Modal initial state of the rig released from rest at the given pitch [rad]."""
    Phi = truth.modal_structure().shapes
    u0 = np.linalg.solve(Phi, [0.0, pitch])
    return np.concatenate([u0, np.zeros(2)])
