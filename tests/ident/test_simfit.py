"""Simulation-error identification: exact sensitivities, truth recovery by free-run
error, divergent starts, mu >= 2, offsets, honest costs, time guard, unstable models."""

import warnings

import numpy as np
import pytest

from casflutter.data import IOData
from casflutter.errors import ConvergenceError
from casflutter.ident import (HWLModel, HWLStructure, IdentificationWarning, UnstableModelWarning,
                              fit_report, identify, random_hwl_model, synthetic_data)
from casflutter.ident import _identify as identify_module
from casflutter.ident._kernels import free_run
from casflutter.ident._simfit import FreeRunProblem, LMResult, fit_simulation_error


def _fd_jacobian(prob, x, seg):
    J = np.zeros((prob.n_rows * prob.N, prob.n_x))
    for k in range(prob.n_x):
        h = 1e-6 * max(1.0, abs(x[k]))
        e = np.zeros(prob.n_x)
        e[k] = h
        J[:, k] = (prob.residual(x + e, seg)[0] - prob.residual(x - e, seg)[0]) / (2 * h)
    return J


@pytest.mark.parametrize("orders,N,has_u,has_v,constant,n_records", [
    ((3, 1, 1, 1, 2, 2), 3, True, True, False, 1),
    ((2, 2, 1, 0, 3, 3), 2, True, False, True, 2),
    ((1, 3, 2, 0, 2, 3), 1, False, True, True, 1),
    ((2, 0, 1, 1, 2, 1), 2, True, True, False, 2),
])
@pytest.mark.parametrize("seg", [0, 40])
def test_sensitivities_match_finite_differences(orders, N, has_u, has_v, constant, n_records,
                                                seg):
    """The forward sensitivities through the recursion of eq. 3 (model parameters and
    initial outputs) against central differences of the free-run residual: 1e-7 relative."""
    m = random_hwl_model(N, orders, has_u=has_u, has_v=has_v, seed=1)
    data = synthetic_data(m, 300, seed=2, noise=0.05, n_records=n_records)
    s = HWLStructure(m.orders, N, has_u, has_v, constant)
    prob = FreeRunProblem(s, data, regularization=0.1)
    rng = np.random.default_rng(0)
    theta = np.concatenate([m.theta, rng.normal(size=N) * 0.1 if constant else []])
    x = prob.x0(theta + 0.01 * rng.normal(size=s.n_params)) + 0.01 * rng.normal(size=prob.n_x)
    r, cache, f = prob.residual(x, seg)
    J = prob.jacobian(cache, seg)
    Jfd = _fd_jacobian(prob, x, seg)
    assert np.abs(J - Jfd).max() < 1e-7 * np.abs(J).max()
    # the same with the initial outputs fixed at the measured ones
    fixed = FreeRunProblem(s, data, regularization=0.1, estimate_initial=False)
    xf = x[:s.n_params]
    Jf = fixed.jacobian(fixed.residual(xf, seg)[1], seg)
    assert Jf.shape == (fixed.n_rows * N, s.n_params)
    Jffd = _fd_jacobian(fixed, xf, seg)
    assert np.abs(Jf - Jffd).max() < 1e-7 * np.abs(Jf).max()


def test_free_run_kernel_matches_numpy_recursion():
    """The compiled recursion against eq. 3 stepped in plain numpy (predict one sample at a
    time with the simulated past)."""
    m = random_hwl_model(2, (2, 2, 1, 1, 2, 3), seed=7)
    rng = np.random.default_rng(3)
    K = 120
    u, v = 0.5 * rng.normal(size=(K, 2)), 0.5 * rng.normal(size=K)
    y = m.simulate(u, v)
    ref = np.zeros((K, 2))
    for k in range(m.max_lag, K):
        ref[k] = m.predict(ref[:k + 1], u[:k + 1], v[:k + 1])[k]
    np.testing.assert_allclose(y, ref, rtol=1e-12, atol=1e-14)


@pytest.fixture(scope="module")
def mimo_truth():
    return random_hwl_model(2, (3, 2, 1, 1, 2, 2), seed=4)


def test_simulation_error_recovers_truth_from_noisy_data(mimo_truth):
    """Output-error noise (5 %): the simulation criterion is consistent, so the free run of
    the estimate tracks the *clean* outputs of fresh data to well below the noise, and the
    parameters approach the truth."""
    noisy = synthetic_data(mimo_truth, 3000, seed=5, noise=0.05)
    res = identify(noisy, mimo_truth.orders, criterion="simulation")
    assert res.success and res.return_status == "Solve_Succeeded"
    assert res.solver == "gauss-newton"
    val = synthetic_data(mimo_truth, 1500, seed=77)
    rec = val.records[0]
    ysim = res.model.simulate(rec.u, rec.v, y0=rec.y[:res.model.max_lag])
    err = np.linalg.norm(ysim - rec.y, axis=0) / np.linalg.norm(rec.y, axis=0)
    assert err.max() < 0.01
    rel = np.abs(res.model.theta - mimo_truth.theta) / np.maximum(np.abs(mimo_truth.theta), 0.05)
    assert rel.max() < 0.2
    # noise-free: exact to rounding
    clean = synthetic_data(mimo_truth, 1500, seed=5)
    exact = identify(clean, mimo_truth.orders, criterion="simulation")
    np.testing.assert_allclose(exact.model.theta, mimo_truth.theta, rtol=1e-6, atol=1e-8)


def test_cost_initial_is_the_free_run_cost(mimo_truth):
    """cost_initial is the free-run criterion of the starting model (measured initial
    outputs), recomputed here from HWLModel.simulate in working units."""
    noisy = synthetic_data(mimo_truth, 1000, seed=6, noise=0.05)
    res = identify(noisy, mimo_truth.orders, criterion="simulation")
    sy, su, sv = noisy.scales()
    L = mimo_truth.max_lag
    rec = noisy.records[0]
    start = res.initial_model
    ysim = start.simulate(rec.u, rec.v, y0=rec.y[:L])
    expected = 0.5 * np.mean(((ysim[L:] - rec.y[L:]) / sy) ** 2)
    assert res.cost_initial == pytest.approx(expected, rel=1e-9)
    assert res.cost <= res.cost_initial
    # the final cost with the estimated initial outputs is what the model achieves
    y0 = np.vstack([rec.y[:L - res.initial_outputs[0].shape[0]], res.initial_outputs[0]])
    yfin = res.model.simulate(rec.u, rec.v, y0=y0)
    assert res.cost == pytest.approx(0.5 * np.mean(((yfin[L:] - rec.y[L:]) / sy) ** 2),
                                     rel=1e-9)


def test_diverging_start_is_handled(mimo_truth):
    """A start whose free run overflows (autoregression x6) converges to the same optimum as
    the stage-1 start: through the segment continuation in the solver itself, and through
    identify (which may first move to the prediction-error optimum); cost_initial is inf."""
    data = synthetic_data(mimo_truth, 2000, seed=5, noise=0.05)
    c = mimo_truth.coefficients()
    c["A"] = 6 * c["A"]
    bad = HWLModel.from_coefficients(mimo_truth.orders, dt=mimo_truth.dt, **c)
    with pytest.warns(UnstableModelWarning, match="unstable in free run"):
        bad.simulate(data.records[0].u, data.records[0].v)
    ref = identify(data, mimo_truth.orders, criterion="simulation")
    res = identify(data, mimo_truth.orders, criterion="simulation", initial=bad)
    assert res.success and np.isinf(res.cost_initial)
    assert res.cost == pytest.approx(ref.cost, rel=1e-6)
    np.testing.assert_allclose(res.model.theta, ref.model.theta, rtol=1e-5, atol=1e-7)
    # the solver alone, in the working units identify uses
    sy, su, sv = data.scales()
    work = data.scaled(sy, su, sv)
    start = bad.rescaled(sy, su, sv).theta
    prob = FreeRunProblem(mimo_truth.structure, work)
    lm = fit_simulation_error(prob, start)
    assert lm.success and np.isinf(lm.cost_initial)
    assert lm.stages[0] > 0 and lm.stages[-1] == 0      # continuation, then whole records
    assert lm.cost == pytest.approx(ref.cost, rel=1e-6)


def test_mu_three_and_long_lags():
    """mu = 3 with three autoregressive lags (lags 3..5) and a long input tail."""
    truth = random_hwl_model(1, (3, 3, 4, 1, 2, 3), has_v=False, seed=12)
    data = synthetic_data(truth, 3000, seed=13, noise=0.02)
    res = identify(data, truth.orders, criterion="simulation")
    assert res.success
    clean = synthetic_data(truth, 3000, seed=13)
    rec = clean.records[0]
    ysim = res.model.simulate(rec.u, y0=rec.y[:truth.max_lag])
    assert np.linalg.norm(ysim - rec.y) / np.linalg.norm(rec.y) < 0.01


def test_offsets_constant_term_and_exact_back_transform():
    """Data with offsets on every channel: offset=True recovers the offset-free truth's
    behaviour on the raw signals, with the constant term the shift implies."""
    truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=21)
    base = synthetic_data(truth, 2000, seed=22)
    rec = base.records[0]
    oy, ou, ov = np.array([3.0, -2.0]), np.array([0.7, -0.4]), 1.5
    raw = IOData.from_arrays(y=rec.y + oy, u=rec.u + ou, v=rec.v + ov, dt=base.dt)
    with pytest.warns(IdentificationWarning, match="offset=True"):
        identify(raw, truth.orders, refine=False)
    res = identify(raw, truth.orders, criterion="simulation", offset=True)
    assert res.success and res.model.structure.constant
    # the raw-signal model is the truth shifted by the offsets: same simulation
    expected = truth.shifted(-oy, -ou, -ov)
    r = raw.records[0]
    y_est = res.model.simulate(r.u, r.v, y0=r.y[:truth.max_lag])
    np.testing.assert_allclose(y_est, r.y, atol=1e-6 * np.abs(r.y).max())
    np.testing.assert_allclose(res.model.coefficients()["c"], expected.coefficients()["c"],
                               rtol=1e-5, atol=1e-7)


def test_shifted_is_the_same_map():
    m = random_hwl_model(3, (2, 2, 1, 1, 3, 3), seed=3)
    rng = np.random.default_rng(0)
    K = 300
    u, v = 0.5 * rng.normal(size=(K, 3)), 0.5 * rng.normal(size=K)
    y = m.simulate(u, v)
    ys, us, vs = rng.normal(size=3), 0.3 * rng.normal(size=3), 0.4
    ms = m.shifted(ys, us, vs)
    np.testing.assert_allclose(ms.simulate(u - us, v - vs, y0=y[:m.max_lag] - ys) + ys, y,
                               atol=1e-12)
    np.testing.assert_allclose(ms.shifted(-ys, -us, -vs).simulate(u, v), y, atol=1e-12)


def test_ipopt_solver_still_available_with_honest_costs(mimo_truth):
    data = synthetic_data(mimo_truth, 600, seed=8, noise=0.05)
    gn = identify(data, mimo_truth.orders, criterion="simulation")
    ip = identify(data, mimo_truth.orders, criterion="simulation", solver="ipopt",
                  shooting_interval=100)
    assert ip.solver == "ipopt" and ip.success
    assert ip.cost_initial == pytest.approx(gn.cost_initial, rel=1e-12)
    # Ipopt keeps the measured initial outputs, Gauss-Newton estimates them: GN's optimum of
    # the larger problem is at most Ipopt's, and close to it
    assert gn.cost <= ip.cost * (1 + 1e-9)
    assert ip.cost == pytest.approx(gn.cost, rel=0.05)
    # Ipopt's reported cost is the free run of its model, recomputed here
    sy = data.scales()[0]
    rec, L = data.records[0], mimo_truth.max_lag
    ysim = ip.model.simulate(rec.u, rec.v, y0=rec.y[:L])
    assert ip.cost == pytest.approx(0.5 * np.mean(((ysim[L:] - rec.y[L:]) / sy) ** 2), rel=1e-9)


def test_time_guard_returns_best_iterate_with_status(mimo_truth):
    """max_time: the best iterate so far (here the start: no time for any step) comes back
    with status Maximum_WallTime_Exceeded and a warning, for both solvers."""
    data = synthetic_data(mimo_truth, 2000, seed=5, noise=0.05)
    with pytest.warns(IdentificationWarning, match="max_time"):
        res = identify(data, mimo_truth.orders, criterion="simulation", max_time=1e-9)
    assert not res.success and res.return_status == "Maximum_WallTime_Exceeded"
    np.testing.assert_allclose(res.model.theta, res.initial_model.theta, rtol=1e-12)
    assert res.cost == res.cost_initial
    with pytest.warns(IdentificationWarning, match="max_time"):
        res = identify(data, mimo_truth.orders, criterion="simulation", solver="ipopt",
                       max_time=1e-9)
    assert res.return_status == "Maximum_WallTime_Exceeded"


def _fake_lm(status):
    def fake(problem, theta0, **kw):
        x = problem.x0(theta0)
        theta, ics = problem.split(x)
        f = problem.cost(x)
        return LMResult(theta, tuple(ics), f, f, status == "Solve_Succeeded", status, 1, 1,
                        (0,), 0.0)
    return fake


def test_acceptable_returned_with_warning_or_raised(monkeypatch, mimo_truth):
    """Acceptable-level stage 2: returned with a warning and the status by default, an error
    with accept_acceptable=False (the solver is replaced to produce that status)."""
    data = synthetic_data(mimo_truth, 800, seed=5)
    monkeypatch.setattr(identify_module, "fit_simulation_error",
                        _fake_lm("Solved_To_Acceptable_Level"))
    with pytest.warns(IdentificationWarning, match="acceptable level"):
        res = identify(data, mimo_truth.orders, criterion="simulation")
    assert res.return_status == "Solved_To_Acceptable_Level" and not res.success
    with pytest.raises(ConvergenceError, match="Solved_To_Acceptable_Level"):
        identify(data, mimo_truth.orders, criterion="simulation", accept_acceptable=False)


def test_unstable_fit_is_a_failure_never_success(mimo_truth):
    """A model whose free run diverges on the estimation data is a failure even when the
    solver (here: none, stage 2 skipped) reports success: ConvergenceError with status
    Unstable_Free_Run and no overflow warnings."""
    data = synthetic_data(mimo_truth, 800, seed=5)
    c = mimo_truth.coefficients()
    c["A"] = 6 * c["A"]
    bad = HWLModel.from_coefficients(mimo_truth.orders, dt=mimo_truth.dt, **c)
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # no overflow RuntimeWarning may leak
        with pytest.raises(ConvergenceError, match="unstable in free run") as info:
            identify(data, mimo_truth.orders, initial=bad, refine=False)
    assert info.value.result.return_status == "Unstable_Free_Run"
    assert not info.value.result.success


def test_max_iter_exhausted_raises(mimo_truth):
    data = synthetic_data(mimo_truth, 1000, seed=2, noise=0.1)
    with pytest.raises(ConvergenceError, match="did not converge") as info:
        identify(data, mimo_truth.orders, criterion="simulation", max_iter=1)
    assert info.value.result.return_status == "Maximum_Iterations_Exceeded"


def test_unstable_simulation_one_warning_no_overflow_noise():
    m = random_hwl_model(1, (1, 1, 0, 0, 1, 3), has_v=False, seed=1)
    c = m.coefficients()
    c["A"][0] = -1.5                      # y(k) = 1.5 y(k-1) + ...: diverges
    bad = HWLModel.from_coefficients(m.orders, dt=1.0, **c)
    u = np.ones((2000, 1))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        y = bad.simulate(u)
        rep = fit_report(bad, IOData.from_arrays(y=np.ones(2000), u=u), "simulation")
    assert [type(x.message) for x in w] == [UnstableModelWarning, UnstableModelWarning]
    k = int(np.argmax(np.isnan(y[:, 0])))
    assert k > 0 and np.all(np.isnan(y[k:])) and np.all(np.isfinite(y[:k]))
    assert not np.isfinite(rep.error_percent).all()


def test_simulate_flap_only_model_without_none():
    m = random_hwl_model(2, (2, 1, 1, 1, 2, 2), has_u=False, seed=3)
    v = np.random.default_rng(0).normal(size=200)
    np.testing.assert_array_equal(m.simulate(v), m.simulate(None, v))
    np.testing.assert_array_equal(m.simulate(v=v), m.simulate(None, v))


def test_free_run_kernel_reports_divergence_index():
    xin = np.ones((50, 1))
    W = np.array([[[[-2.0]]]])            # y(k) = 1 + 2 y(k-1)
    ybuf, _, div = free_run(xin, W, np.array([1], dtype=np.int64), np.zeros((1, 1)),
                            np.zeros((51, 1)), 0, 1e6)
    # y(t) = 2^(t+1) - 1 exceeds 1e6 first at t = 19
    assert div == 19
    assert np.all(np.isnan(ybuf[1 + div:]))
    np.testing.assert_allclose(ybuf[1:1 + div, 0], 2.0 ** np.arange(1, div + 1) - 1)


def test_fixed_initial_outputs_option(mimo_truth):
    """estimate_initial=False: the records start from their measured outputs, and the cost
    is the free run from them (the criterion fit_report scores)."""
    data = synthetic_data(mimo_truth, 1000, seed=6, noise=0.05)
    res = identify(data, mimo_truth.orders, criterion="simulation", estimate_initial=False)
    rec, L = data.records[0], mimo_truth.max_lag
    H = res.initial_outputs[0].shape[0]
    np.testing.assert_allclose(res.initial_outputs[0], rec.y[L - H:L], rtol=1e-12)
    sy = data.scales()[0]
    ysim = res.model.simulate(rec.u, rec.v, y0=rec.y[:L])
    assert res.cost == pytest.approx(0.5 * np.mean(((ysim[L:] - rec.y[L:]) / sy) ** 2),
                                     rel=1e-9)
    free = identify(data, mimo_truth.orders, criterion="simulation")
    assert free.cost <= res.cost * (1 + 1e-9)


@pytest.mark.slow
def test_duffing_65k_simulation_fit():
    """The benchmark's SISO case: 65,000 samples of a Duffing-type oscillator (1 % output
    noise), 14-parameter HWL model by simulation error.  The free-run error on the data is
    near the noise floor and far below the best linear model's, and the same fit from
    scipy's least_squares on the same residual is not better."""
    from casflutter.cli.bench.identify import _scipy_simulation
    from casflutter.ident import duffing_data, stage1

    data = duffing_data(65000, seed=1)
    res = identify(data, (1, 5, 5, 0, 1, 3), criterion="simulation")
    assert res.success and res.n_params == 14
    assert res.fit.error_percent[0] < 2.0
    lin = identify(data, (1, 5, 5, 0, 1, 1), criterion="simulation")
    assert lin.fit.error_percent[0] > 10 * res.fit.error_percent[0]
    sy, su, _ = data.scales()
    work = data.scaled(sy, su)
    s = HWLStructure(res.model.orders, 1, True, False)
    theta0 = stage1(s, work).model.theta
    prob = FreeRunProblem(s, work, 0.0, theta0)
    _, scipy_cost, _, _ = _scipy_simulation(prob, prob.x0(theta0), exact_jacobian=True)
    assert res.cost <= scipy_cost * (1 + 1e-8)


def test_bit_identical_in_two_fresh_processes():
    """Same data, same settings: the simulation fit gives bit-identical parameters in two
    fresh interpreters (no hidden randomness, BLAS thread count pinned inside identify)."""
    import subprocess
    import sys

    code = ("from casflutter.ident import identify, random_hwl_model, synthetic_data\n"
            "t = random_hwl_model(2, (2, 2, 1, 1, 2, 2), seed=3)\n"
            "d = synthetic_data(t, 800, seed=4, noise=0.05)\n"
            "print(identify(d, t.orders, criterion='simulation').model.theta.tobytes().hex())\n")
    out = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout for _ in range(2)]
    assert out[0] == out[1] and len(out[0]) > 100
