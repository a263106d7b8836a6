"""Loop-at-a-time gain and phase margins, checked three ways.

* against :func:`control.stability_margins` (its polynomial method, on loops small enough
  for it: the seed wing's truth loop with its order-4 witness, including speeds where the
  wing alone flutters, so that the open loop is unstable);
* by scaling the broken channel by the reported gain margin (up and down): the loop closed
  by python-control must then have an eigenvalue on the imaginary axis at the reported
  phase-crossover frequency (or be ill posed, a crossing at ω = ∞), and be stable just
  inside the margin;
* by rotating the broken channel by the reported phase margin: the return difference
  ``I - s K(jω) P(jω) diag(e^{±jφ})``, evaluated from python-control's frequency responses,
  must be singular at the gain-crossover frequency.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from casflutter.aeroelastic import TruthLoop
from casflutter.truth import SeedWing
from casflutter.verify import broken_loops, classical_margins, load_controller, loop_margins

from family_helpers import SERVO, WITNESSES, random_family, small_controller


@pytest.fixture(scope="module")
def wing():
    fam = TruthLoop(SeedWing(), SERVO)
    K = load_controller(WITNESSES / "truth_interval_controller_order4.json")
    return fam, K


def _nyquist_reading(L):
    gm, pm, _, _, _, _ = control.stability_margins(L, returnall=True)
    gm, pm = np.atleast_1d(gm), np.atleast_1d(pm)
    up = gm[gm > 1].min() if np.any(gm > 1) else math.inf
    low = gm[gm <= 1].max() if np.any(gm <= 1) else 0.0
    return up, low, float(np.min(np.abs(pm))) if pm.size else math.inf


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")   # poly method
@pytest.mark.parametrize("V", [0.5, 1.2, 2.0, 2.35])
@pytest.mark.parametrize("side", ["input", "output"])
def test_margins_agree_with_python_control(wing, V, side):
    fam, K = wing
    P = fam.control_plant(V)
    for L in broken_loops(P, K, 1.0, side):
        m = classical_margins(L)
        up, low, pm = _nyquist_reading(L)
        assert m.gain_increase == pytest.approx(up, rel=1e-6)
        assert m.gain_decrease == pytest.approx(low, rel=1e-6, abs=1e-12)
        assert m.phase == pytest.approx(pm, rel=1e-5, abs=1e-9)


def _closed(P, K, sign, j, factor, side):
    """The loop with channel j of one side multiplied by ``factor`` (python-control)."""
    n = P.ninputs if side == "input" else P.noutputs
    S = np.eye(n, dtype=complex if np.iscomplexobj(factor) else float)
    S[j, j] = factor
    Pj = P * control.ss([], [], [], S) if side == "input" else control.ss([], [], [], S) * P
    return control.feedback(Pj, K, sign=sign)


def _cases():
    """Loops whose open loop is unstable (the wing above its flutter speed) and a random
    family's loops (both sides, a controller with a feed-through)."""
    fam = TruthLoop(SeedWing(), SERVO)
    K = load_controller(WITNESSES / "truth_interval_controller_order4.json")
    yield "wing V=2.0", fam.control_plant(2.0), K, 1.0
    rf = random_family(3, with_d=True)
    Kr = small_controller(np.random.default_rng(103), 2, 2, 2, gain=3.0, with_d=True)
    yield "random q=0.6", rf.control_plant(0.6), Kr, -1.0


@pytest.mark.parametrize("case", list(_cases()), ids=lambda c: c[0])
@pytest.mark.parametrize("side", ["input", "output"])
def test_scaling_by_the_gain_margin_puts_a_pole_on_the_axis(case, side):
    _, P, K, sign = case
    assert np.max(control.feedback(P, K, sign=sign).poles().real) < 0
    checked = 0
    for j, m in enumerate(loop_margins(P, K, sign, side)):
        for k in (m.gain_increase, m.gain_decrease):
            if not (0 < k < math.inf):
                continue
            try:
                poles = _closed(P, K, sign, j, k, side).poles()
            except ValueError:       # the crossing at ω = ∞: I - s D_K D_P is singular there
                n = P.ninputs if side == "input" else P.noutputs
                S = np.eye(n)
                S[j, j] = k
                DP = P.D @ S if side == "input" else S @ P.D
                M = np.eye(K.noutputs) - sign * K.D @ DP
                assert abs(np.linalg.det(M)) < 1e-9
                poles = None
            if poles is not None:
                on_axis = poles[np.argmin(np.abs(poles.real))]
                scale = max(1.0, float(np.max(np.abs(poles))))
                assert abs(on_axis.real) < 1e-6 * scale
                # the binding margin's phase crossover is the crossing's frequency
                if k == (m.gain_increase if m.gain_increase_db <= m.gain_decrease_db
                         else m.gain_decrease):
                    assert abs(on_axis.imag) == pytest.approx(m.omega_gain, rel=1e-6,
                                                              abs=1e-9)
            inside = k * (0.999 if k > 1 else 1.001)
            assert np.max(_closed(P, K, sign, j, inside, side).poles().real) < 0
            checked += 1
    assert checked > 0


@pytest.mark.parametrize("case", list(_cases()), ids=lambda c: c[0])
@pytest.mark.parametrize("side", ["input", "output"])
def test_rotating_by_the_phase_margin_makes_the_return_difference_singular(case, side):
    _, P, K, sign = case
    checked = 0
    for j, m in enumerate(loop_margins(P, K, sign, side)):
        if not math.isfinite(m.phase):
            continue
        w = m.omega_phase
        Pw = np.atleast_2d(P(1j * w))
        Kw = np.atleast_2d(K(1j * w)) if isinstance(K, control.StateSpace) else K
        smallest = []
        for rot in (np.exp(1j * math.radians(m.phase)), np.exp(-1j * math.radians(m.phase))):
            n = P.ninputs if side == "input" else P.noutputs
            R = np.eye(n, dtype=complex)
            R[j, j] = rot
            loop = Kw @ Pw @ R if side == "input" else R @ Pw @ Kw
            smallest.append(np.linalg.svd(np.eye(loop.shape[0]) - sign * loop,
                                          compute_uv=False)[-1])
        assert min(smallest) < 1e-6 * max(1.0, np.linalg.norm(Pw) * np.linalg.norm(Kw))
        checked += 1
    assert checked > 0


def test_a_channel_the_controller_does_not_use_has_no_margin_limit():
    fam = random_family(0)
    K = control.ss([[-1.0]], [[1.0, 0.0]], [[0.3], [0.0]], np.zeros((2, 2)))  # y0 -> u0 only
    P = fam.control_plant(0.5)
    ins, outs = loop_margins(P, K, -1.0, "input"), loop_margins(P, K, -1.0, "output")
    assert ins[1].gain_db == math.inf and ins[1].phase == math.inf
    assert outs[1].gain_db == math.inf and outs[1].phase == math.inf
