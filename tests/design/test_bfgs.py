"""The nonsmooth BFGS (Lewis-Overton weak Wolfe line search) against known minimisers."""

import numpy as np
import pytest

from casflutter.design._bfgs import nonsmooth_bfgs


def test_smooth_quadratic_reaches_its_minimiser():
    """A convex quadratic: the minimiser solves ``A x = b`` (numpy's solve is the check)."""
    rng = np.random.default_rng(0)
    M = rng.standard_normal((6, 6))
    A, b = M @ M.T + 6 * np.eye(6), rng.standard_normal(6)

    def f(x):
        return 0.5 * x @ A @ x - b @ x, A @ x - b

    res = nonsmooth_bfgs(f, np.zeros(6), max_iter=200)
    assert np.allclose(res.x, np.linalg.solve(A, b), atol=1e-6)


def test_nonsmooth_maximum_of_affine_functions_reaches_the_kink():
    """``f(x) = max(|x1| + 2 |x2|, ...)``-type: ``max_i |a_i . x - c_i|`` with a known
    minimiser where several pieces are active; the value there is the LP's optimum,
    computed independently with scipy's linprog."""
    from scipy.optimize import linprog
    rng = np.random.default_rng(3)
    a, c = rng.standard_normal((5, 2)), rng.standard_normal(5)

    def f(x):
        r = a @ x - c
        k = int(np.argmax(np.abs(r)))
        return float(abs(r[k])), np.sign(r[k]) * a[k]

    # min t s.t. -t <= a x - c <= t
    A_ub = np.vstack([np.hstack([a, -np.ones((5, 1))]), np.hstack([-a, -np.ones((5, 1))])])
    lp = linprog([0, 0, 1], A_ub=A_ub, b_ub=np.concatenate([c, -c]),
                 bounds=[(None, None)] * 3)
    res = nonsmooth_bfgs(f, np.array([3.0, -2.0]), max_iter=500)
    assert res.fun == pytest.approx(lp.fun, abs=1e-5)


def test_target_and_stall_stop_early():
    """The target stops the run as soon as it is met; a flat function stalls."""
    def f(x):
        return float(x @ x), 2 * x

    res = nonsmooth_bfgs(f, np.array([10.0, 10.0]), target=50.0)
    assert res.reason == "target" and res.fun <= 50.0 < 200.0
    flat = nonsmooth_bfgs(lambda x: (1.0 + 1e-12 * float(x @ x), 2e-12 * x),
                          np.ones(3), stall=1e-6, window=5)
    assert flat.reason in {"stalled", "line search", "stationary"}
    assert flat.iterations <= 6


def test_a_line_search_that_reaches_the_target_takes_that_step():
    """Along a direction in which the function falls without bound (a gain that lowers the
    closed-loop abscissa linearly), the weak Wolfe curvature test never passes and the step
    would double to the end of the line search (2**40); the first step that reached the
    target is taken instead."""
    res = nonsmooth_bfgs(lambda x: (1.0 - float(x[0]), np.array([-1.0])), np.zeros(1),
                         target=-1.0)
    assert res.reason == "target" and res.fun <= -1.0
    assert res.x[0] <= 4.0                  # a step or two past x = 2, not 1e12
    unbounded = nonsmooth_bfgs(lambda x: (1.0 - float(x[0]), np.array([-1.0])), np.zeros(1))
    assert unbounded.reason == "line search" and unbounded.x[0] > 1e10


def test_start_outside_the_domain_is_reported():
    res = nonsmooth_bfgs(lambda x: (np.inf, np.zeros_like(x)), np.ones(2))
    assert res.reason == "not finite" and res.iterations == 0


def test_a_lazy_gradient_gives_the_same_iterates_and_is_called_only_where_needed():
    """The gradient passed as a callable is evaluated only for the start and the trial steps
    that pass the sufficient-decrease test, and the run is the eager run's, step for step
    (the same result, iterations and evaluations)."""
    rng = np.random.default_rng(3)
    a, c = rng.standard_normal((5, 2)), rng.standard_normal(5)
    calls = []

    def value_and_gradient(x):
        r = a @ x - c
        k = int(np.argmax(np.abs(r)))
        return float(abs(r[k])), np.sign(r[k]) * a[k]

    def lazy(x):
        v, g = value_and_gradient(x)

        def gradient():
            calls.append(1)
            return g
        return v, gradient

    eager = nonsmooth_bfgs(value_and_gradient, np.array([3.0, -2.0]), max_iter=500)
    res = nonsmooth_bfgs(lazy, np.array([3.0, -2.0]), max_iter=500)
    assert np.array_equal(res.x, eager.x) and res.fun == eager.fun
    assert (res.iterations, res.evaluations, res.reason) == \
        (eager.iterations, eager.evaluations, eager.reason)
    # every evaluation that was not a rejected trial step asked for its gradient once
    assert 1 + res.iterations <= len(calls) < res.evaluations
