"""The Goland wing with flap segments (FlapWingFamily): with one flap it is the Goland truth's
own loop; flap segments superpose; the state matrix is quadratic in the airspeed, as
speed_degree says; its inputs are checked.

Truths used: :meth:`casflutter.truth.GolandWing.statespace` (the same strip theory with one
flap behind a servo, built independently), the linearity of strip theory in the flap (a flap
over two adjacent segments is the sum of the two), and the exact quadratic through three
speeds checked at a fourth.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import FlapWingFamily
from casflutter.errors import ConfigError
from casflutter.truth import GolandParams, GolandWing

PARAMS = GolandParams(n_bending=3, n_torsion=2, flap_chord=0.25, flap_span_start=0.6,
                      zeta=0.02)
ACT = dict(actuator_omega=180.0, actuator_zeta=0.6)


def test_one_flap_is_the_goland_truth_with_its_servo():
    fam = FlapWingFamily(PARAMS, flap_segments=((0.6, 1.0),), gyro_stations=(1.0,), **ACT)
    wing = GolandWing(PARAMS)
    U = 120.0
    A, B, _, _ = fam.matrices(U)
    P = wing.statespace(wing.speed_index(U), actuator_omega=180.0, actuator_zeta=0.6)
    n = P.nstates                      # the same states in the same order, then the gyro
    assert A.shape[0] == n + 1
    assert_allclose(A[:n, :n], P.A, rtol=1e-12, atol=1e-9 * np.max(np.abs(P.A)))
    assert_allclose(B[:n, 0], np.asarray(P.B)[:, 0], rtol=1e-12, atol=1e-12)
    assert np.all(A[:n, n:] == 0)      # the gyro filter reads the wing, not the reverse


def _response(fam, U, s, u):
    A, B, C, D = fam.matrices(U)
    return C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B @ u) + D @ u


def test_adjacent_flap_segments_superpose():
    two = FlapWingFamily(PARAMS, flap_segments=((0.6, 0.8), (0.8, 1.0)), **ACT)
    one = FlapWingFamily(PARAMS, flap_segments=((0.6, 1.0),), **ACT)
    for U in (80.0, 150.0):
        for s in (5j, 60j, 200j):
            g2 = _response(two, U, s, np.ones(2))
            g1 = _response(one, U, s, np.ones(1))
            assert_allclose(g2, g1, rtol=1e-11)


def test_state_matrix_is_quadratic_in_the_airspeed():
    fam = FlapWingFamily()
    U = np.array([70.0, 120.0, 190.0])
    c = np.linalg.solve(np.vander(U, 3, increasing=True),
                        np.array([fam.state_matrix(u).ravel() for u in U]))
    u4 = 157.3
    pred = (c[0] + u4 * c[1] + u4 ** 2 * c[2]).reshape(50, 50)
    assert_allclose(pred, fam.state_matrix(u4), rtol=1e-9,
                    atol=1e-10 * np.max(np.abs(pred)))
    assert fam.speed_degree == 2 and fam.n_states == 50


@pytest.mark.parametrize("kw, match", [
    (dict(flap_segments=((0.2, 0.5), (0.4, 0.6))), "overlap"),
    (dict(flap_segments=((0.5, 0.2),)), "0 <= y_a < y_b <= 1"),
    (dict(gyro_stations=(0.0,)), "gyro_stations"),
    (dict(actuator_omega=-1.0), "actuator_omega"),
    (dict(speed_range=(100.0, 50.0)), "speed_range"),
    (dict(params="goland"), "GolandParams"),
])
def test_inputs_are_checked(kw, match):
    with pytest.raises(ConfigError, match=match):
        FlapWingFamily(**kw)
