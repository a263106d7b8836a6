"""Two-stage identification: truth recovery, noise, bad input (paper section II.C)."""

import numpy as np
import pytest

from casflutter.data import IOData, Record, chirp_excitation
from casflutter.errors import ConvergenceError, DataError, OrderError
from casflutter.ident import (IdentificationSettings, identify, random_hwl_model, stage1,
                              synthetic_data)

PAPER_ORDERS = (3, 1, 1, 1, 2, 2)


@pytest.fixture(scope="module")
def truth():
    return random_hwl_model(5, PAPER_ORDERS, seed=1)


@pytest.fixture(scope="module")
def clean_data(truth):
    return synthetic_data(truth, 4000, seed=2)


def test_noise_free_recovers_truth(truth, clean_data):
    """N = 5, paper orders, band-limited chirps: coefficients and simulation to 1e-6 rel."""
    res = identify(clean_data, PAPER_ORDERS)
    assert res.success and res.return_status == "Solve_Succeeded"
    rel = np.abs(res.model.theta - truth.theta) / np.maximum(np.abs(truth.theta), 1e-3)
    assert rel.max() < 1e-6
    for name, arr in truth.coefficients().items():
        np.testing.assert_allclose(res.model.coefficients()[name], arr, rtol=1e-6, atol=1e-9,
                                   err_msg=name)
    # fresh validation input, not seen in identification
    val = synthetic_data(truth, 2000, seed=99)
    rec = val.records[0]
    ysim = res.model.simulate(rec.u, rec.v, y0=rec.y[:truth.max_lag])
    err = np.linalg.norm(ysim - rec.y) / np.linalg.norm(rec.y)
    assert err < 1e-6
    assert res.fit.error_percent.max() < 1e-4


def test_stage1_alone_is_exact_without_noise(truth, clean_data):
    s1 = stage1(truth.structure, clean_data)
    assert s1.rank1_residual < 1e-9
    np.testing.assert_allclose(s1.model.theta, truth.theta, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("noise", [0.02, 0.05])
def test_measurement_noise_bound(truth, noise):
    """White output noise of relative RMS sigma: the free-run error against the *clean*
    outputs stays below sigma/2 (the ROM filters the noise; its own error is parameter
    error only), and the fit error % on the noisy data is close to 100 sigma."""
    noisy = synthetic_data(truth, 4000, seed=2, noise=noise)
    res = identify(noisy, PAPER_ORDERS)
    clean = synthetic_data(truth, 4000, seed=2)
    rec, crec = noisy.records[0], clean.records[0]
    ysim = res.model.simulate(rec.u, rec.v, y0=crec.y[:truth.max_lag])
    err_clean = np.linalg.norm(ysim - crec.y, axis=0) / np.linalg.norm(crec.y, axis=0)
    assert err_clean.max() < 0.5 * noise
    assert np.all(np.abs(res.fit.error_percent - 100 * noise) < 30 * noise)
    assert res.cost <= res.cost_initial * (1 + 1e-9)


def test_simulation_criterion_improves_free_run(truth):
    noisy = synthetic_data(truth, 600, seed=4, noise=0.05)
    pred = identify(noisy, PAPER_ORDERS)
    sim = identify(noisy, PAPER_ORDERS, criterion="simulation", shooting_interval=100)
    assert sim.success
    assert sim.fit.rms_error.sum() <= pred.fit.rms_error.sum() * (1 + 1e-6)


def test_u_less_and_v_less_records():
    for has_u, has_v in [(False, True), (True, False)]:
        truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), has_u=has_u, has_v=has_v, seed=5)
        data = synthetic_data(truth, 1500, seed=6)
        res = identify(data, truth.orders)
        assert res.model.has_u == has_u and res.model.has_v == has_v
        np.testing.assert_allclose(res.model.theta, truth.theta, rtol=1e-6, atol=1e-8)


def test_several_records_and_single_mode():
    truth = random_hwl_model(1, (3, 2, 1, 1, 2, 2), seed=8)
    data = synthetic_data(truth, 500, n_records=3, seed=9)
    assert len(data.records) == 3
    res = identify(data, truth.orders)
    np.testing.assert_allclose(res.model.theta, truth.theta, rtol=1e-6, atol=1e-8)


def test_nonconvergence_is_raised(truth):
    noisy = synthetic_data(truth, 1000, seed=2, noise=0.1)
    with pytest.raises(ConvergenceError, match="did not converge") as info:
        identify(noisy, PAPER_ORDERS, ipopt_options={"ipopt.max_iter": 1})
    assert info.value.result is not None and not info.value.result.success


# -- bad input -------------------------------------------------------------------------
def test_nan_and_inf_named():
    y = np.ones((100, 2))
    y[17, 1] = np.nan
    with pytest.raises(DataError, match="NaN/inf.*sample 17"):
        IOData.from_arrays(y=y, u=np.ones((100, 2)))
    u = np.ones((100, 2))
    u[3, 0] = np.inf
    with pytest.raises(DataError, match="signal u"):
        IOData.from_arrays(y=np.ones((100, 2)), u=u)


def test_length_mismatch_named():
    with pytest.raises(DataError, match="length mismatch, u has 99 samples and y has 100"):
        IOData.from_arrays(y=np.ones((100, 2)), u=np.ones((99, 2)))
    with pytest.raises(DataError, match="length mismatch, v"):
        IOData.from_arrays(y=np.ones((100, 2)), v=np.ones(98))


def test_fewer_samples_than_parameters():
    rng = np.random.default_rng(0)
    data = IOData.from_arrays(y=rng.normal(size=(40, 5)), u=rng.normal(size=(40, 5)),
                              v=rng.normal(size=40), dt=0.01)
    with pytest.raises(DataError, match="too few samples: 35 usable samples .* 70 regression"):
        identify(data, PAPER_ORDERS)


def test_non_exciting_input_reports_conditioning():
    rng = np.random.default_rng(1)
    K = 500
    u1 = chirp_excitation(K, 0.01, 1, band=(0.5, 20), seed=0)[:, 0]
    u = np.column_stack([u1, 2 * u1])  # collinear channels
    data = IOData.from_arrays(y=rng.normal(size=(K, 2)), u=u, dt=0.01)
    with pytest.raises(DataError, match="non-exciting input.*condition number"):
        identify(data, (2, 1, 0, 1, 1, 1))
    dead = IOData.from_arrays(y=rng.normal(size=(K, 2)), u=np.column_stack([u1, 0 * u1]),
                              dt=0.01)
    with pytest.raises(DataError, match="identically zero"):
        identify(dead, (2, 1, 0, 1, 1, 1))


def test_orders_out_of_range_or_inconsistent():
    rng = np.random.default_rng(2)
    data = IOData.from_arrays(y=rng.normal(size=(30, 1)), u=rng.normal(size=(30, 1)), dt=1.0)
    with pytest.raises(OrderError, match="p=0 is out of range"):
        identify(data, (3, 1, 1, 1, 0, 2))
    with pytest.raises(OrderError, match="inconsistent with the data.*largest lag 41"):
        identify(data, (20, 1, 20, 1, 1, 1))
    with pytest.raises(ValueError, match="criterion"):
        IdentificationSettings(criterion="magic")


def test_data_record_without_input():
    with pytest.raises(DataError, match="no input"):
        Record(np.ones((10, 1)))
