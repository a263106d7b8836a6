"""The seed-wing truth's LCO branch (saturating lift, leading-edge suction): supercritical
flutter on the lateral-mode branch, checked against time simulations of the wing."""

from __future__ import annotations

import numpy as np
import pytest

from casflutter.lco import lco_branch
from casflutter.truth import SeedWing

from ._helpers import measure

# the modes and sensors that carry the LCO (bending 3 and torsion 1 move by < 1 %)
CHECKED = ("bending 1", "lateral 1", "bending 2", "Acc1 (bending/torsion)", "Acc2 (lateral)")


@pytest.fixture(scope="module")
def seed():
    truth = SeedWing()
    return truth, lco_branch(truth, (0.8, 1.32))


def _signals(truth, sim):
    ms = truth.modal_structure()
    out = {n: sim.u[:, i] for i, n in enumerate(ms.mode_names)}
    out.update({n: sim.u @ ms.Hs[j] for j, n in enumerate(ms.sensor_names)})
    return out


def test_supercritical_flutter_of_the_lateral_mode(seed):
    truth, br = seed
    h = br.hopf
    assert h.V == pytest.approx(1.0850, abs=5e-4)       # problem.toml: truth flutter 1.0850
    assert h.freq_hz == pytest.approx(9.42, abs=0.01)    # 9.42 Hz
    assert h.kind == "supercritical" and h.consistent and h.branch_direction == 1
    assert h.normal_form_agreement == pytest.approx(1.0, abs=0.01)
    assert br.speed_unit == "m/s" and br.speed(1.0) == pytest.approx(28.9)
    assert all(p.stable for p in br.points) and not br.folds
    assert br.completed


def test_branch_against_a_simulation_started_off_the_cycle(seed):
    """Started 15 % outside the cycle at V ~ 1.3, the wing returns to it: amplitudes and
    frequency within 2 % after 6 s (the cycle's multiplier is ~0.9 per period)."""
    truth, br = seed
    p = min(br.points, key=lambda q: abs(q.V - 1.3))
    t = np.arange(0.0, 6.0, 0.0005)
    sig = _signals(truth, truth.simulate(t, 1.15 * p.state, p.V))
    for name in CHECKED:
        amp, freq = measure(t, sig[name])
        assert amp == pytest.approx(p.amplitude[name], rel=0.02), name
        assert freq == pytest.approx(p.freq_hz, rel=0.02), name


@pytest.mark.slow
def test_branch_against_a_simulation_from_rest(seed):
    """Released from a small lateral velocity, the wing's LCO after 14 s has the branch's
    amplitudes and frequency (2 % target)."""
    truth, br = seed
    p = min(br.points, key=lambda q: abs(q.V - 1.3))
    t = np.arange(0.0, 14.0, 0.0005)
    x0 = np.zeros(10)
    x0[1] = 0.01
    sig = _signals(truth, truth.simulate(t, x0, p.V))
    for name in CHECKED:
        amp, freq = measure(t, sig[name])
        assert amp == pytest.approx(p.amplitude[name], rel=0.02), name
        assert freq == pytest.approx(p.freq_hz, rel=0.02), name
