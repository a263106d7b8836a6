"""The synthesis's trust-region QP (:class:`casflutter.design._qp.CutQP`) against its own
optimality conditions, checked in numpy: the step it returns with its multipliers must satisfy
the KKT conditions of the QP of the module docstring."""

import numpy as np
import pytest

from casflutter.design._qp import CutQP


def _instance(n, no, nc, seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    H = M @ M.T / n + np.eye(n)
    f = rng.standard_normal(no)
    G = rng.standard_normal((no, n))
    c = -rng.uniform(0.1, 1.0, nc)            # d = 0 feasible
    Hc = rng.standard_normal((nc, n))
    return H, f, G, c, Hc


@pytest.mark.parametrize("n, no, nc, delta", [(40, 20, 5, 1e3), (77, 60, 40, 1e3),
                                              (120, 20, 0, 0.3), (30, 33, 17, 0.05)])
def test_the_step_satisfies_the_kkt_conditions(n, no, nc, delta):
    """Stationarity (with the box's multipliers of the right sign where the step sits on the
    box, zero inside it), the objective cuts' multipliers summing to one, complementarity
    and feasibility, to 1e-6 of the data's scale; sizes past one cut slot, and at the
    H-inf phase's largest (120 parameters)."""
    H, f, G, c, Hc = _instance(n, no, nc, seed=n + no)
    step = CutQP(n).solve(H, f, G, c, Hc, delta)
    assert step.success
    d, t, mu, nu = step.d, step.t, step.mu, step.nu
    tol = 1e-6 * (1 + np.abs(G).max())
    # feasibility
    assert np.all(f + G @ d - t <= tol) and np.all(c + Hc @ d <= tol)
    # Ipopt relaxes simple bounds by its bound_relax_factor (1e-8)
    assert np.all(np.abs(d) <= delta + 1e-7)
    # the objective cuts' multipliers: nonnegative, summing to one (the derivative in t)
    assert np.all(mu >= 0) and mu.sum() == pytest.approx(1.0, abs=1e-6)
    # complementarity
    assert np.all(np.abs(mu * (f + G @ d - t)) <= tol)
    assert np.all(np.abs(nu * (c + Hc @ d)) <= tol)
    # stationarity in d: r = box multipliers, + at the upper bound, - at the lower, 0 inside
    r = -(H @ d + G.T @ mu + Hc.T @ nu)
    upper, lower = d >= delta - 1e-6, d <= -delta + 1e-6
    inside = ~(upper | lower)
    assert np.all(np.abs(r[inside]) <= tol)
    assert np.all(r[upper] >= -tol) and np.all(r[lower] <= tol)
    # the model value it reports is the QP's objective at the step
    assert step.model == pytest.approx(float(np.max(f + G @ d)) + 0.5 * d @ H @ d, abs=1e-9)
