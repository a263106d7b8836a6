"""The chirp motion of prescribed-motion records and BDF2 grid velocities."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.data import (backward_derivatives, check_band, chirp_excitation, chirp_motion,
                             stepped_chirp_motion)
from casflutter.errors import ConfigError, DataError


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


@pytest.mark.parametrize("call", [
    lambda: chirp_excitation(100, 0.1, 1, band=(0.1, 6.0)),
    lambda: chirp_motion(np.arange(100) * 0.1, (0.1, 6.0)),
    lambda: check_band((0.1, 6.0), 0.1),
])
def test_both_chirps_refuse_a_band_above_nyquist_alike(call):
    """One check of the band: the same error class and message for both chirp shapes."""
    with pytest.raises(ConfigError, match="above the Nyquist frequency 5 Hz"):
        call()


@pytest.mark.parametrize("band", [(2.0, 1.0), (-1.0, 1.0), ("a", 1.0), (1.0,)])
def test_a_band_that_is_not_increasing_is_refused(band):
    with pytest.raises(ConfigError, match="band"):
        check_band(band)


def test_stepped_chirp_is_the_chirp_once_per_level():
    """Each segment is the single chirp over its own samples scaled by its level, so the
    record starts and ends every segment at rest and its derivatives stay exact."""
    t = np.arange(3000) * 0.01
    levels = (0.1, 0.5, 1.0)
    s, sd, sdd = stepped_chirp_motion(t, (0.1, 5.0), levels, taper=0.1)
    edges = (0, 1000, 2000, 3000)
    for k, a in enumerate(levels):
        seg = slice(edges[k], edges[k + 1])
        ref = chirp_motion(t[seg], (0.1, 5.0), a, 0.1)
        for got, want in zip((s, sd, sdd), ref):
            assert_allclose(got[seg], want, rtol=0, atol=0)
        assert np.max(np.abs(s[seg])) == pytest.approx(a, rel=0.01)
        assert abs(s[edges[k]]) < 1e-15 and abs(sd[edges[k]]) < 1e-12
    # one level is the plain chirp
    assert_allclose(stepped_chirp_motion(t, (0.1, 5.0), [0.3])[0], chirp_motion(t, (0.1, 5.0), 0.3)[0])


@pytest.mark.parametrize("levels, error", [((), ConfigError), ((1.0, float("nan")), ConfigError),
                                            ("ab", ConfigError), ((1.0,) * 40, DataError)])
def test_stepped_chirp_refuses_bad_levels(levels, error):
    with pytest.raises(error, match="levels|chirps"):
        stepped_chirp_motion(np.arange(100) * 0.01, (0.1, 5.0), levels)
