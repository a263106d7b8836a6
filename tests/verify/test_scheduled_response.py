"""Time response of the ROM loop along a speed profile, controllers switched with the speed.

Fixture: ``default_rom_loop`` (the default run's frozen ROM loop of eq. 8) with the flap behind
the 40 Hz servo, and the order-4 pair ``tests/witnesses/rom_order4_{low,high}_controller.json``
(certified over (0, 1.9033) and (1.8442, 2.4014), ``tests/verify/test_rom_witness.py``).
Truth used: python-control's ``forced_response`` of the loop closed by ``control.feedback`` at a
fixed speed; switch times worked out from the piecewise-linear profile by hand; and the frozen
closed loop's spectral abscissa (``closed_loop_abscissa``), which the response must follow once
the speed stops changing.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest
from scipy.signal import lfilter

from casflutter.errors import ConfigError
from casflutter.verify import load_controller, scheduled_response

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"

SERVO = 251.3
SWITCH = 1.875              # inside the overlap (1.8442, 1.9033) of the two certificates


@pytest.fixture(scope="module")
def family(default_rom_loop):
    return default_rom_loop[0].with_servo(SERVO)


@pytest.fixture(scope="module")
def pair():
    return [load_controller(WITNESS_DIR / f"rom_order4_{end}_controller.json")
            for end in ("low", "high")]


def _gust(n_total, n_on, dt=1e-3, seed=0):
    """A seeded gust on the first mode's force, low-passed at 10 rad/s, over the first
    ``n_on`` samples."""
    w = np.zeros((n_total, 5))
    a = np.exp(-10 * dt)
    w[:n_on, 0] = 1e-2 * lfilter([1 - a], [1, -a], np.random.default_rng(seed).normal(size=n_on))
    return w


@pytest.mark.parametrize("servo, feedthrough", [(True, False), (False, True)])
def test_at_a_fixed_speed_the_response_is_python_controls(default_rom_loop, family, pair,
                                                          servo, feedthrough):
    """One controller at V = 1.2 from an initial modal displacement: the measurements and the
    flap command agree with ``control.forced_response`` of the loop closed by
    ``control.feedback`` (exact discretisation on both sides).  Also without the servo, where
    the accelerometers see the flap directly (D22 ≠ 0), with a controller feed-through, so
    that the algebraic loop ``(1 − Dk D22)⁻¹`` is exercised."""
    V, K = 1.2, pair[0]
    if feedthrough:
        K = control.ss(K.A, K.B, K.C, [[2e-4, -3e-4]])      # Dk D22 ≈ −0.2 at V = 1.2
    loop = (family if servo else default_rom_loop[0]).loop(V)
    assert servo or np.any(loop.D22 != 0)
    P = loop.statespace()
    x0 = np.zeros(P.nstates)
    x0[0] = 1e-2
    r = scheduled_response(lambda _: P, [K], [], [0.0, 3.0], [V, V], x0=x0, dt=2e-3)
    assert r.switches == () and r.stopped_at is None and np.all(r.controller == 0)
    # v = K zm closed by python-control: the controller's outputs land on the flap input only
    nw = P.ninputs - 1
    Kx = control.ss(K.A, K.B, np.vstack([np.zeros((nw, K.nstates)), K.C]),
                    np.vstack([np.zeros((nw, K.ninputs)), K.D]))
    cl = control.feedback(P, Kx, sign=1)
    ref = control.forced_response(cl, r.t, np.zeros((P.ninputs, r.t.size)),
                                  X0=np.concatenate([x0, np.zeros(K.nstates)]),
                                  return_x=True)
    zm = np.asarray(ref.outputs).T
    v = (np.asarray(K.C) @ np.asarray(ref.states)[P.nstates:]).T + zm @ np.asarray(K.D).T
    scale = np.max(np.abs(zm))
    np.testing.assert_allclose(r.measurements, zm, atol=1e-8 * scale)
    np.testing.assert_allclose(r.control, v, atol=1e-8 * np.max(np.abs(v)))


def test_switches_happen_half_the_hysteresis_past_the_switch_speed(family, pair):
    """Up from 1.80 to 2.00 in 10 s and back: with a hysteresis of 0.02 the switch up is at
    V = 1.885 (t = 4.25 s) and the switch down at V = 1.865 (t = 16.75 s); the incoming
    controller starts from rest, so (strictly proper) its first command is zero; with
    ``transfer="output"`` it starts where its command repeats the last one."""
    x0 = np.zeros(family.loop(1.8).A.shape[0])
    x0[0] = 1e-2
    dt = 1e-3
    r = scheduled_response(lambda V: family.loop(V).statespace(), pair, [SWITCH],
                           [0.0, 10.0, 20.0], [1.8, 2.0, 1.8], x0=x0, hysteresis=0.02, dt=dt)
    (t_up, V_up, a, b), (t_down, V_down, c, d) = r.switches
    assert (a, b, c, d) == (0, 1, 1, 0)
    assert t_up == pytest.approx(4.25, abs=dt) and V_up == pytest.approx(1.885, abs=2e-5)
    assert t_down == pytest.approx(16.75, abs=dt) and V_down == pytest.approx(1.865, abs=2e-5)
    k_up, k_down = np.searchsorted(r.t, [t_up, t_down])
    assert np.all(r.controller[:k_up] == 0) and np.all(r.controller[k_up:k_down] == 1)
    assert np.all(r.controller[k_down:] == 0)
    assert all(np.allclose(np.asarray(K.D), 0) for K in pair)
    assert r.control[k_up, 0] == 0.0 and r.control[k_down, 0] == 0.0
    assert r.control[k_up - 1, 0] != 0.0
    # transfer="output": the incoming controller repeats the last command, so it does not jump
    smooth = scheduled_response(lambda V: family.loop(V).statespace(), pair, [SWITCH],
                                [0.0, 10.0, 20.0], [1.8, 2.0, 1.8], x0=x0, hysteresis=0.02,
                                dt=dt, transfer="output")
    assert [sw[:2] for sw in smooth.switches] == [sw[:2] for sw in r.switches]
    for k in (k_up, k_down):
        assert smooth.control[k, 0] == pytest.approx(smooth.control[k - 1, 0], rel=1e-9)
        assert smooth.control[k, 0] != 0.0


def test_the_order4_pair_holds_a_speed_sweep_the_low_controller_alone_does_not(
        family, pair, closed_loop_abscissa):
    """A 40-s sweep from V = 0.05 to 2.4 under a seeded gust, then 30 s at 2.4 without it.

    Switched at 1.875 (hysteresis 0.02), the pair holds: the run never blows up, and once the
    gust stops the response decays at the frozen loop's rate at V = 2.4 (its spectral
    abscissa, −0.057 rad/s: the thin margin the gallery shows).  The low controller alone
    follows the same path up to the switch, then blows up at a speed where its frozen loop is
    unstable."""
    dt, T, H = 1e-3, 40.0, 30.0
    n = int(round((T + H) / dt)) + 1
    w = _gust(n, int(T / dt), dt)
    plant = lambda V: family.loop(V).statespace()        # noqa: E731
    both = scheduled_response(plant, pair, [SWITCH], [0.0, T, T + H], [0.05, 2.4, 2.4],
                              disturbance=w, hysteresis=0.02, dt=dt)
    low = scheduled_response(plant, pair[:1], [], [0.0, T, T + H], [0.05, 2.4, 2.4],
                             disturbance=w, dt=dt)
    assert both.stopped_at is None and len(both.switches) == 1
    t_switch = both.switches[0][0]
    k = np.searchsorted(both.t, t_switch)
    np.testing.assert_array_equal(low.measurements[:k], both.measurements[:k])
    # after the gust: envelope (1-s peaks) against the frozen closed loop's abscissa at 2.4
    starts = np.arange(T + 5.0, T + H - 1.0, 1.0)
    peaks = np.array([both.peak(a, a + 1.0) for a in starts])
    rate = np.polyfit(starts + 0.5, np.log(peaks), 1)[0]
    frozen = closed_loop_abscissa(family, pair[1], 2.4)
    assert -0.1 < frozen < 0
    assert rate == pytest.approx(frozen, rel=0.1)
    # the low controller alone: blown up (state norm past 1e50) where its frozen loop grows
    assert low.stopped_at is not None and low.stopped_at < T
    assert closed_loop_abscissa(family, pair[0], float(low.V[-1])) > 1.0


@pytest.mark.parametrize("kwargs, words", [
    (dict(times=[0.0], speeds=[1.0]), "two or more breakpoints"),
    (dict(times=[0.0, "a"], speeds=[1.0, 1.0]), "times = .*'a' is not a finite number"),
    (dict(switch_speeds=["x"]), "switch_speeds = .*'x' is not a finite number"),
    (dict(times=[1.0, 2.0], speeds=[1.0, 1.0]), "start at 0"),
    (dict(times=[0.0, 1.0], speeds=[1.0, -1.0]), ">= 0"),
    (dict(switch_speeds=[1.0, 2.0]), "need 1 switch speeds"),
    (dict(switch_speeds=[2.0, 1.0], n_controllers=3), "increase"),
    (dict(hysteresis=0.2, switch_speeds=[1.0, 1.1], n_controllers=3), "smallest gap"),
    (dict(hysteresis=-1.0), ">= 0"),
    (dict(hysteresis="wide"), "hysteresis"),
    (dict(transfer="bumpless"), "transfer"),
    (dict(dt=0.0), "dt"),
    (dict(dt=5.0), "shorter than the run"),
    (dict(disturbance=np.zeros((3, 5))), "disturbance"),
    (dict(x0=np.zeros(3)), "x0"),
    (dict(x0=None), "no excitation"),
    (dict(ncon=9), "ncon"),
    (dict(controller=control.ss(-1.0, [[1.0, 1.0, 1.0]], 1.0, 0.0)), "3 inputs"),
])
def test_bad_requests_are_refused_before_any_simulation(family, pair, kwargs, words):
    P = family.loop(1.0).statespace()
    x0 = np.ones(P.nstates)
    n_controllers = kwargs.pop("n_controllers", 2)
    K = kwargs.pop("controller", pair[0])
    args = dict(times=[0.0, 1.0], speeds=[1.0, 1.0], switch_speeds=[SWITCH], x0=x0)
    args.update(kwargs)
    with pytest.raises(ConfigError, match=words):
        scheduled_response(lambda _: P, [K] * n_controllers, args.pop("switch_speeds"),
                           args.pop("times"), args.pop("speeds"), **args)
