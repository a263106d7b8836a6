"""Sensitivity of the optimal γ against finite differences of closed-form optima and of the
exact H∞ norm."""

import control
import numpy as np
import pytest

from casflutter.design import synthesize, verify_closed_loop
from casflutter.study import gamma_sensitivity

from ._evals import first_order_plant


def gamma_star(a, rho):
    """Static optimum for a < 0: κ* = -1/(ρ² a), γ* = sqrt(1 + ρ²κ*²)/(κ* - a)."""
    k = -1.0 / (rho ** 2 * a)
    return np.sqrt(1 + rho ** 2 * k ** 2) / (k - a)


@pytest.fixture(scope="module")
def static_optimum():
    p = {"a": -1.0, "rho": 0.7}
    # tol bounds the relative decrease the local model still predicts, so the gain is
    # accurate to about sqrt(tol): 1e-12 for a gain (and dγ/dp) to 1e-6
    res = synthesize(first_order_plant(p), 1, 1, 0, starts=2, seed=1, options={"tol": 1e-12})
    return p, res


def test_optimal_gamma_sensitivity_matches_closed_form_differences(static_optimum):
    p, res = static_optimum
    np.testing.assert_allclose(res.gamma, gamma_star(p["a"], p["rho"]), rtol=1e-6)
    gs = gamma_sensitivity(first_order_plant, p, 1, 1, res)
    assert gs.kkt_residual < 1e-5  # the synthesised gain is stationary
    np.testing.assert_allclose(gs.gamma, res.gamma, rtol=1e-9)
    h = 1e-5
    fd_a = (gamma_star(p["a"] + h, p["rho"]) - gamma_star(p["a"] - h, p["rho"])) / (2 * h)
    fd_rho = (gamma_star(p["a"], p["rho"] + h) - gamma_star(p["a"], p["rho"] - h)) / (2 * h)
    np.testing.assert_allclose(gs.dgamma_dp["a"], fd_a, rtol=1e-6)
    np.testing.assert_allclose(gs.dgamma_dp["rho"], fd_rho, rtol=1e-6)
    # the envelope derivative differs from the fixed-gain one only by the optimality of K*
    np.testing.assert_allclose(gs.normalized["rho"], p["rho"] / gs.gamma * fd_rho, rtol=1e-6)
    assert [r[0] for r in gs.ranked()] == ["rho", "a"]


def test_fixed_controller_derivative_matches_exact_norm_differences():
    # a dynamic controller (not optimal): with one active peak the formula is dγ/dp at
    # fixed K, checked against central differences of the exact (SLICOT/verify) norm
    p = {"a": -1.0, "rho": 0.7}
    K = control.ss([[-3.0]], [[1.0]], [[-4.0]], [[-0.5]])
    gs = gamma_sensitivity(first_order_plant, p, 1, 1, K)
    assert len(gs.peaks) == 1
    np.testing.assert_allclose(gs.gamma, verify_closed_loop(first_order_plant(p), K, 1, 1)[0],
                               rtol=1e-8)
    for name in p:
        h = 1e-6
        gp = verify_closed_loop(first_order_plant({**p, name: p[name] + h}), K, 1, 1)[0]
        gm = verify_closed_loop(first_order_plant({**p, name: p[name] - h}), K, 1, 1)[0]
        np.testing.assert_allclose(gs.dgamma_dp[name], (gp - gm) / (2 * h), rtol=1e-5)
