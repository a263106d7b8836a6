"""Block observer-canonical realisation: Markov parameters, continuity, Tustin round trip."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.ident import random_hwl_model
from casflutter.realize import (canonical_realization, continuous_to_tustin, lag_coefficients,
                                tustin_to_continuous)


def _impulse(sys, n):
    A, B, C, D = (np.asarray(M) for M in (sys.A, sys.B, sys.C, sys.D))
    out = [D]
    P = B
    for _ in range(n - 1):
        out.append(C @ P)
        P = A @ P
    return np.array(out)


@pytest.mark.parametrize("orders, has_v, N", [
    ((3, 1, 1, 1, 2, 2), True, 3),     # the paper's orders
    ((1, 2, 5, 0, 1, 1), True, 2),     # the route's orders (direct feed-through)
    ((2, 3, 0, 2, 1, 2), False, 4),    # long input delay, no flap
    ((4, 0, 2, 0, 2, 1), True, 2),     # no autoregression (FIR)
])
def test_markov_parameters_equal_the_models(orders, has_v, N):
    model = random_hwl_model(N, orders, has_v=has_v, seed=3)
    sysd = canonical_realization(model)
    assert sysd.dt == model.dt
    assert sysd.nstates == N * model.max_lag
    G_model = model.markov_parameters(40)
    G_ss = _impulse(sysd, 40)
    scale = np.max(np.abs(G_model))
    assert_allclose(G_ss, G_model, rtol=0, atol=1e-12 * scale)
    assert list(sysd.input_labels) == list(model.u_names) + (["v"] if has_v else [])


def test_realisation_is_linear_in_the_coefficients():
    """Ad, Bd, Dd are affine in the coefficients (Bd bilinear in A and D): a small change
    of theta gives a proportionally small change of the matrices (continuity in V)."""
    m = random_hwl_model(2, (1, 2, 3, 0, 1, 1), seed=1)
    rng = np.random.default_rng(0)
    d = rng.normal(size=m.theta.size)
    mats = []
    for eps in (0.0, 1e-6, 2e-6):
        s = canonical_realization(m.with_theta(m.theta + eps * d))
        mats.append(np.concatenate([np.ravel(np.asarray(M)) for M in (s.A, s.B, s.C, s.D)]))
    first, second = mats[1] - mats[0], mats[2] - mats[1]
    assert np.linalg.norm(first) < 1e-4
    assert_allclose(first, second, atol=1e-10)


def test_lag_coefficients_layout():
    m = random_hwl_model(2, (3, 1, 1, 1, 2, 2), seed=5)
    Abar, Bbar = lag_coefficients(m)
    c = m.coefficients()
    assert_allclose(Abar[3], c["A"][0])          # AR lag mu + m - 1 = 3
    assert_allclose(Bbar[1][:, :2], c["H"][0])   # H^(0) at lag r = 1
    assert_allclose(Bbar[4][:, 2], c["b"][0])    # b^(0) at lag r + mu = 4
    assert not np.any(Bbar[0])                   # no feed-through for r = 1


def test_tustin_round_trip_of_the_canonical_form():
    m = random_hwl_model(2, (1, 2, 3, 0, 1, 1), seed=2)
    sysd = canonical_realization(m)
    back = continuous_to_tustin(tustin_to_continuous(sysd), m.dt)
    assert_allclose(_impulse(back, 30), _impulse(sysd, 30), atol=1e-10)
