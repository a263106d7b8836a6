"""How far one controller holds the seed wing's ROM loop stable (continuation in speed).

Fixture: ``default_rom_loop`` (``problems/seed_wing_rom/rom_loop_seed0.npz``, Σf and Σs of the
default run, seed 0).
Truth used: the independent verification layer's exact stable interval (guardian map on the
LFT at Vf) and eigenvalues of the closed loop computed here.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from casflutter.aeroelastic import build_lft
from casflutter.design import full_order_start, loop_abscissa, stabilize_interval
from casflutter.errors import ConfigError
from casflutter.verify import verify_controller


def _exact(system, nominal, K):
    """The verification layer's exact interval on the LFT built at ``nominal``."""
    lft = build_lft(system, nominal)
    return verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=nominal, n_delta=lft.n_delta)


def test_continuation_extends_the_interval_and_the_verification_certifies_it(default_rom_loop):
    system, _ = default_rom_loop
    hi, lo = 2.4, 2.15
    start = full_order_start(system, hi)
    # the start does not hold (lo, hi): the loop is unstable at lo
    assert loop_abscissa(system, start, [lo])[0] > 0
    reach = stabilize_interval(system, start, (lo, hi), anchor="high", n_speeds=20)
    assert reach.met and reach.reached == (lo, hi)
    assert reach.controller.nstates == start.nstates
    ver = _exact(system, hi, reach.controller)
    assert ver.stable and ver.exact_V[0] <= lo and ver.exact_V[1] >= hi
    # the continuation's own dense scan agrees with eigenvalues computed here
    assert np.all(loop_abscissa(system, reach.controller, np.linspace(lo, hi, 60)) < 0)
    assert reach.worst_abscissa < 0


def test_full_order_start_stabilises_the_loop_at_its_speed(default_rom_loop):
    system, _ = default_rom_loop
    for V in (1.5, 2.4):
        K = full_order_start(system, V)
        assert K.nstates == system.n_states
        A = system.closed_loop_state_matrix(V, K)
        assert np.max(np.linalg.eigvals(A).real) < 0
        # and the open loop there is unstable: the controller does the work
        assert np.max(np.linalg.eigvals(system.state_matrix(V)).real) > 0


def test_bad_requests_are_refused_before_any_work(default_rom_loop):
    system, Vf = default_rom_loop
    K = full_order_start(system, 2.4)
    with pytest.raises(ConfigError, match="interval"):
        stabilize_interval(system, K, (2.0, 1.0))
    with pytest.raises(ConfigError, match="anchor"):
        stabilize_interval(system, K, (0.05, 2.4), anchor="middle")
    idle = control.ss([[-1.0]], [[0.0, 0.0]], [[0.0]], [[0.0, 0.0]])   # K = 0
    with pytest.raises(ConfigError, match="does not stabilise"):
        stabilize_interval(system, idle, (0.05, 2.4), anchor="high")   # open loop flutters
    with pytest.raises(ConfigError, match="> 0"):
        full_order_start(system, 2.4, state_weight=0.0)


@pytest.mark.slow
def test_continuation_on_the_truth_loop_is_certified_on_the_truth():
    """The same continuation on the seed wing's own linearisation (flap behind the 40 Hz
    servo): the interval it claims is inside the verification layer's exact interval on the
    truth (polynomial guardian map, python-control closing the loop)."""
    from casflutter.aeroelastic import TruthLoop
    from casflutter.truth import SeedWing
    from casflutter.verify import speed_family_interval

    fam = TruthLoop(SeedWing(), 251.3)
    hi, lo = 2.4, 1.8
    start = full_order_start(fam, hi)
    assert loop_abscissa(fam, start, [lo])[0] > 0
    reach = stabilize_interval(fam, start, (lo, hi), anchor="high", n_speeds=20)
    assert reach.met

    cert = speed_family_interval(lambda V: fam.loop(V).flap_to_sensors(), reach.controller,
                                 0.5 * (lo + hi))
    assert cert.lower <= lo and cert.upper >= hi


def test_the_feedthrough_gradient_is_the_finite_difference_one(default_rom_loop):
    """``free_feedthrough``: the eigenvalue gradient with respect to ``Dk`` (through the
    algebraic loop ``1/(1 - Dk D22)`` of the accelerometers) against central differences."""
    from casflutter.design._interval import _ClosedLoopsAtSpeeds, _pack

    system, Vf = default_rom_loop
    assert np.any(system.loop(Vf).D22 != 0)        # the algebraic loop is exercised
    rng = np.random.default_rng(3)
    K = control.ss(rng.normal(size=(3, 3)) - 3 * np.eye(3), rng.normal(size=(3, 2)),
                   rng.normal(size=(1, 3)), 0.05 * rng.normal(size=(1, 2)))
    loops = _ClosedLoopsAtSpeeds(system, [0.5 * Vf, Vf], 3, np.asarray(K.D))
    p = _pack(K, True)
    _, grads = loops.rightmost(p)
    h = 1e-6
    for k in range(2):
        fd = np.array([(loops.rightmost(p + h * e)[0][k] - loops.rightmost(p - h * e)[0][k])
                       / (2 * h) for e in np.eye(len(p))])
        # relative to the largest entry; the last two are ∂/∂Dk
        assert np.max(np.abs(fd - grads[k])) < 1e-6 * np.max(np.abs(fd))
        assert np.all(np.abs(fd[-2:]) > 0)


def test_the_worst_from_eigenvalues_alone_is_the_full_computation(default_rom_loop):
    """The objective at ``tau = None`` takes eigenvectors only at the worst speed: its value
    and gradient are those of the loop whose every eigenvector is computed (``rightmost``),
    and its value is the largest real part of eigenvalues computed here."""
    from casflutter.design._interval import _ClosedLoopsAtSpeeds, _pack

    system, Vf = default_rom_loop
    K = full_order_start(system, Vf)
    speeds = np.linspace(0.3, 2.4, 12)
    loops = _ClosedLoopsAtSpeeds(system, speeds, K.nstates, np.asarray(K.D))
    p = _pack(K, False)
    value, grad = loops.smoothed(p, None)
    values, grads = loops.rightmost(p)
    k = int(np.argmax(values))
    here = max(float(np.max(np.linalg.eigvals(system.closed_loop_state_matrix(V, K)).real))
               for V in speeds)
    assert value == pytest.approx(here, abs=1e-9 * max(1.0, abs(here)))
    assert value == pytest.approx(values[k], abs=1e-9 * max(1.0, abs(here)))
    np.testing.assert_allclose(grad, grads[k], rtol=1e-8, atol=1e-10 * np.max(np.abs(grads[k])))


def test_a_free_feedthrough_is_optimised_and_certified(default_rom_loop):
    system, Vf = default_rom_loop
    hi, lo = 2.4, 2.15
    reach = stabilize_interval(system, full_order_start(system, hi), (lo, hi), anchor="high",
                               n_speeds=20, free_feedthrough=True)
    assert reach.met and np.any(np.asarray(reach.controller.D) != 0)   # the start has D = 0
    ver = _exact(system, hi, reach.controller)
    assert ver.stable and ver.exact_V[0] <= lo and ver.exact_V[1] >= hi


def test_one_controller_for_several_models(default_rom_loop):
    """A sequence of loop families: the continuation holds the worst of them.  Here the ROM
    loop and the same loop with the flap behind a 40 Hz servo; each result is certified on
    both by the verification layer."""
    from casflutter.verify import speed_family_interval

    system, _ = default_rom_loop
    servo = system.with_servo(251.3)
    hi, lo = 2.4, 2.15
    reach = stabilize_interval([system, servo], full_order_start(system, hi), (lo, hi),
                               anchor="high", n_speeds=20)
    assert reach.met
    ver = _exact(system, hi, reach.controller)
    assert ver.stable and ver.exact_V[0] <= lo and ver.exact_V[1] >= hi
    cert = speed_family_interval(lambda V: servo.loop(V).flap_to_sensors(), reach.controller, hi)
    assert cert.lower <= lo and cert.upper >= hi


def test_models_with_other_sensors_are_refused(default_rom_loop):
    from dataclasses import replace

    from casflutter.aeroelastic import LoopFamily
    from casflutter.errors import DimensionError

    system, _ = default_rom_loop

    class ThreeSensors(LoopFamily):          # the first accelerometer twice
        def loop(self, V):
            lp = system.loop(V)
            return replace(lp, C2=np.vstack([lp.C2, lp.C2[:1]]),
                           D21=np.vstack([lp.D21, lp.D21[:1]]), D22=np.r_[lp.D22, lp.D22[:1]])

    K = full_order_start(system, 2.4)
    with pytest.raises(DimensionError, match="different numbers of sensors"):
        stabilize_interval([system, ThreeSensors()], K, (2.15, 2.4), anchor="high")
    with pytest.raises(ConfigError, match="loop family"):
        stabilize_interval([], K, (2.15, 2.4), anchor="high")
