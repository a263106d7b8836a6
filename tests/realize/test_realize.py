"""ERA, Tustin and the continuous Σf (paper eq. 5)."""

import control
import numpy as np
import pytest

from casflutter.errors import DimensionError, OrderError
from casflutter.ident import random_hwl_model
from casflutter.realize import (choose_order, continuous_to_tustin, era, realize,
                                tustin_to_continuous)


def _markov(sys, n):
    A, B, C, D = (np.asarray(x) for x in (sys.A, sys.B, sys.C, sys.D))
    G, P = [D], B
    for _ in range(1, n):
        G.append(C @ P)
        P = A @ P
    return np.array(G)


def _stable_discrete_system(rng, pairs: int, p: int, m: int, dt: float) -> control.StateSpace:
    """A minimal discrete system of order ``2 pairs`` drawn from ``rng``: complex pole pairs of
    radius 0.5-0.85, in a random orthogonal basis, with random B, C, D."""
    blocks = []
    for r, th in zip(rng.uniform(0.5, 0.85, pairs), rng.uniform(0.2, 2.8, pairs)):
        blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
    Q, _ = np.linalg.qr(rng.standard_normal((2 * pairs, 2 * pairs)))
    A = Q @ np.block([[blocks[i] if i == j else np.zeros((2, 2)) for j in range(pairs)]
                      for i in range(pairs)]) @ Q.T
    return control.ss(A, rng.standard_normal((2 * pairs, m)), rng.standard_normal((p, 2 * pairs)),
                      rng.standard_normal((p, m)), dt)


def test_era_recovers_known_discrete_system():
    # a seeded system (control.drss draws from numpy's global state, so it is not used here)
    truth = _stable_discrete_system(np.random.default_rng(0), 3, 2, 3, 0.01)
    G = _markov(truth, 81)
    sysd, S = era(G, "auto", dt=0.01)
    assert sysd.nstates == 6
    assert S[6] < 1e-10 * S[0]
    np.testing.assert_allclose(_markov(sysd, 81), G, atol=1e-10 * np.abs(G).max())
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(sysd.A)),
                               np.sort_complex(np.linalg.eigvals(truth.A)), atol=1e-8)


def test_tustin_round_trip(numpy_global_seed):
    sysc = control.rss(5, 3, 2)
    sysc = control.ss(sysc.A - 0.1 * np.eye(5), sysc.B, sysc.C, sysc.D)
    back = tustin_to_continuous(continuous_to_tustin(sysc, 0.02))
    w = np.logspace(-1, 2, 20)
    np.testing.assert_allclose(back(1j * w), sysc(1j * w), rtol=1e-9, atol=1e-12)


def test_sigma_f_matches_linearised_mu_markov_model():
    """Frequency response of Σf equals the mu-Markov model's at the Tustin-warped frequency."""
    model = random_hwl_model(5, (3, 1, 1, 1, 2, 2), seed=4)
    real = realize(model)
    assert real.order == real.exact_order_bound == 25
    T = model.dt
    c = model.coefficients()
    # transfer function of the linear mu-Markov difference equation, from its coefficients
    w = np.array([0.5, 5.0, 50.0, 300.0])
    z = (1 + 1j * w * T / 2) / (1 - 1j * w * T / 2)
    o = model.orders
    for k, zk in enumerate(z):
        Den = np.eye(5) + sum(c["A"][m] * zk ** -(o.mu + m) for m in range(o.na))
        num_u = sum(c["H"][d] * zk ** -(o.r + d) for d in range(o.mu)) + \
            sum(c["B"][d] * zk ** -(o.r + o.mu + d) for d in range(o.nb + 1))
        num_v = sum(c["h"][d] * zk ** -(o.r + d) for d in range(o.mu)) + \
            sum(c["b"][d] * zk ** -(o.r + o.mu + d) for d in range(o.nb + 1))
        G = np.linalg.solve(Den, np.column_stack([num_u, num_v]))
        np.testing.assert_allclose(real.sigma_f(1j * w[k]), G, rtol=1e-9, atol=1e-11)
    assert real.sigma_f.input_labels[-1] == "v"


def test_paper_order_15_is_a_truncation_with_documented_error():
    model = random_hwl_model(5, (3, 1, 1, 1, 2, 2), seed=4)
    full, r15 = realize(model), realize(model, 15)
    assert r15.order == 15
    S = full.hankel_singular_values
    # balanced truncation bound: H-inf error <= 2 * sum of discarded Hankel singular values
    w = np.linspace(0.1, np.pi / model.dt * 0.9, 200)
    err = max(np.linalg.norm(full.discrete(np.exp(1j * wk * model.dt)) -
                             r15.discrete(np.exp(1j * wk * model.dt)), 2) for wk in w)
    assert err <= 2 * S[15:25].sum() * 1.05


def test_bad_orders():
    model = random_hwl_model(2, (2, 1, 0, 1, 1, 1), seed=1)
    with pytest.raises(OrderError, match="out of range"):
        realize(model, 10_000)
    with pytest.raises(OrderError, match="zero"):
        choose_order(np.zeros(3))
    with pytest.raises(DimensionError, match="too few"):
        era(np.zeros((5, 2, 2)), 2, hankel_blocks=4)
    with pytest.raises(DimensionError, match="numeric dt"):
        tustin_to_continuous(control.ss(-1, 1, 1, 0))
