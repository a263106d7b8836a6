"""Exact H∞ norm: slycot and scipy branches against each other, against analytic values
and against an independent dense frequency sweep."""

from __future__ import annotations

import sys

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError
from casflutter.verify import hinf_norm, sigma_max, slycot_available
from casflutter.verify._hinf import _hamiltonian
from verify_helpers import dense_peak, random_stable_ss, sigma_max_control

needs_slycot = [pytest.mark.slycot,
                pytest.mark.skipif(not slycot_available(), reason="slycot not installed")]

CASES = [  # (seed, n, m, p, with_d, min_damping)
    (1, 4, 1, 1, False, 0.05), (2, 6, 2, 2, True, 0.05), (3, 10, 3, 2, True, 0.02),
    (4, 12, 1, 3, False, 0.01), (5, 8, 2, 1, True, 0.005), (6, 20, 2, 3, True, 0.002),
    (7, 28, 3, 3, True, 0.01), (8, 3, 2, 2, True, 0.3),
]


@pytest.mark.parametrize("seed,n,m,p,with_d,zmin", CASES)
def test_scipy_branch_matches_dense_sweep(seed, n, m, p, with_d, zmin):
    G = random_stable_ss(np.random.default_rng(seed), n, m, p, with_d=with_d,
                         min_damping=zmin)
    h = hinf_norm(G, method="scipy")
    g_ref, w_ref = dense_peak(G)
    assert h.stable and h.method == "scipy"
    # the sweep is a lower bound: the exact norm is >= it and equal to ~1e-6
    assert h.gamma >= g_ref * (1 - 1e-9)
    assert_allclose(h.gamma, g_ref, rtol=1e-6)
    # the reported peak frequency attains the norm (independent evaluation)
    if np.isfinite(h.omega_peak):
        assert_allclose(sigma_max_control(G, np.array([h.omega_peak]))[0], h.gamma, rtol=1e-9)


@pytest.mark.slycot
@pytest.mark.skipif(not slycot_available(), reason="slycot not installed")
@pytest.mark.parametrize("seed,n,m,p,with_d,zmin", CASES)
def test_slycot_and_scipy_agree(seed, n, m, p, with_d, zmin):
    G = random_stable_ss(np.random.default_rng(seed), n, m, p, with_d=with_d,
                         min_damping=zmin)
    a = hinf_norm(G, method="scipy")
    b = hinf_norm(G, method="slycot")
    assert b.method == "slycot"
    assert_allclose(a.gamma, b.gamma, rtol=1e-8)
    if np.isfinite(b.omega_peak):
        assert_allclose(sigma_max_control(G, np.array([b.omega_peak]))[0], b.gamma, rtol=1e-7)


@pytest.mark.parametrize("method", ["scipy", pytest.param("slycot", marks=needs_slycot)])
@pytest.mark.parametrize("zeta,wn", [(1e-2, 3.0), (1e-3, 50.0), (1e-4, 0.7)])
def test_lightly_damped_second_order_analytic(method, zeta, wn):
    """G = wn²/(s² + 2ζwn s + wn²): peak 1/(2ζ sqrt(1-ζ²)) at wn sqrt(1-2ζ²)."""
    G = control.ss(control.tf([wn**2], [1, 2 * zeta * wn, wn**2]))
    h = hinf_norm(G, method=method)
    assert_allclose(h.gamma, 1 / (2 * zeta * np.sqrt(1 - zeta**2)), rtol=1e-8)
    assert_allclose(h.omega_peak, wn * np.sqrt(1 - 2 * zeta**2), rtol=1e-6)


@pytest.mark.parametrize("method", ["scipy", pytest.param("slycot", marks=needs_slycot)])
def test_peak_at_infinity_and_at_zero(method):
    hi = hinf_norm(control.ss(control.tf([1, 1], [1, 2])), method=method)  # (s+1)/(s+2)
    assert_allclose(hi.gamma, 1.0, rtol=1e-9)
    assert hi.omega_peak == np.inf
    lo = hinf_norm(control.ss(control.tf([1, 2], [1, 1])), method=method)  # (s+2)/(s+1)
    assert_allclose(lo.gamma, 2.0, rtol=1e-9)
    assert_allclose(lo.omega_peak, 0.0, atol=1e-6)


def test_hamiltonian_has_jomega_exactly_at_singular_values():
    rng = np.random.default_rng(12)
    G = random_stable_ss(rng, 6, 2, 3)
    A, B, C, D = (np.asarray(M, float) for M in (G.A, G.B, G.C, G.D))
    w0 = 1.7
    for s in np.linalg.svd(C @ np.linalg.solve(1j * w0 * np.eye(6) - A, B) + D,
                           compute_uv=False):
        ev = np.linalg.eigvals(_hamiltonian(A, B, C, D, s))
        assert np.min(np.abs(ev - 1j * w0)) < 1e-7 * max(1, w0)


def test_without_slycot_auto_falls_back_to_scipy(monkeypatch):
    """Make slycot look absent (as on a machine without it): 'auto' must still work."""
    G = random_stable_ss(np.random.default_rng(11), 8, 2, 2, min_damping=0.01)
    monkeypatch.setitem(sys.modules, "slycot", None)   # `import slycot` now raises
    assert not slycot_available()
    h = hinf_norm(G, method="auto")
    assert h.method == "scipy"
    assert_allclose(h.gamma, dense_peak(G)[0], rtol=1e-6)
    with pytest.raises(ConfigError, match="slycot is not installed"):
        hinf_norm(G, method="slycot")


@pytest.mark.slycot
@pytest.mark.skipif(not slycot_available(), reason="slycot not installed")
def test_with_slycot_auto_uses_slycot():
    assert hinf_norm(control.ss(control.tf([1], [1, 1, 1])), method="auto").method == "slycot"


def test_unstable_system_reports_infinite_norm():
    h = hinf_norm(control.ss([[1.0, 0], [0, -1]], [[1], [1]], [[1, 1]], [[0]]))
    assert h.gamma == np.inf and not h.stable and h.method == "unstable"
    assert_allclose(h.spectral_abscissa, 1.0)
    # a pole at the origin is not stable either
    assert hinf_norm(control.ss(control.tf([1], [1, 0]))).gamma == np.inf


def test_static_gain_and_zero_system():
    D = np.array([[3.0, 4.0], [0.0, 0.0]])
    assert_allclose(hinf_norm(D).gamma, 5.0)
    z = hinf_norm(control.ss([[-1.0]], [[0.0]], [[1.0]], [[0.0]]), method="scipy")
    assert z.gamma == 0.0


def test_bad_arguments_are_rejected():
    G = control.ss(control.tf([1], [1, 1]))
    with pytest.raises(ConfigError, match="method"):
        hinf_norm(G, method="bisection")
    with pytest.raises(ConfigError, match="discrete time"):
        hinf_norm(control.ss([[0.5]], [[1]], [[1]], [[0]], 0.1))


def test_sigma_max_vector_and_scalar():
    rng = np.random.default_rng(13)
    G = random_stable_ss(rng, 5, 2, 2)
    A, B, C, D = (np.asarray(M, float) for M in (G.A, G.B, G.C, G.D))
    w = np.array([0.0, 0.3, 2.0, 40.0])
    assert_allclose(sigma_max(A, B, C, D, w), sigma_max_control(G, w), rtol=1e-12)
    assert_allclose(sigma_max(A, B, C, D, 2.0), sigma_max_control(G, np.array([2.0]))[0],
                    rtol=1e-12)
