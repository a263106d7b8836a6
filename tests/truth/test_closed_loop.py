"""The truth in closed loop: the sampled-data loop against the truth's own integrator, the
gain schedule, and the linear loop."""

import control
import numpy as np
import pytest

from casflutter.truth import closed_loop_truth, gain_schedule
from casflutter.truth import load_problem


@pytest.fixture(scope="module")
def wing():
    return load_problem("seed_wing")


def test_gain_schedule():
    g = gain_schedule(1.0, 2.0, 3.0)
    assert [g(t) for t in (0.5, 1.0, 2.0, 3.0, 5.9, 6.0, 7.0)] == [0, 0, 0.5, 1, 1, 0, 0]


def test_open_loop_matches_truth_simulate(wing):
    """With the gain at zero the flap stays at rest and the RK4 sampled-data loop must
    reproduce the truth's own adaptive integration (DOP853)."""
    V, dt = 1.0, 0.002
    t = np.arange(0.0, 1.0, dt)
    x0 = wing.displaced_state(1, 0.05)
    K = control.ss([[-1.0]], [[1.0, 1.0]], [[1.0]], [[0.0, 0.0]])
    cl = closed_loop_truth(wing, K, V, t, x0, lambda tt: 0.0)
    ref = wing.simulate(t, x0, V)
    Hs = np.asarray(wing.modal_structure().Hs)
    zm_ref = ref.uddot @ Hs.T
    err = np.abs(cl.zm - zm_ref).max() / np.abs(zm_ref).max()
    assert err < 1e-5
    np.testing.assert_array_equal(cl.v, 0.0)


def test_flap_dynamics_linearisation_is_state_matrix(wing):
    """Small-amplitude flap_dynamics equals the linear state matrix (flap at rest)."""
    V = 1.1
    f = wing.flap_dynamics(V)
    A = wing.state_matrix(V)
    rng = np.random.default_rng(0)
    s = 1e-7 * rng.normal(size=A.shape[0])
    ds, _ = f(s, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(ds, A @ s, rtol=1e-4, atol=1e-12 * np.abs(A @ s).max())
