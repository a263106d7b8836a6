"""Chirp records of the truth and the common-denominator ROM identification."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.data import IOData
from casflutter.errors import ConfigError, DataError
from casflutter.pipeline import (backward_derivatives, chirp_motion,
                                 identify_common_denominator, truth_records)
from casflutter.truth import TypicalSection


def test_chirp_derivatives_are_exact():
    t = np.linspace(0.0, 50.0, 20001)
    s, sd, sdd = chirp_motion(t, (0.05, 1.0), amplitude=0.3, taper=0.2, phase=0.4)
    h = t[1] - t[0]
    # central differences, O(h^2) ~ 1e-6 relative; s'' of the raised-cosine taper jumps
    # where the taper joins the flat part (t = 10, 40): skip those two samples there
    ok = (np.abs(t - 10.0) > 2 * h) & (np.abs(t - 40.0) > 2 * h)
    ok[:2] = ok[-2:] = False
    assert_allclose(np.gradient(s, h)[ok], sd[ok], atol=2e-4 * np.max(np.abs(sd)))
    assert_allclose(np.gradient(sd, h)[ok], sdd[ok], atol=2e-4 * np.max(np.abs(sdd)))
    assert abs(s[0]) < 1e-15 and abs(s[-1]) < 1e-12 and abs(sd[0]) < 1e-12
    assert np.max(np.abs(s)) <= 0.3 + 1e-12


def test_backward_differences_are_exact_on_cubics():
    dt = 0.1
    t = np.arange(40) * dt
    x = 0.5 * t ** 3 - t ** 2 + 2 * t  # zero at t = 0, the record starts at rest
    d1, d2 = backward_derivatives(x, dt)
    # BDF2 first derivative is exact for quadratics: error -dt^2 x'''/3 for cubics
    assert_allclose(d1[3:], (1.5 * t ** 2 - 2 * t + 2)[3:] - dt ** 2 * 3.0 / 3, atol=1e-9)
    # the four-point second derivative is exact for cubics
    assert_allclose(d2[3:], (3 * t - 2)[3:], atol=1e-9)


@pytest.fixture(scope="module")
def ts_data():
    return truth_records(TypicalSection(), 2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))


def test_records_one_per_input(ts_data):
    assert len(ts_data.records) == 3 and ts_data.has_v and ts_data.n_modes == 2
    # the first record moves mode 1 only
    assert np.all(ts_data.records[0].u[:, 1] == 0) and np.all(ts_data.records[0].v == 0)


def test_identification_is_exact_and_recovers_the_wagner_poles(ts_data):
    """On BDF2 data the truth is exactly a common-denominator ARX model whose poles are the
    sampled Jones lag rates exp(-b_j V dt) (independently from the truth's matrices)."""
    res = identify_common_denominator(ts_data, na=2, nb=6)
    assert res.relative_residual < 1e-10
    lams = np.array(TypicalSection().aero_matrices(2.0).lams)
    assert_allclose(np.sort(res.poles.real), np.sort(np.exp(-lams * 0.1)), rtol=1e-9)
    assert res.stable and res.V == 2.0
    assert res.model.orders.as_tuple() == (1, 2, 5, 0, 1, 1)
    # the model's own free run reproduces the forces of a record it was fitted on
    rec = ts_data.records[1]
    ysim = res.model.simulate(rec.u, rec.v, y0=rec.y[:res.model.max_lag])
    assert np.max(np.abs(ysim - rec.y)) < 1e-8 * np.max(np.abs(rec.y))


def test_non_exciting_input_is_refused(ts_data):
    rec = ts_data.records[0]
    dead = IOData.from_arrays(y=rec.y, u=np.zeros_like(rec.u), v=rec.v, dt=0.1)
    with pytest.raises(DataError, match="non-exciting"):
        identify_common_denominator(dead)


def test_band_above_nyquist_is_refused():
    with pytest.raises(ConfigError, match="Nyquist"):
        truth_records(TypicalSection(), 2.0, dt=0.5, duration=100.0, band=(0.01, 2.0))
