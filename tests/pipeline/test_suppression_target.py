"""Paper Fig. 11 on the truth in a tunnel (issue 32, item 4): at 1.05 and 1.2 times the wing's
flutter speed the default study's controller is switched on against the truth's *established*
LCO, in Dryden turbulence with noisy accelerometers, through a servo with travel and rate
limits; target: the LCO suppressed by at least 90 % (the paper's figure) at both speeds, and
it returns after the release.

Independent truths: the truth's own LCO simulation (:func:`casflutter.truth.truth_lco`,
the adaptive DOP853 integrator, not the closed-loop RK4) for the LCO each run starts on, and
the stationary response of the truth's *linear* closed loop to the Dryden gust (a Lyapunov
equation of the truth's state space, the continuous controller and the Dryden filter) for the
floor the turbulence leaves under the suppressed LCO."""

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

from casflutter.pipeline import default_config_path, load_config, run
from casflutter.truth import gust_modal_forces, truth_lco


@pytest.fixture(scope="module")
def study():
    return run(load_config(default_config_path()), quiet=True, write=False)


def _gust_floor(truth, K, V: float, cfg) -> np.ndarray:
    """Stationary rms of the accelerometers of the truth's linear closed loop (flap behind
    the 40 Hz servo, the continuous controller) driven by the Dryden gust of ``cfg`` alone."""
    N = truth.n_modes
    G = truth.statespace(V, actuator_omega=2 * np.pi * 40.0, actuator_zeta=0.7)
    A, B = np.asarray(G.A), np.asarray(G.B)
    Bv, Bg = B[:, :1], B[:, 1:] @ gust_modal_forces(truth, V)[:, None]
    Hs = np.asarray(truth.modal_structure().with_sensors(cfg.sensors.rows or None).Hs)
    Ca, Dv, Dg = Hs @ A[N:2 * N], Hs @ Bv[N:2 * N], Hs @ Bg[N:2 * N]   # zm = Hs u''
    U = truth.airspeed(V)
    sigma, tau = cfg.suppression.gust_intensity * U, cfg.suppression.gust_scale / U
    # Dryden filter (1 + sqrt(3) tau s) / (1 + tau s)^2 on unit white noise, scaled to sigma
    Af = np.array([[0.0, 1.0], [-1 / tau ** 2, -2 / tau]])
    Bf = np.array([[0.0], [1 / tau ** 2]])
    Cf = np.array([[1.0, np.sqrt(3.0) * tau]])
    Cf = Cf * sigma / np.sqrt((Cf @ solve_continuous_lyapunov(Af, -Bf @ Bf.T) @ Cf.T).item())
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, float)) for M in (K.A, K.B, K.C, K.D))
    assert not Dk.any()                      # strictly proper: the flap command is Ck xk
    nx, nk = A.shape[0], Ak.shape[0]
    Acl = np.block([[A, Bv @ Ck, Bg @ Cf],
                    [Bk @ Ca, Ak + Bk @ Dv @ Ck, Bk @ Dg @ Cf],
                    [np.zeros((2, nx + nk)), Af]])
    assert np.linalg.eigvals(Acl).real.max() < 0
    Bcl = np.vstack([np.zeros((nx + nk, 1)), Bf])
    Ccl = np.hstack([Ca, Dv @ Ck, Dg @ Cf])
    return np.sqrt(np.diag(Ccl @ solve_continuous_lyapunov(Acl, -Bcl @ Bcl.T) @ Ccl.T))


@pytest.mark.slow
def test_the_established_lco_meets_the_tunnels_turbulence_through_the_servo(study):
    r = study
    cfg = r.config
    runs = r.suppression.runs
    assert [s.speed_factor for s in runs] == list(cfg.suppression.speed_factors) == [1.05, 1.2]
    dt = cfg.data.dt
    for sup in runs:
        assert sup.started_from_lco and sup.lco_returns
        # the gust's rms is the documented intensity times the airspeed, to sampling (the
        # run is 40 s against a Dryden time constant of a few ms)
        assert sup.gust_rms == pytest.approx(cfg.suppression.gust_intensity
                                             * r.truth.airspeed(sup.V), rel=0.05)
        # the run starts on the truth's converged LCO at that speed, simulated without
        # turbulence by the truth's own integrator: the open-loop RMS before the ramp
        # against that LCO's (just above flutter the cycle still creeps and the turbulence
        # adds a little: measured +4 % at 1.05 Vf, 0 % at 1.2 Vf; a developing LCO would be
        # far below)
        if abs(r.lco.truth.V - sup.V) <= 1e-9 * sup.V:
            quiet = r.lco.truth
        else:
            quiet = truth_lco(r.truth, sup.V, cfg.lco.duration, int(r.flutter.flutter_mode),
                              cfg.lco.initial_deflection, dt=dt)
        quiet_rms = np.sqrt(np.mean(quiet.zm ** 2, axis=0))
        np.testing.assert_allclose(sup.open_loop_rms, quiet_rms, rtol=0.08)
        # the flap stayed inside the servo's limits, also between the samples
        sim = sup.simulation
        assert np.max(np.abs(sim.v)) <= cfg.suppression.flap_limit * (1 + 1e-9)
        assert np.max(np.abs(np.diff(sim.v))) / dt <= cfg.suppression.flap_rate_limit * (1 + 1e-9)
        assert sup.flap_rate_peak <= cfg.suppression.flap_rate_limit * (1 + 1e-12)
    # at 1.05 Vf the LCO is gone: what is left at full gain is the linear closed loop's
    # response to the turbulence (measured 8.6 against 7.9 m/s^2 on Acc1; the window is the
    # last 2 s of the hold), so the attenuation is set by the tunnel's turbulence
    low = r.suppression.at(1.05)
    # and it came back after the release: the run ended once its RMS over the open-loop
    # window was back above half the open loop's, well after the shortest release (the
    # window) and before the longest
    ss = cfg.suppression
    t_release = ss.settle + ss.ramp + ss.hold
    assert t_release + ss.settle / 3 + 2.0 < low.simulation.timepts[-1] < t_release + ss.release
    floor = _gust_floor(r.truth, r.controller, low.V, cfg)
    dom = low.dominant_sensor
    assert low.closed_loop_rms[dom] == pytest.approx(floor[dom], rel=0.2)
    assert low.attenuation_percent >= 90.0
    # the controller is still the verified robust design at Vf
    assert r.verification.stable and r.verification.exact_V[0] < r.Vf < r.verification.exact_V[1]


@pytest.mark.slow
def test_the_lco_at_1_2_times_the_flutter_speed_dies_out_through_the_rate_limited_flap(study):
    """At 1.2 Vf the 300 deg/s flap saturates.  The default tunnel runs the flap command
    through the phase-compensating limiter (``suppression.command_limiter``) and holds full
    gain for 40 s: the LCO dies out to the turbulence's floor (measured 95.0-95.2 % on seeds
    0-4).  The same controller through the bare servo, from the same established LCO in the
    same turbulence, pushes late and leaves it (seed 0: 7-8 %): the limiter, not the hold,
    does it."""
    from dataclasses import replace

    from casflutter.truth import suppression_run

    r, cfg = study, study.config
    ss = cfg.suppression
    assert ss.command_limiter == "phase_compensated" and ss.hold >= 40.0
    high = r.suppression.at(1.2)
    lo, hi = r.truth_stable_V
    assert lo <= high.V <= hi                   # a speed the wing's linear loop is certified at
    assert high.attenuation_percent >= 90.0
    # and it has died out: what is left is the linear closed loop's response to the
    # turbulence, as at 1.05 Vf (measured 11.1 against 10.1 m/s^2 on Acc1)
    dom = high.dominant_sensor
    floor = _gust_floor(r.truth, r.controller, high.V, cfg)
    assert high.closed_loop_rms[dom] == pytest.approx(floor[dom], rel=0.2)
    # the run's own start (the truth's established LCO there) and turbulence (seed (seed, k))
    mode, dt = int(r.flutter.flutter_mode), cfg.data.dt
    lco = truth_lco(r.truth, high.V, cfg.lco.duration, mode, cfg.lco.initial_deflection, dt=dt)
    bare = suppression_run(r.truth, r.controller, r.Vf_truth, replace(ss, command_limiter="none"),
                           dt=dt, mode=mode, deflection=cfg.lco.initial_deflection,
                           sensor_rows=cfg.sensors.rows or None, sensor=cfg.sensors.kind,
                           x0=lco.final_state, speed_factor=1.2,
                           seed=(cfg.seed, list(ss.speed_factors).index(1.2)))
    np.testing.assert_allclose(bare.open_loop_rms, high.open_loop_rms, rtol=1e-9)
    assert bare.started_from_lco and bare.lco_returns
    assert np.max(np.abs(np.diff(bare.simulation.v))) / dt \
        <= ss.flap_rate_limit * (1 + 1e-9)
    assert bare.attenuation_percent < 50.0


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_the_other_seeds_suppress_both_lcos_too(seed):
    """Item 4 holds for seeds 0-4 of the default run, not only seed 0 (above): both LCOs
    attenuated by at least 90 % (measured 90.8-91.6 % and 95.1-95.2 %).  This is what
    ``[controller] extra_outer = 0`` in ``run.toml`` keeps: seed 3's design, run on past
    ``max_outer`` while its sensitivity still fell, attenuated the LCO at 1.2 Vf by 33.5 %."""
    r = run(load_config(default_config_path(), seed=seed), quiet=True, write=False)
    att = [r.suppression.at(f).attenuation_percent for f in (1.05, 1.2)]
    assert min(att) >= 90.0, att
