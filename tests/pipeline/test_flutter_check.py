"""The flutter check (``problems/typical_section/flutter_check.toml``, a configuration of the
study run): an order-2 controller through the flap of the typical section, designed on the
ROM's LFT at the ROM's flutter speed Vf.

Targets: the verified exact stable interval of V contains [0.5 Vf, 1.2 Vf]; above the
open-loop flutter speed (1.1 Vf) the open loop grows and the closed loop decays, on the ROM
loop and on the truth.  Every number is checked against an independent computation:

- the truth's flutter speed against the published Hodges & Pierce value (Jones aero), the
  ROM's against the truth's (at the fixed point V0 = Vf_ROM the ROM is the truth frozen at
  its own flutter speed, so the two must agree to the identification error);
- the exact interval (guardian-map pencil, casflutter.verify) against a dense eigenvalue
  sweep of the same loop, and the verified γ against the synthesis's own γ for that plant;
- simulated envelope growth rates against the spectral abscissae of the linear loops.
  Open loop (one growing mode dominates): truth, same model in an RK4 sampled-data loop,
  to 1e-3 (measured 1e-5); ROM, the discrete HWL model with ZOH force coupling at dt = 0.1
  against the Tustin realisation, to 5e-3 (measured 3e-3, the half-sample delay of the
  coupling).  Closed loop: to 0.01 (several modes decay at comparable rates; measured
  differences 0.001-0.007).
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError
from casflutter.pipeline import config_path, load_config, run
from casflutter.truth import TypicalSection, problem_definition, truth_loop_matrix

#: the slow check: five design plants and up to 20 minimax solves
FULL = {"controller.speeds": [0.5, 1.0, 1.1, 1.2, 1.25], "controller.max_outer": 20}


def flutter_check_settings(**updates):
    """The flutter-check configuration with dotted-path changes."""
    return load_config(config_path("typical_section", "flutter_check"), updates=updates)


def flutter_check(cfg=None):
    return run(cfg or flutter_check_settings(), quiet=True, write=False)


def _check_rom_and_truth_flutter(res):
    ref = problem_definition("typical_section")["reference"]["jones"]
    assert_allclose(res.Vf_truth, ref["flutter_speed"], rtol=ref["rtol"])
    V0, Vf = res.identification_history[-1]
    assert abs(Vf - V0) <= res.config.rom.v0_rtol * Vf
    # the first ROM (V0 = 1.8) is 4 % off; at the fixed point it is the truth at Vf
    assert abs(res.identification_history[0][1] / res.Vf_truth - 1) > 0.03
    assert_allclose(res.Vf, res.Vf_truth, rtol=2e-3)
    assert res.identification.relative_residual < 1e-10


def _check_verification(res):
    ver, syn = res.verification, res.synthesis
    assert res.controller.nstates == res.config.controller.order == 2
    assert ver.stable and np.isfinite(ver.gamma)
    # the verified γ of the nominal plant is the synthesis's own γ for that plant
    i = list(res.config.controller.speeds).index(1.0)
    assert_allclose(ver.gamma, syn.gammas[i], rtol=1e-6)
    assert_allclose(ver.small_gain_dV[1], 1.0 / ver.gamma, rtol=1e-12)
    # small gain is a certificate inside the exact interval
    (a, b), (lo, hi) = ver.small_gain_V, ver.exact_V
    assert lo <= a < res.Vf < b <= hi


def _check_dense_sweep(res):
    """The exact interval against the eigenvalues of the same loop on a dense V grid:
    stable at every grid point inside, unstable at the grid points just beyond each finite
    edge (further out the loop may be stable again: the interval is the component of the
    stable set that contains Vf)."""
    sw = res.rom_sweep
    lo, hi = res.verification.exact_V
    inside = (sw.V > lo * 1.001) & (sw.V < hi * 0.999)
    assert inside.sum() > 100 and np.all(sw.spectral_abscissa[inside] < 0)
    above = sw.V > hi * 1.001
    assert np.all(sw.spectral_abscissa[above][:5] > 0)
    below = (sw.V < lo * 0.999) & (sw.V > 0)
    assert np.all(sw.spectral_abscissa[below][-5:] > 0)


def _check_simulations(res):
    rom, tru = res.closed_loop.rom_simulation, res.closed_loop.truth_simulation
    assert_allclose(rom.V, res.config.closed_loop.speed_factor * res.Vf)
    assert_allclose(tru.V, res.config.closed_loop.speed_factor * res.Vf_truth)
    for sim, tol in ((rom, 5e-3), (tru, 1e-3)):
        assert sim.open_eig_rate > 0 > sim.closed_eig_rate
        assert sim.grows_open_decays_closed, sim.model
        assert_allclose(sim.open_rate, sim.open_eig_rate, atol=tol)
        # several closed-loop modes decay at comparable rates and the envelope fit mixes
        # them (and the ROM's ZOH coupling): agreement to 0.01 (measured up to 0.0072)
        assert_allclose(sim.closed_rate, sim.closed_eig_rate, atol=0.01)


def _check_targets(res):
    """The issue's targets: the verified interval on the ROM, and open-loop growth /
    closed-loop decay above flutter on the ROM and on the truth (linear loop stable at the
    simulation speed, edges of its stable interval are eigenvalue crossings)."""
    assert res.interval_ok, (res.verification.exact_V, res.required_V)
    _check_dense_sweep(res)
    _check_simulations(res)
    assert res.success
    tsw = res.closed_loop.truth_sweep
    a, b = tsw.stable_V
    assert a < res.Vf_truth < res.closed_loop.truth_simulation.V < b
    kw = dict(actuator_omega=res.config.closed_loop.actuator_omega,
              actuator_zeta=res.config.closed_loop.actuator_zeta)
    for edge in (a, b):
        if tsw.V[0] < edge < tsw.V[-1]:
            A = truth_loop_matrix(TypicalSection(), res.controller, edge, **kw)
            assert abs(np.linalg.eigvals(A).real.max()) < 1e-7
    # open loop: the sweep's zero crossing is the truth's own flutter speed
    crossing = tsw.V[np.argmax(tsw.open_abscissa > 1e-9)]
    assert_allclose(crossing, res.Vf_truth, atol=2 * (tsw.V[1] - tsw.V[0]))


def _check_truth_interval(res):
    """Past the issue: the truth's closed loop is stable on the same multiples of its own
    flutter speed as the ROM's verified interval must cover."""
    a, b = res.closed_loop.truth_sweep.stable_V
    lo, hi = res.config.verify.required
    assert a <= lo * res.Vf_truth and b >= hi * res.Vf_truth, (a, b)


def test_flutter_check():
    """The problem's settings (problems/typical_section/flutter_check.toml: design plants at
    0.5, 1, 1.2 and 1.25 Vf).  One test function, not a module
    fixture shared by several: under ``pytest -n 2`` a shared fixture would be computed once
    per worker.  Measured: truth closed loop stable on (0.02, 1.2413) x Vf_truth."""
    res = flutter_check()
    _check_rom_and_truth_flutter(res)
    _check_verification(res)
    _check_targets(res)
    _check_truth_interval(res)


def test_truth_loop_matrix_without_controller_is_the_truth():
    """K = 0: the open truth plus the actuator's poles."""
    import control
    T = TypicalSection()
    K = control.ss(np.diag([-1.0, -2.0]), np.zeros((2, 2)), np.zeros((1, 2)), np.zeros((1, 2)))
    wa, za, V = 10.0, 0.7, 2.0
    ev = np.sort_complex(np.linalg.eigvals(truth_loop_matrix(T, K, V, actuator_omega=wa,
                                                              actuator_zeta=za)))
    act = np.roots([1.0, 2 * za * wa, wa * wa])
    ref = np.sort_complex(np.r_[np.linalg.eigvals(T.state_matrix(V)), act, -1.0, -2.0])
    assert_allclose(ev, ref, rtol=1e-9, atol=1e-9)


def test_settings_validation():
    with pytest.raises(ConfigError, match="unknown key 'V00' in \\[data\\] \\(did you mean 'V0'\\?\\); allowed: V0"):
        flutter_check_settings(**{"data.V00": 2.0})
    with pytest.raises(ConfigError, match="containing 1.0"):
        flutter_check_settings(**{"controller.speeds": [0.5, 1.2]})
    with pytest.raises(ConfigError, match="closed_loop.speed_factor = 0.9: must be > 1"):
        flutter_check_settings(**{"closed_loop.speed_factor": 0.9})
    s = flutter_check_settings()
    assert s.controller.order == 2 and s.verify.required == (0.5, 1.2)


@pytest.fixture(scope="module")
def full():
    return flutter_check(flutter_check_settings(**FULL))


@pytest.mark.slow
def test_flutter_check_full(full):
    """Five design plants, full-length records, up to 20 minimax solves."""
    _check_rom_and_truth_flutter(full)
    _check_verification(full)
    _check_targets(full)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "the five-plant design (gamma 9.776, exact interval (0, 1.378) x Vf on the ROM) leaves "
    "the truth stable only on (0.02, 1.119) x Vf_truth (closed-loop eigenvalue crossing at "
    "V = 2.4279; at 1.1 Vf_truth it decays at only -0.0030): robustness on the ROM family "
    "(aerodynamics frozen at Vf, scaled by V^2) does not carry over to the truth above Vf; "
    "the three-plant default design reaches 1.241 x Vf_truth"))
def test_full_truth_stable_on_the_required_range(full):
    _check_truth_interval(full)
