"""HWL model (eq. 1-4): numpy/CasADi twins, index conventions, normalisation, counts."""

import numpy as np
import pytest

from casflutter.errors import DataError, DimensionError, OrderError
from casflutter.ident import (HWLModel, HWLOrders, HWLStructure, hwl_predict_function,
                              hwl_simulate_function, paper_parameter_count, random_hwl_model)


@pytest.fixture(scope="module")
def model():
    return random_hwl_model(5, (3, 1, 1, 1, 2, 2), seed=3)


@pytest.fixture(scope="module")
def signals():
    rng = np.random.default_rng(7)
    K = 300
    return rng.normal(size=(K, 5)) * 0.5, rng.normal(size=K) * 0.5, rng.normal(size=(K, 5))


def test_parameter_count_against_paper_formula():
    N, o = 5, HWLOrders(3, 1, 1, 1, 2, 2)
    s = HWLStructure(o, N)
    # eq. 3 coefficients: N^2 (na + mu + nb+1 + q + p) + N (mu + nb+1 + p)
    assert s.n_coefficients == 25 * (1 + 3 + 2 + 2 + 2) + 5 * (3 + 2 + 2) == 285
    # minus one normalised coefficient per polynomial: N^2 (alpha) + N^2 (gamma) + N (beta)
    assert s.n_params == 285 - 25 - 25 - 5 == 230
    # the formula printed in section II.C counts more than the model has
    assert paper_parameter_count(N, o) == 455


@pytest.mark.parametrize("orders,has_u,has_v,N", [
    ((3, 1, 1, 1, 2, 2), True, True, 5),
    ((1, 2, 0, 0, 3, 1), True, False, 2),
    ((2, 0, 2, 1, 2, 3), False, True, 3),
    ((2, 2, 1, 2, 1, 2), True, True, 1),
])
def test_numpy_and_casadi_twins_agree(orders, has_u, has_v, N):
    m = random_hwl_model(N, orders, has_u=has_u, has_v=has_v, seed=11)
    rng = np.random.default_rng(0)
    K = 200
    u = rng.normal(size=(K, N)) * 0.5 if has_u else None
    v = rng.normal(size=K) * 0.5 if has_v else None
    y = rng.normal(size=(K, N))
    L = m.max_lag
    args = [a for a in (u, v) if a is not None]
    pred = m.predict(y, u, v)
    f = hwl_predict_function(m.structure, K)
    np.testing.assert_allclose(np.array(f(m.theta, y, *[a.reshape(K, -1) for a in args])),
                               pred[L:], rtol=0, atol=1e-12)
    sim = m.simulate(u, v, y0=y[:L], n_samples=K)
    g = hwl_simulate_function(m.structure, K)
    np.testing.assert_allclose(np.array(g(m.theta, y[:L], *[a.reshape(K, -1) for a in args])),
                               sim[L:], rtol=0, atol=1e-12 * max(1, np.abs(sim).max()))


def test_eq3_by_hand(model, signals):
    """y(k) written term by term from eq. 3 with the documented index convention."""
    u, v, y = signals
    c = model.coefficients()
    o = model.orders
    k = 57
    N = 5
    out = np.zeros(N)
    for i in range(N):
        acc = 0.0
        for j in range(N):
            for m in range(1, o.na + 1):
                acc -= c["A"][m - 1, i, j] * sum(c["alpha"][l - 1, i, j] * y[k - o.mu - m + 1, j] ** l
                                                 for l in range(1, o.q + 1))
            for d in range(o.mu):
                acc += c["H"][d, i, j] * sum(c["gamma"][l - 1, i, j] * u[k - o.r - d, j] ** l
                                             for l in range(1, o.p + 1))
            for d in range(o.nb + 1):
                acc += c["B"][d, i, j] * sum(c["gamma"][l - 1, i, j] * u[k - o.r - o.mu - d, j] ** l
                                             for l in range(1, o.p + 1))
        for d in range(o.mu):
            acc += c["h"][d, i] * sum(c["beta"][l - 1, i] * v[k - o.r - d] ** l for l in range(1, o.p + 1))
        for d in range(o.nb + 1):
            acc += c["b"][d, i] * sum(c["beta"][l - 1, i] * v[k - o.r - o.mu - d] ** l
                                      for l in range(1, o.p + 1))
        out[i] = acc
    np.testing.assert_allclose(model.predict(y, u, v)[k], out, rtol=1e-13, atol=1e-14)


def test_step_matches_simulation(model, signals):
    u, v, _ = signals
    y = model.simulate(u, v)
    L = model.max_lag
    for k in (L, 100, 250):
        yk = model.step(y[k - L:k + 1][::-1], u[k - L:k + 1][::-1], v[k - L:k + 1][::-1])
        np.testing.assert_allclose(yk, y[k], atol=1e-13)


def test_markov_parameters_are_the_coefficients(model):
    """mu-Markov property: the first mu impulse-response samples after the delay r are H, h."""
    G = model.markov_parameters(12)
    c = model.coefficients()
    o = model.orders
    for d in range(o.mu):
        np.testing.assert_allclose(G[o.r + d][:, :5], c["H"][d], atol=1e-15)
        np.testing.assert_allclose(G[o.r + d][:, 5], c["h"][d], atol=1e-15)
    np.testing.assert_array_equal(G[:o.r], 0)


def test_linearisation_is_small_signal_limit(model, signals):
    """With alpha^[1]=gamma^[1]=beta^[1]=1, the p=q=1 model is the tangent at zero."""
    u, v, _ = signals
    eps = 1e-6
    lin = model.linear_model()
    ylin = lin.simulate(eps * u, eps * v)
    ynl = model.simulate(eps * u, eps * v)
    np.testing.assert_allclose(ynl / eps, ylin / eps, atol=1e-5)


def test_rescaling_preserves_the_map(model, signals):
    u, v, _ = signals
    sy, su, sv = np.arange(1.0, 6.0), np.linspace(0.5, 2, 5), 3.0
    scaled = model.rescaled(sy, su, sv)
    np.testing.assert_allclose(scaled.simulate(u / su, v / sv) * sy, model.simulate(u, v),
                               atol=1e-12)


def test_pack_unpack_roundtrip(model):
    m2 = HWLModel.from_coefficients(model.orders, **model.coefficients(), dt=model.dt)
    np.testing.assert_array_equal(m2.theta, model.theta)


def test_bad_inputs():
    with pytest.raises(OrderError, match="mu"):
        HWLOrders(0, 1, 1, 1, 2, 2)
    with pytest.raises(OrderError, match="integer"):
        HWLOrders(3, 1.5, 1, 1, 2, 2)
    with pytest.raises(OrderError, match="mu, na, nb, r, p, q"):
        HWLOrders.from_tuple((3, 1, 1))
    with pytest.raises(OrderError, match="at least one input"):
        HWLStructure(HWLOrders(), 2, has_u=False, has_v=False)
    s = HWLStructure(HWLOrders(), 2)
    with pytest.raises(DimensionError, match="needs"):
        HWLModel(s, np.zeros(3))
    m = HWLModel(s, np.zeros(s.n_params))
    with pytest.raises(DimensionError, match="u has shape"):
        m.simulate(np.zeros((50, 3)), np.zeros(50))
    with pytest.raises(DataError, match="pass v="):
        m.simulate(np.zeros((50, 2)))
    with pytest.raises(DataError, match="must be 1"):
        c = m.coefficients()
        c["alpha"][0] = 2.0
        HWLModel.from_coefficients(m.orders, **c)


def test_advanced_model_is_the_identified_one_with_its_inputs_one_sample_earlier():
    """Lowering r by one is the same recursion fed the inputs one sample earlier: the
    advanced model's one-step predictions on (y, u, v) equal the original's on the inputs
    shifted forward by a sample (both predict the same y(k))."""
    from casflutter.ident import random_hwl_model
    model = random_hwl_model(3, (3, 1, 1, 2, 2, 2), seed=4)
    rng = np.random.default_rng(1)
    y, u, v = rng.normal(size=(300, 3)), rng.normal(size=(301, 3)), rng.normal(size=301)
    adv = model.advanced(1)
    assert adv.orders.r == 1 and adv.max_lag == model.max_lag - 1
    p_adv = adv.predict(y, u[:-1], v[:-1])
    p_ref = model.predict(y, u[1:], v[1:])
    np.testing.assert_allclose(p_adv[-250:], p_ref[-250:], rtol=1e-12, atol=1e-12)
    assert model.advanced(0).orders == model.orders
    with pytest.raises(OrderError, match="r = 2"):
        model.advanced(3)
