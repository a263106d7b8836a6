"""Which ROM loop predicts a flutter controller on the seed wing?

The paper's ROM is identified at one speed V0 and closed with the V² scaling of eq. 8, which
freezes the aerodynamic time scale at V0.  A controller that holds the seed wing over
V ∈ (0, 2.4) — the order-8 witness, certified on the truth in
``tests/verify/test_truth_witness.py`` — is closed around each model and compared with the
wing (the truth's own linearisation, :class:`casflutter.aeroelastic.TruthLoop`, the
reference):

* the parametric ROM (linear ROMs at seven speeds, interpolated in V; paper §V future work);
* the convective ROM (one linear ROM at V0, its time scaled by V/V0:
  ``AeroelasticSystem(convective_V0=V0)``), which is what strip theory's dependence on the
  reduced frequency implies;
* the frozen ROM of eq. 8 as the paper writes it (the run's HWL ROM, and the linear ROM
  unscaled), which loses the loop below the flutter speed.

Every loop has the flap behind the same 40 Hz servo.  Last, the paper's order-3 design at Vf
is made on the convective and on the frozen linear ROM, and the interval each certifies on
its own loop is compared with the one the wing certifies.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.aeroelastic import (AeroelasticSystem, ParametricSystem, TruthLoop, build_lft,
                                   find_flutter)
from casflutter.errors import ConfigError
from casflutter.ident import identify_common_denominator
from casflutter.realize import ParametricROM, speed_nodes
from casflutter.truth import RecordSettings, SeedWing, truth_records
from casflutter.verify import load_controller, speed_family_interval

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"

SERVO = 251.3                           # rad/s, the seed wing's 40 Hz servo
SPEEDS = np.linspace(0.3, 2.3, 21)      # the parametric ROM's nodes span (0.3, 2.5)
V0 = 0.69                               # the paper's identification speed (Table I)


def _rightmost(A):
    lam = np.linalg.eigvals(A)
    return lam[np.argmax(lam.real)]


@pytest.fixture(scope="module")
def models():
    truth = SeedWing()
    records = RecordSettings(amplitude=0.002, coupling_delay=0)   # flutter.toml's records
    nodes = speed_nodes((0.3, 2.5), 7)
    rom = ParametricROM(nodes, tuple(
        identify_common_denominator(truth_records(truth, records, V0=float(v)), 2, 6)
        for v in nodes))
    K = load_controller(WITNESS_DIR / "truth_interval_controller_order8.json")
    return ParametricSystem(rom, truth.modal_structure()), TruthLoop(truth, SERVO), K


def test_the_parametric_rom_predicts_the_closed_loop_on_the_wing(models):
    psys, truth, K = models
    for V in SPEEDS:
        lam = np.linalg.eigvals(psys.loop(V).with_servo(SERVO).closed_loop_state_matrix(K))
        lt = _rightmost(truth.closed_loop_state_matrix(V, K))
        # both stable, with the same spectral abscissa to 0.3 rad/s (the witness's rates are
        # 0.3-1.1 rad/s), and the wing's rightmost mode is in the ROM loop to 4 % (the flutter
        # branch to 1 %; at 2.3 the rightmost is a 143 rad/s mode, 3.3 % off)
        assert lam.real.max() < 0 and lt.real < 0, V
        assert abs(lam.real.max() - lt.real) < 0.3, V
        assert np.min(np.abs(lam - lt)) < 0.04 * abs(lt), V


def test_the_frozen_rom_does_not(models, default_rom_loop):
    _, _, K = models
    frozen, Vf = default_rom_loop
    worst = max(_rightmost(frozen.loop(V).with_servo(SERVO).closed_loop_state_matrix(K)).real
                for V in SPEEDS[SPEEDS < Vf])
    assert worst > 1.0      # unstable below its own flutter speed (1.2)


def test_the_servo_multiplies_the_flap_path_by_its_transfer_function(models):
    psys, _, _ = models
    lp = psys.loop(1.5)
    omega, zeta = SERVO, 0.7
    G = lp.flap_to_sensors()
    Gs = lp.with_servo(omega, zeta).flap_to_sensors()
    for w in (3.0, 60.0, 400.0):
        s = 1j * w
        servo = omega ** 2 / (s * s + 2 * zeta * omega * s + omega ** 2)
        np.testing.assert_allclose(Gs(s), G(s) * servo, rtol=1e-8)
    # the disturbance feed-through is kept, the flap's is now a state
    assert np.array_equal(lp.with_servo(omega).D21, lp.D21)
    assert not np.any(lp.with_servo(omega).D22)


@pytest.mark.parametrize("omega, zeta", [(0.0, 0.7), (-1.0, 0.7), (100.0, -0.1),
                                         (float("nan"), 0.7)])
def test_a_bad_servo_is_refused(models, omega, zeta):
    with pytest.raises(ConfigError, match="servo omega"):
        models[0].loop(1.0).with_servo(omega, zeta)


def test_the_parametric_loop_is_the_system_at_that_speed(models):
    psys, _, K = models
    V = 1.7
    np.testing.assert_allclose(psys.loop(V).A, psys.state_matrix(V), rtol=1e-12, atol=1e-9)
    P = psys.system_at(V).loop(V).flap_to_sensors()
    Acl = control.feedback(P, K, sign=1).A
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(Acl)),
                               np.sort_complex(np.linalg.eigvals(
                                   psys.closed_loop_state_matrix(V, K))), rtol=1e-7, atol=1e-7)


@pytest.fixture(scope="module")
def convective(seed_wing_sigma_f):
    truth, sigma_f = SeedWing(), seed_wing_sigma_f
    return (AeroelasticSystem.from_parts(sigma_f, truth.modal_structure(), convective_V0=V0),
            AeroelasticSystem.from_parts(sigma_f, truth.modal_structure()))


def test_one_rom_scaled_in_time_has_the_wings_flutter_speed(convective, models):
    conv, frozen = convective
    wing = models[1]
    grid = dict(V_range=(0.3, 2.5), n_grid=23)
    Vf_wing = find_flutter(SeedWing(), **grid).Vf                       # 1.085
    assert abs(find_flutter(conv, **grid).Vf / Vf_wing - 1) < 0.01      # 1.080
    assert abs(find_flutter(frozen, **grid).Vf / Vf_wing - 1) > 0.05    # 1.003
    # and the whole open-loop spectral abscissa, to 3.5 V0 (0.04 rad/s against 8.7 at 2.4)
    for V in np.linspace(0.3, 2.4, 15):
        a_wing = wing.loop(V).poles().real.max()
        assert abs(conv.loop(V).poles().real.max() - a_wing) < 0.05, V


def test_the_convective_rom_certifies_the_wings_controller(convective, models):
    conv, _ = convective
    K = models[2]
    cert = speed_family_interval(lambda V: conv.loop(V).with_servo(SERVO).flap_to_sensors(),
                                 K, 1.0)
    # on the wing: (0, 2.4007) (test_truth_witness.py); on this ROM loop to 0.01 of it
    assert cert.lower == 0.0 and cert.upper > 2.39


def test_the_scaled_loop_is_eq_8_with_the_lags_times_v_over_v0(convective):
    conv, frozen = convective
    s, V = conv.structure, 1.9
    r = V / V0
    A = np.block([[s.As + V ** 2 * s.Bs @ conv.Df @ s.Cs, V ** 2 * s.Bs @ conv.Cf],
                  [r * conv.Bf @ s.Cs, r * conv.Af]])
    np.testing.assert_allclose(conv.state_matrix(V), A, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(conv.loop(V).B2[-conv.n_f:], r * conv.bf, rtol=1e-13)
    # at V0 it is the paper's loop
    np.testing.assert_allclose(conv.state_matrix(V0), frozen.state_matrix(V0), rtol=1e-13,
                               atol=1e-12)


@pytest.mark.parametrize("bad", [0.0, -0.5, float("nan"), float("inf"), True, "0.69"])
def test_a_bad_identification_speed_is_refused(convective, bad):
    frozen = convective[1]
    with pytest.raises(ConfigError, match="convective_V0"):
        AeroelasticSystem(frozen.structure, frozen.Af, frozen.Bf, frozen.bf, frozen.Cf,
                          frozen.Df, frozen.df, convective_V0=bad)


def test_the_paper_lft_of_a_scaled_loop_is_exact_at_its_speed(convective):
    conv, frozen = convective
    Vf = 1.08
    lft = build_lft(conv, Vf)
    np.testing.assert_allclose(lft.A, conv.state_matrix(Vf), rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(lft.B2[:, 0], conv.loop(Vf).B2, rtol=1e-13, atol=1e-12)
    # it is the LFT of the ROM frozen at Vf, not of the one frozen at V0
    assert not np.allclose(lft.A, build_lft(frozen, Vf).A)
    assert conv.frozen_at(Vf).convective_V0 is None
    assert frozen.frozen_at(Vf) is frozen


def test_a_design_on_the_scaled_rom_is_certified_for_the_wing(convective, models):
    """The paper's order-3 design at Vf (run.toml's controller settings) on each ROM: the
    interval certified on the convective ROM loop (flap behind the servo) is the wing's to
    0.5 % (measured 0.1 %); on the frozen ROM it is not (measured 8 % too wide)."""
    from dataclasses import replace

    from casflutter._settings import settings_as
    from casflutter.design import SynthesisOptions, synthesize, with_flap_rate
    from casflutter.pipeline import config_path, load_config

    cfg = load_config(config_path("seed_wing", "run"))
    c = cfg.controller
    options = replace(settings_as(c, SynthesisOptions), ipopt={**cfg.solver.ipopt, **c.ipopt})
    wing = models[1]
    ends = {}
    for name, system in zip(("convective", "frozen"), convective):
        Vf = find_flutter(system, (0.3, 2.5), n_grid=56).Vf
        lft = build_lft(system, Vf)
        P = with_flap_rate(lft.P, lft.nmeas, c.flap_rate_weight, c.flap_rate_bandwidth)
        K = synthesize(P, lft.nmeas, lft.ncon, c.order, starts=c.starts, seed=0,
                       options=options).controller
        on_rom = speed_family_interval(
            lambda V: system.loop(V).with_servo(SERVO).flap_to_sensors(), K, Vf)
        on_wing = speed_family_interval(lambda V: wing.loop(V).flap_to_sensors(), K, V0)
        assert on_rom.lower == on_wing.lower == 0.0
        ends[name] = on_rom.upper / on_wing.upper - 1
    assert abs(ends["convective"]) < 0.005
    assert abs(ends["frozen"]) > 0.03
