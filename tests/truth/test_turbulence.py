"""A tunnel's turbulence and sensor noise in the truth's closed-loop runs.

Truths used: the Dryden spectrum and rms (MIL-F-8785C) for the gust samples; the truth's own
linear state space (python-control's ``statespace`` with scipy's exact zero-order-hold
discretisation) for the disturbance's path through the closed-loop simulation."""

import control
import numpy as np
import pytest
from scipy.signal import cont2discrete, welch

from casflutter.errors import ConfigError, DimensionError
from casflutter.truth import (SuppressionSettings, closed_loop_truth, dryden_gust,
                              gust_modal_forces, load_problem, suppression_run,
                              tunnel_disturbances)


@pytest.fixture(scope="module")
def wing():
    return load_problem("seed_wing")


def test_dryden_gust_has_the_dryden_rms_and_spectrum():
    """400 s of gust (40000 time constants): rms within 2 % of sigma; Welch's spectrum
    within 15 % of the Dryden spectrum averaged over octaves from 1 to 64 Hz."""
    dt, sigma, tau = 0.002, 0.3, 0.01
    g = dryden_gust(200_000, dt, sigma, tau, np.random.default_rng(3))
    assert np.std(g) == pytest.approx(sigma, rel=0.02)
    f, P = welch(g, fs=1 / dt, nperseg=4096)
    w = 2 * np.pi * f
    dryden = sigma ** 2 * tau / np.pi * (1 + 3 * (tau * w) ** 2) / (1 + (tau * w) ** 2) ** 2
    for lo in (1.0, 2.0, 4.0, 8.0, 16.0, 32.0):
        band = (f >= lo) & (f < 2 * lo)
        # Welch's one-sided density per Hz is 2 pi times the one-sided density per rad/s
        assert np.mean(P[band]) / (2 * np.pi) == pytest.approx(np.mean(dryden[band]), rel=0.15)


def test_the_draws_depend_on_the_seed_alone(wing):
    kw = dict(gust_intensity=0.005, gust_scale=0.1, noise=0.1, n_sensors=2)
    a = tunnel_disturbances(wing, 1.1, 500, 0.002, seed=(0, 1), **kw)
    b = tunnel_disturbances(wing, 1.1, 500, 0.002, seed=(0, 1), **kw)
    c = tunnel_disturbances(wing, 1.1, 500, 0.002, seed=(1, 1), **kw)
    for x, y, z in zip(a, b, c):
        np.testing.assert_array_equal(x, y)
        assert not np.allclose(x, z)
    w, noise, gust = tunnel_disturbances(wing, 1.1, 500, 0.002, seed=0, gust_intensity=0.0,
                                         gust_scale=0.1, noise=0.0, n_sensors=2)
    assert not w.any() and not noise.any() and not gust.any()


def test_the_gust_forces_are_quasi_steady_strip_lift_and_need_strip_theory(wing):
    """The truth's steady strip lift of a uniform upwash w_g, against the quasi-steady lift of
    the gust angle w_g / U written out: rho U^2 b c_l_alpha (w_g / U) per span on each strip
    (no moment about the seed wing's quarter-chord elastic axis), generalised with each
    mode's plunge (positive down) and scaled as eq. 7's w = V^2 y_g, i.e.
    w_i = -c_l_alpha V^2 mean(h_i) / U per m/s of gust; to rounding.  Proportional to V (U is
    proportional to V); the first bending mode is pushed up."""
    for V in (0.7, 1.3):
        h = wing.strip_shapes()["h"]
        formula = -wing.params.lift_slope * V ** 2 * h.mean(axis=1) / wing.airspeed(V)
        np.testing.assert_allclose(gust_modal_forces(wing, V), formula, rtol=1e-12,
                                   atol=1e-12 * np.abs(formula).max())
    b1, b2 = gust_modal_forces(wing, 1.0), gust_modal_forces(wing, 1.3)
    np.testing.assert_allclose(b2, 1.3 * b1, rtol=1e-12)
    assert b1[0] < 0
    with pytest.raises(ConfigError, match="gust_intensity = 0"):
        gust_modal_forces(load_problem("typical_section"), 1.0)
    with pytest.raises(ConfigError, match="gust_intensity = 0"):
        gust_modal_forces(load_problem("goland"), 1.0)      # modal, not strip, downwash


def test_the_disturbance_enters_as_the_truths_own_disturbance_input(wing):
    """A small held modal disturbance below flutter, controller at rest: the closed-loop
    simulation's displacement sensors against the truth's linear state space driven by the
    same held inputs (exact ZOH discretisation), within 2e-5 of the response's peak (the
    wing's quadratic leading-edge suction makes the relative difference proportional to the
    amplitude: 5e-4 at 100 times this one)."""
    V, dt, n = 0.9, 0.002, 600
    rng = np.random.default_rng(5)
    w = 1e-6 * rng.standard_normal((n, wing.n_modes))
    K = control.ss([], [], [], [[0.0, 0.0]])
    t = np.arange(n) * dt
    sim = closed_loop_truth(wing, K, V, t, np.zeros(2 * wing.n_modes), lambda tt: 0.0,
                            sensor="displacement", disturbance=w)
    G = wing.statespace(V)
    nx = G.nstates
    Ad, Bd, *_ = cont2discrete((np.asarray(G.A), np.asarray(G.B)[:, 1:], np.eye(nx),
                                np.zeros((nx, wing.n_modes))), dt, method="zoh")
    x, ref = np.zeros(nx), []
    C = np.asarray(G.C)[wing.n_modes:]
    for k in range(n):
        ref.append(C @ x)
        x = Ad @ x + Bd @ w[k]
    ref = np.asarray(ref)
    assert np.abs(sim.zm - ref).max() <= 2e-5 * np.abs(ref).max()
    with pytest.raises(DimensionError, match="disturbance"):
        closed_loop_truth(wing, K, V, t, np.zeros(10), lambda tt: 0.0, disturbance=w[:, :2])


def test_a_suppression_run_in_turbulence_is_reproducible_and_recorded(wing):
    """A short gain ramp in turbulence with noisy sensors: the same seed gives the same
    record, another seed another; the record keeps the speed factor, the flap's peaks within
    the servo's limits and the gust's rms (sigma = intensity x airspeed, to sampling)."""
    sp = SuppressionSettings(speed_factors=(1.05,), settle=0.6, ramp=0.2, hold=0.6,
                             release=0.2, flap_limit=0.2618, flap_rate_limit=5.236,
                             gust_intensity=0.005, gust_scale=0.1, noise=0.1)
    K = control.ss([[-50.0]], [[0.0, 1.0]], [[-0.01]], [[0.0, 0.0]])
    kw = dict(dt=0.002, mode=1, deflection=0.01)
    a = suppression_run(wing, K, 1.085, sp, seed=(0, 0), **kw)
    b = suppression_run(wing, K, 1.085, sp, seed=(0, 0), **kw)
    c = suppression_run(wing, K, 1.085, sp, seed=(0, 1), **kw)
    np.testing.assert_array_equal(a.simulation.zm, b.simulation.zm)
    assert not np.allclose(a.simulation.zm, c.simulation.zm)
    rec = a.record()
    assert rec["speed_factor"] == 1.05 and rec["V"] == pytest.approx(1.05 * 1.085)
    assert 0 < rec["flap_peak"] <= 0.2618 * (1 + 1e-9)
    assert 0 < rec["flap_rate_peak"] <= 5.236 * (1 + 1e-9)
    assert rec["gust_rms"] == pytest.approx(0.005 * wing.airspeed(a.V), rel=0.5)
    # the servo's rate limit is far above what this gentle controller asks of it
    assert rec["flap_saturated_percent"] == 0.0 and rec["flap_rate_saturated_percent"] == 0.0


def test_a_servo_too_slow_for_the_command_is_reported_at_its_rate_limit(wing):
    """The share of the hold the servo spends at its limits, against what the limits
    physically do: the free servo follows this controller's command with a flap of about
    0.2 deg moving at up to about 10 deg/s (measured).  A rate limit of 0.5 deg/s holds the
    flap at its rate limit nearly the whole hold (>= 90 %); a limit of 500 deg/s never binds
    (0 %); a servo without a rate limit has no share (None).  The travel limit of 15 deg is
    far away throughout (0 %)."""
    base = dict(speed_factors=(1.05,), settle=0.4, ramp=0.1, hold=0.6, release=0.1,
                flap_limit=0.2618)
    K = control.ss([[-50.0]], [[0.0, 1.0]], [[-0.05]], [[0.0, 0.0]])
    kw = dict(dt=0.002, mode=1, deflection=0.01)
    slow, fast = (suppression_run(wing, K, 1.085, SuppressionSettings(
        flap_rate_limit=np.radians(rate), **base), **kw) for rate in (0.5, 500.0))
    assert slow.flap_rate_saturated_percent >= 90.0
    assert fast.flap_rate_saturated_percent == 0.0
    # the slow servo did bind: the free flap moves at well above 0.5 deg/s
    assert fast.flap_rate_peak > 10 * np.radians(0.5)
    assert slow.flap_saturated_percent == fast.flap_saturated_percent == 0.0
    free = suppression_run(wing, K, 1.085, SuppressionSettings(**base), **kw)
    assert free.flap_rate_saturated_percent is None


@pytest.mark.parametrize("changes, words", [
    ({"speed_factors": []}, "speed_factors"), ({"speed_factors": [1.1, -1.0]}, "> 0"),
    ({"gust_intensity": -0.1}, "gust_intensity"), ({"gust_scale": 0.0}, "gust_scale"),
    ({"noise": float("nan")}, "noise")])
def test_bad_suppression_settings_are_refused(changes, words):
    with pytest.raises(ConfigError, match=words):
        SuppressionSettings(**changes)
