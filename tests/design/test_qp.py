"""The synthesis's trust-region QP (:class:`casflutter.design._qp.CutQP`) against its own
optimality conditions, checked in numpy: the step it returns with its multipliers must satisfy
the KKT conditions of the QP of the module docstring."""

import numpy as np
import pytest

from casflutter.design._qp import CutQP, QPStep
from casflutter.errors import ConfigError


def _instance(n, no, nc, seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    H = M @ M.T / n + np.eye(n)
    f = rng.standard_normal(no)
    G = rng.standard_normal((no, n))
    c = -rng.uniform(0.1, 1.0, nc)            # d = 0 feasible
    Hc = rng.standard_normal((nc, n))
    return H, f, G, c, Hc


@pytest.mark.parametrize("solver", ["qpoases", "ipopt"])
@pytest.mark.parametrize("n, no, nc, delta", [(40, 20, 5, 1e3), (77, 60, 40, 1e3),
                                              (120, 20, 0, 0.3), (30, 33, 17, 0.05)])
def test_the_step_satisfies_the_kkt_conditions(n, no, nc, delta, solver):
    """Stationarity (with the box's multipliers of the right sign where the step sits on the
    box, zero inside it), the objective cuts' multipliers summing to one, complementarity
    and feasibility, to 1e-6 of the data's scale; sizes past one cut slot, and at the
    H-inf phase's largest (120 parameters)."""
    H, f, G, c, Hc = _instance(n, no, nc, seed=n + no)
    step = CutQP(n, solver=solver).solve(H, f, G, c, Hc, delta)
    assert step.success
    d, t, mu, nu = step.d, step.t, step.mu, step.nu
    tol = 1e-6 * (1 + np.abs(G).max())
    # feasibility
    assert np.all(f + G @ d - t <= tol) and np.all(c + Hc @ d <= tol)
    # Ipopt relaxes simple bounds by its bound_relax_factor (1e-8); qpOASES does not
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


def test_the_active_set_solver_prints_nothing(capfd):
    """qpOASES writes its copyright notice to standard output when a solver is built; the
    results a command prints there (``--json``) must stay parseable."""
    CutQP(3, solver="qpoases").solve(np.eye(3), np.zeros(1), np.ones((1, 3)), np.zeros(0),
                                     np.zeros((0, 3)), 1.0)
    assert capfd.readouterr().out == ""


def test_an_unknown_qp_solver_is_refused_by_name():
    with pytest.raises(ConfigError, match="'quadprog'.*qpoases, ipopt"):
        CutQP(3, solver="quadprog")


def test_a_qp_the_active_set_solver_fails_is_solved_by_ipopt(monkeypatch):
    """Where qpOASES reports no solution, Ipopt solves the same QP: the step satisfies the
    QP's constraints, and the status names both solvers."""
    H, f, G, c, Hc = _instance(20, 12, 4, seed=3)
    failed = QPStep(d=np.zeros(20), model=np.nan, t=np.nan, mu=np.zeros(12), nu=np.zeros(4),
                    status="MAX_NWSR_REACHED", success=False)
    qp = CutQP(20)
    monkeypatch.setattr(qp, "_active_set", lambda *a: failed)
    step = qp.solve(H, f, G, c, Hc, 0.5)
    assert step.success
    assert step.status.startswith("qpoases: MAX_NWSR_REACHED; ipopt: Solve_Succeeded")
    assert np.all(c + Hc @ step.d <= 1e-8) and np.all(np.abs(step.d) <= 0.5 + 1e-7)
    reference = CutQP(20, solver="qpoases").solve(H, f, G, c, Hc, 0.5)
    assert step.model == pytest.approx(reference.model, rel=1e-6, abs=1e-8)
