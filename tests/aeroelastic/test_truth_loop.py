"""TruthLoop: the truth's linearisation as an AeroelasticLoop, flap behind a servo."""

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import TruthLoop
from casflutter.errors import ConfigError
from casflutter.truth import SeedWing, TypicalSection

SERVO = 251.3


@pytest.fixture(scope="module")
def wing():
    return SeedWing()


def _sorted(ev):
    return ev[np.lexsort((np.round(ev.imag, 6), np.round(ev.real, 6)))]


def test_open_loop_poles_are_the_truth_and_the_servo(wing):
    """The servo drives the flap but nothing drives the servo back: the poles are the
    truth's (flap held) and the servo's own pair, computed independently."""
    fam = TruthLoop(wing, SERVO, 0.7)
    V = 1.6
    servo = np.roots([1.0, 2 * 0.7 * SERVO, SERVO ** 2])
    want = _sorted(np.concatenate([np.linalg.eigvals(wing.state_matrix(V)), servo]))
    assert_allclose(_sorted(np.linalg.eigvals(fam.state_matrix(V))), want, rtol=1e-8,
                    atol=1e-8)


def test_accelerometers_are_s_squared_times_the_displacements(wing):
    """zm = Hs ü: at any frequency the command-to-sensor response is (jω)² times Hs applied
    to the truth's own command-to-displacement response (its ``u`` outputs)."""
    fam = TruthLoop(wing, SERVO, 0.7)
    V = 1.3
    lp = fam.loop(V)
    G = control.ss(lp.A, lp.B2[:, None], lp.C2, lp.D22[:, None])
    P = wing.statespace(V, actuator_omega=SERVO, actuator_zeta=0.7)
    N = wing.n_modes
    Hs = wing.modal_structure().Hs
    for w in (3.0, 52.0, 400.0):
        s = 1j * w
        acc = G(s)[:, 0]
        disp = P(s)[:N, 0]
        assert_allclose(acc, s ** 2 * (Hs @ disp), rtol=1e-7)
    # the disturbance channels likewise
    Gw = control.ss(lp.A, lp.B1, lp.C2, lp.D21)
    s = 1j * 40.0
    assert_allclose(Gw(s), s ** 2 * (Hs @ P(s)[:N, 1:]), rtol=1e-7)


def test_closed_loop_matches_feedback_interconnection(wing):
    """The closed-loop matrix has the poles of python-control's positive feedback of the
    loop's command-to-sensor system with K."""
    fam = TruthLoop(wing, SERVO)
    V = 2.0
    lp = fam.loop(V)
    G = control.ss(lp.A, lp.B2[:, None], lp.C2, lp.D22[:, None])
    K = control.ss([[-30.0]], [[0.01, -0.02]], [[1.5]], [[0.0, 0.0]])
    want = _sorted(control.feedback(G, K, sign=1).poles())
    got = _sorted(np.linalg.eigvals(fam.closed_loop_state_matrix(V, K)))
    assert_allclose(got, want, rtol=1e-7, atol=1e-7)


def test_displacement_sensors_have_no_feedthrough():
    sec = TypicalSection()
    fam = TruthLoop(sec, 100.0)
    lp = fam.loop(1.0)
    assert sec.modal_structure().sensor == "displacement"
    assert_allclose(lp.D22, 0.0)
    assert_allclose(lp.C2[:, :sec.n_modes], sec.modal_structure().Hs)


@pytest.mark.parametrize("kw, msg", [({"servo_omega": 0.0}, "servo_omega"),
                                     ({"servo_omega": 10.0, "servo_zeta": -1.0}, "servo_zeta")])
def test_bad_servo_is_refused(wing, kw, msg):
    with pytest.raises(ConfigError, match=msg):
        TruthLoop(wing, **kw)


def test_not_a_truth_is_refused():
    with pytest.raises(ConfigError, match="AeroelasticTruth"):
        TruthLoop(object(), 100.0)


def test_flap_to_sensors_is_the_flap_column_of_the_loop(wing):
    lp = TruthLoop(wing, SERVO).loop(1.7)
    full = lp.statespace()          # inputs [w_1..w_N, v]
    G = lp.flap_to_sensors()
    for w in (5.0, 60.0):
        assert_allclose(G(1j * w)[:, 0], full(1j * w)[:, -1], rtol=1e-10)
