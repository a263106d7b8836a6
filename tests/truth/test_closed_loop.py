"""The truth in closed loop: the sampled-data loop against the truth's own integrator, the
gain schedule, and the linear loop."""

import control
import numpy as np
import pytest

from casflutter.truth import closed_loop_truth, gain_schedule
from casflutter.truth import load_problem


@pytest.fixture(scope="module")
def wing():
    return load_problem("seed_wing")


def test_gain_schedule():
    g = gain_schedule(1.0, 2.0, 3.0)
    assert [g(t) for t in (0.5, 1.0, 2.0, 3.0, 5.9, 6.0, 7.0)] == [0, 0, 0.5, 1, 1, 0, 0]


def test_open_loop_matches_truth_simulate(wing):
    """With the gain at zero the flap stays at rest and the RK4 sampled-data loop must
    reproduce the truth's own adaptive integration (DOP853)."""
    V, dt = 1.0, 0.002
    t = np.arange(0.0, 1.0, dt)
    x0 = wing.displaced_state(1, 0.05)
    K = control.ss([[-1.0]], [[1.0, 1.0]], [[1.0]], [[0.0, 0.0]])
    cl = closed_loop_truth(wing, K, V, t, x0, lambda tt: 0.0)
    ref = wing.simulate(t, x0, V)
    Hs = np.asarray(wing.modal_structure().Hs)
    zm_ref = ref.uddot @ Hs.T
    err = np.abs(cl.zm - zm_ref).max() / np.abs(zm_ref).max()
    assert err < 1e-5
    np.testing.assert_array_equal(cl.v, 0.0)


def test_flap_dynamics_linearisation_is_state_matrix(wing):
    """Small-amplitude flap_dynamics equals the linear state matrix (flap at rest)."""
    V = 1.1
    f = wing.flap_dynamics(V)
    A = wing.state_matrix(V)
    rng = np.random.default_rng(0)
    s = 1e-7 * rng.normal(size=A.shape[0])
    ds, _ = f(s, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(ds, A @ s, rtol=1e-4, atol=1e-12 * np.abs(A @ s).max())


def _aggressive_loop(wing, **limits):
    """A high static gain from both accelerometers to the flap at 1.1 Vf: without limits
    the commanded flap runs far past any real servo's travel and rate."""
    V, dt = 1.1, 0.002
    t = np.arange(0.0, 0.6, dt)
    K = control.ss([], [], [], [[-0.05, -0.05]])
    return dt, closed_loop_truth(wing, K, V, t, wing.displaced_state(1, 0.05),
                                 lambda tt: 1.0, **limits)


def test_flap_position_and_rate_limits_hold(wing):
    """The servo never exceeds its travel or its rate, and the limits bite (the unlimited
    run exceeds both), so the check is not vacuous."""
    pos, rate = 0.05, 2.0
    dt, free = _aggressive_loop(wing)
    _, lim = _aggressive_loop(wing, flap_limit=pos, flap_rate_limit=rate)
    free_v, lim_v = free.v[np.isfinite(free.zm[:, 0])], lim.v
    assert np.abs(free_v).max() > 2 * pos or np.abs(np.diff(free_v)).max() / dt > 2 * rate
    assert np.abs(lim_v).max() <= pos * (1 + 1e-12)
    # the recorded samples are dt apart; the RK4 rate clip holds inside every substep
    assert np.abs(np.diff(lim_v)).max() / dt <= rate * (1 + 1e-9)


def test_the_rate_limit_holds_against_a_noisy_command(wing):
    """Sensor noise makes the command jump at every sample, so the servo's acceleration is
    large inside each Runge--Kutta step: the flap still moves no faster than the limit
    between samples, and its recorded rate stays within it."""
    rate = 2.0
    noise = 50.0 * np.random.default_rng(2).standard_normal((300, 2))
    dt, lim = _aggressive_loop(wing, flap_limit=0.2, flap_rate_limit=rate, sensor_noise=noise)
    assert np.abs(np.diff(lim.v)).max() / dt == pytest.approx(rate, rel=1e-9)
    assert np.abs(lim.v_rate).max() <= rate * (1 + 1e-12)


def test_limits_far_away_change_nothing(wing):
    """Limits the loop never reaches leave the simulation bit-identical."""
    _, free = _aggressive_loop(wing)
    _, far = _aggressive_loop(wing, flap_limit=1e9, flap_rate_limit=1e9)
    np.testing.assert_array_equal(free.v, far.v)
    np.testing.assert_array_equal(free.zm, far.zm)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_bad_limits_are_refused(wing, bad):
    from casflutter.errors import ConfigError
    from casflutter.truth import SuppressionSettings
    with pytest.raises(ConfigError, match="flap_limit"):
        _aggressive_loop(wing, flap_limit=bad)
    with pytest.raises(ConfigError, match="flap_rate_limit"):
        SuppressionSettings(flap_rate_limit=bad)


@pytest.mark.slow
def test_suppression_starts_from_the_established_lco(wing):
    """Started from the end state of a converged truth LCO, the open-loop amplitude the
    controller is switched on against is that LCO's amplitude (peak vs half peak-to-peak of
    a near-symmetric cycle: within 3 %), and with a zero controller nothing is attenuated
    (the LCO is a stable cycle, it neither grows nor decays: within 3 %)."""
    from casflutter.aeroelastic import find_flutter
    from casflutter.truth import SuppressionSettings, suppression_run, truth_lco
    Vf = find_flutter(wing.state_matrix, (0.3, 2.0), omega=wing.modal_structure().omega).Vf
    sp = SuppressionSettings(speed_factors=[1.05], settle=1.5, ramp=0.5, hold=1.5, release=0.5,
                             flap_limit=0.2618, flap_rate_limit=5.236)
    lco = truth_lco(wing, 1.05 * Vf, 10.0, 1, 0.01, dt=0.002)  # the run's [lco] settings
    assert lco.kind == "lco" and lco.final_state is not None
    K0 = control.ss([], [], [], [[0.0, 0.0]])
    run = suppression_run(wing, K0, Vf, sp, dt=0.002, mode=1, deflection=0.01,
                          x0=lco.final_state)
    assert run.started_from_lco
    dom = run.dominant_sensor
    assert run.open_loop_amplitude[dom] == pytest.approx(lco.amplitude[dom], rel=0.03)
    assert abs(run.attenuation_percent) < 3.0


def test_the_controller_starts_at_its_engagement(wing):
    """A near-integrator controller (pole at -1e-4, no feed-through) beside an oscillating
    wing: while the gain is zero its state stays at rest, so its first command at switch-on
    is exactly zero and the flap is still at rest one sample later -- a controller that had
    run open-loop would command ``C x`` with ``x`` the integral of the open-loop sensors."""
    V, dt, t_on = 1.1, 0.002, 0.3
    t = np.arange(0.0, 0.5, dt)
    x0 = wing.displaced_state(1, 0.05)
    K = control.ss([[-1e-4]], [[1.0, 1.0]], [[1e-3]], [[0.0, 0.0]])
    run = closed_loop_truth(wing, K, V, t, x0, lambda tt: 1.0 if tt >= t_on else 0.0)
    on = int(np.argmax(t >= t_on))
    open_loop_command = 1e-3 * abs(run.zm[:on].sum() * dt)
    assert open_loop_command > 1e-5            # what a running controller would command
    assert run.v[on] == 0.0 and run.v[on + 1] == 0.0
    assert np.abs(run.v[on + 2:on + 10]).max() > 0   # and the loop does act after that


def test_the_release_ends_when_the_lco_is_back(wing):
    """A suppression run ends at the first sample of the release at which the dominant
    sensor's RMS over the open-loop window's length (settle / 3) is back above half its
    open-loop RMS; here against the full-length record of the same loop (the criterion
    computed on it with numpy): the run is that record's prefix, cut at that sample."""
    from casflutter.truth import SuppressionSettings, gain_schedule, suppression_run
    V, dt = 1.3, 0.002
    sp = SuppressionSettings(settle=0.6, ramp=0.2, hold=0.4, release=1.0)
    K = control.ss([[-20.0]], [[1e-3, 1e-3]], [[1.0]], [[0.0, 0.0]])
    run = suppression_run(wing, K, V / 1.05, sp, dt=dt, mode=1, deflection=0.01,
                          speed_factor=1.05)
    t, t_release = np.arange(0.0, 2.2, dt), 0.6 + 0.2 + 0.4
    full = closed_loop_truth(wing, K, V, t, wing.displaced_state(1, 0.01),
                             gain_schedule(0.6, 0.2, 0.4), kick=(t_release, 1, 0.01)).zm
    opened = (t >= 0.4) & (t < 0.6)
    m, dom = int(opened.sum()), run.dominant_sensor
    half = 0.5 * np.sqrt(np.mean(full[opened, dom] ** 2))
    k_release = int(np.argmax(t >= t_release))        # the gain is off, the wing tapped
    returned = [k for k in range(k_release + m - 1, t.size)
                if np.sqrt(np.mean(full[k - m + 1:k + 1, dom] ** 2)) > half]
    assert returned and returned[0] < t.size - 1       # the criterion cuts the record short
    n = returned[0] + 1
    assert run.simulation.zm.shape == (n, 2) and run.lco_returns
    np.testing.assert_array_equal(run.simulation.zm, full[:n])
    np.testing.assert_allclose(run.released_rms, np.sqrt(np.mean(full[n - m:n] ** 2, axis=0)))


def test_runs_in_worker_processes_give_the_numbers_of_this_process(wing):
    """The runs at two speeds, in turbulence and noise, computed in two worker processes
    and in this one: every sample of the records is the same (each run carries its own seed,
    ``(seed, k)``).  Without a fork (macOS, Windows) both run here."""
    from casflutter.errors import ConfigError
    from casflutter.truth import SuppressionSettings, suppression_runs
    sp = SuppressionSettings(speed_factors=[1.05, 1.2], settle=0.6, ramp=0.2, hold=0.4,
                             release=0.2, gust_intensity=0.005, gust_scale=0.1, noise=0.1,
                             flap_limit=0.2618, flap_rate_limit=5.236)
    K = control.ss([[-20.0]], [[1e-3, 1e-3]], [[1.0]], [[0.0, 0.0]])
    kw = dict(dt=0.002, mode=1, deflection=0.01, lco_duration=0.5, seed=7)
    here = suppression_runs(wing, K, 1.085, sp, workers=1, **kw)
    apart = suppression_runs(wing, K, 1.085, sp, workers=2, **kw)
    assert [r.V for r in apart] == [r.V for r in here] == [1.05 * 1.085, 1.2 * 1.085]
    for a, b in zip(here, apart):
        assert np.array_equal(a.simulation.zm, b.simulation.zm)
        assert np.array_equal(a.simulation.v, b.simulation.v)
        assert a.attenuation_percent == b.attenuation_percent
    with pytest.raises(ConfigError, match="workers = -1"):
        suppression_runs(wing, K, 1.085, sp, workers=-1, **kw)
