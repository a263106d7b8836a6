"""Invariant circles of the sampled-data seed-wing ROM loop (HWL ROM of ``casflutter run`` in
feedback with Σs, problems/seed_wing_rom/rom.npz): the map against
:func:`casflutter.aeroelastic.simulate_loop` step by step, the Neimark--Sacker point against
the growth of simulated disturbances, and the circles against long simulations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casflutter.aeroelastic import simulate_loop
from casflutter.ident import HWLModel
from casflutter.lco import LCOSettings, rom_lco_branch, rom_loop_map
from casflutter.truth import SeedWing

ROM = Path(__file__).resolve().parents[2] / "problems" / "seed_wing_rom" / "rom.npz"


@pytest.fixture(scope="module")
def loop():
    rom = HWLModel.load(ROM)
    ms = SeedWing().modal_structure()
    st = ms.with_sensors(kind="displacement")
    return rom, st, ms


@pytest.fixture(scope="module")
def branch(loop):
    rom, st, ms = loop
    return rom_lco_branch(rom, st, (0.6, 1.42), LCOSettings(harmonics=8),
                          mode_names=ms.mode_names, sensor_names=ms.sensor_names,
                          problem="seed_wing (ROM loop)", speed_scale=28.9, speed_unit="m/s")


def _map_state(sim, k, L, Ly):
    """The map's state at sample k of a simulate_loop record: ``[x_s, u_{k-1..k-L},
    y_{k-1..k-Ly}]`` (inputs held at u_0 and outputs zero before the release)."""
    uh = [sim.u[k - d] if k - d >= 0 else sim.u[0] for d in range(1, L + 1)]
    yh = [sim.y[k - d] if k - d >= 0 else np.zeros(sim.y.shape[1]) for d in range(1, Ly + 1)]
    return np.concatenate([sim.xs[k], *uh, *yh])


def _assert_map_steps_the_record(F, sim, V, L, Ly):
    for k in (Ly + 1, 50, 200, 398):
        nxt = np.asarray(F(_map_state(sim, k, L, Ly), V)).ravel()
        ref = _map_state(sim, k + 1, L, Ly)
        assert np.max(np.abs(nxt - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_map_is_one_step_of_simulate_loop(loop):
    """The CasADi map reproduces simulate_loop's recursion along a simulated record."""
    rom, st, _ = loop
    F = rom_loop_map(rom, st)
    N, L = rom.n_modes, rom.max_lag
    V = 1.25
    xs0 = np.zeros(2 * N)
    xs0[2] = 0.05
    sim = simulate_loop(rom, st, V, 400, xs0=xs0)
    _assert_map_steps_the_record(F, sim, V, L, L)


def test_neimark_sacker_point_against_simulated_growth(loop, branch):
    """A small disturbance decays 1 % below the Neimark-Sacker speed and grows 1 % above."""
    rom, st, _ = loop
    Vns = branch.hopf.V
    xs0 = np.zeros(2 * rom.n_modes)
    xs0[2] = 1e-4
    for factor, sign in ((0.99, -1), (1.01, 1)):
        sim = simulate_loop(rom, st, Vns * factor, 6000, xs0=xs0, window=0.5)
        assert np.sign(sim.modes.growth_rate) == sign
    assert branch.hopf.discrete
    assert branch.hopf.freq_hz == pytest.approx(9.29, abs=0.05)


def test_supercritical_and_consistent(branch):
    h = branch.hopf
    assert h.kind == "supercritical" and h.lyapunov < 0 and h.consistent
    assert h.branch_direction == 1
    # the ROM's nonlinearity is quadratic (p = q = 2): the agreement checks the B terms of d
    assert h.normal_form_agreement == pytest.approx(1.0, abs=0.02)
    assert branch.system == "rom_loop" and branch.completed
    assert all(p.trivial_error < 1e-2 for p in branch.points)
    assert all(p.stable for p in branch.points)


@pytest.mark.parametrize("target", [1.30, 1.40])
def test_circles_against_simulate_loop(loop, branch, target):
    """At a branch point's speed, simulate_loop released from a small deflection settles on
    the circle: amplitude per mode and sensor and frequency within 2 %."""
    rom, st, ms = loop
    p = min(branch.points, key=lambda q: abs(q.V - target))
    xs0 = np.zeros(2 * rom.n_modes)
    xs0[2] = 0.01
    sim = simulate_loop(rom, st, p.V, 25000, xs0=xs0, window=0.2)
    assert sim.kind == "lco"
    for i, name in enumerate(ms.mode_names[:3]):
        assert sim.modes.amplitude[i] == pytest.approx(p.amplitude[name], rel=0.02), name
    for j, name in enumerate(ms.sensor_names):
        assert sim.sensors.amplitude[j] == pytest.approx(p.amplitude[name], rel=0.02), name
    assert sim.modes.frequency_hz == pytest.approx(p.freq_hz, rel=0.02)


def test_accelerometer_outputs_against_simulate_loop(loop):
    """With sensor_kind="acceleration" the sensors are Hs u'' read at t_k as simulate_loop
    reads accelerometers (the held force of the previous step)."""
    rom, st, ms = loop
    acc = st.with_sensors(kind="acceleration")
    br = rom_lco_branch(rom, acc, (0.6, 1.32), LCOSettings(harmonics=8, sensor_kind="acceleration"),
                        mode_names=ms.mode_names, sensor_names=ms.sensor_names)
    p = br.points[-1]
    xs0 = np.zeros(2 * rom.n_modes)
    xs0[2] = 0.01
    sim = simulate_loop(rom, acc, p.V, 25000, xs0=xs0, window=0.2)
    for j, name in enumerate(ms.sensor_names):
        assert sim.sensors.amplitude[j] == pytest.approx(p.amplitude[name], rel=0.02), name


def test_the_speed_following_map_is_one_step_of_simulate_loop(loop):
    """Stepped at dt V0 / V with the first-order hold (the ROM without the records' coupling
    delay, the loop of the ROM that follows the wing), the map still reproduces
    simulate_loop's recursion; its state keeps two past forces for the hold's slope and the
    accelerometers' left limit."""
    rom, st, _ = loop
    rom = rom.advanced(1)
    F = rom_loop_map(rom, st, convective_V0=0.69, hold="foh")
    N, L = rom.n_modes, rom.max_lag
    Ly = max(L, 2)
    assert F.size1_in(0) == 2 * N + (L + Ly) * N
    V = 1.25
    xs0 = np.zeros(2 * N)
    xs0[2] = 0.05
    sim = simulate_loop(rom, st, V, 400, xs0=xs0, convective_V0=0.69, hold="foh")
    assert sim.dt == pytest.approx(rom.dt * 0.69 / V)
    _assert_map_steps_the_record(F, sim, V, L, Ly)


def test_the_speed_following_loop_flutters_where_its_continuous_loop_does(loop):
    """With the first-order hold the sampled loop's Neimark-Sacker point lies within 0.5 % of
    the Hopf point of its continuous ΣAE (Σf realised at its exact order from the same ROM,
    time scaled by V / V0); with the zero-order hold the half-step lag moves it by more than
    5 %.  Both are searched independently (map multipliers vs ΣAE eigenvalues)."""
    from casflutter.aeroelastic import speed_following_rom
    from casflutter.lco import rom_loop_flutter
    rom, st, _ = loop
    acc = st.with_sensors(kind="acceleration")
    sf = speed_following_rom(rom, acc, 0.69, coupling_delay=1)
    Vc = sf.flutter.Vf
    V_foh = rom_loop_flutter(sf.model, acc, (0.8, 1.6), n_grid=41, convective_V0=0.69,
                             hold="foh")
    V_zoh = rom_loop_flutter(sf.model, acc, (0.8, 1.6), n_grid=41, convective_V0=0.69)
    assert V_foh == pytest.approx(Vc, rel=5e-3)
    assert abs(V_zoh / Vc - 1) > 0.05
