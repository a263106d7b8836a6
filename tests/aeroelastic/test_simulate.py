"""Nonlinear loop simulation: linear test double vs the exact sampled-data loop, LCO vs
harmonic balance, controller with gain schedule."""

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.signal import cont2discrete

from casflutter.aeroelastic import simulate_loop
from casflutter.structure import ModalStructure
from casflutter.data import analyze_response
from casflutter.errors import ConfigError, DimensionError
from casflutter.ident import random_hwl_model

from ._cases import DF2, OMEGA2, ZETA2


class LinearARX:
    """Test double of the HWL-ROM protocol: y_k = a1 y_{k-1} + B0 u_k + B1 u_{k-1} + e v_k."""

    def __init__(self, a1, B0, B1, e, dt):
        self.a1, self.B0, self.B1, self.e, self.dt = a1, np.asarray(B0), np.asarray(B1), np.asarray(e), dt
        self.n_modes, self.max_lag, self.has_u, self.has_v = self.B0.shape[0], 1, True, True

    def step(self, y_hist, u_hist, v_hist):
        return self.a1 * y_hist[1] + self.B0 @ u_hist[0] + self.B1 @ u_hist[1] + self.e * v_hist[0]


class Rayleigh:
    """One-mode ROM with negative, cubic-saturating aerodynamic damping:
    y = c u̇ − c3 u̇³ with u̇ ≈ (u_k − u_{k−1})/dt, plus flap effectiveness e v."""

    def __init__(self, c, c3, e, dt):
        self.c, self.c3, self.e, self.dt = c, c3, e, dt
        self.n_modes, self.max_lag, self.has_u, self.has_v = 1, 1, True, True

    def step(self, y_hist, u_hist, v_hist):
        ud = (u_hist[0] - u_hist[1]) / self.dt
        return self.c * ud - self.c3 * ud ** 3 + self.e * v_hist[0]


def _sampled_loop_growth(rom, s, V):
    """Independent growth rate: eigenvalues of the exact sampled-data loop matrix."""
    N, nx, dt = s.n_modes, s.n_states, rom.dt
    Ad, Bd, *_ = cont2discrete((s.As, s.Bs, np.eye(nx), np.zeros((nx, N))), dt, method="zoh")
    Cs, V2 = s.Cs, V ** 2
    a1 = rom.a1 * np.eye(N)
    # z_k = [xs_k, y_{k-1}, u_{k-1}]
    Phi = np.block([
        [Ad + V2 * Bd @ rom.B0 @ Cs, V2 * Bd @ a1, V2 * Bd @ rom.B1],
        [rom.B0 @ Cs, a1, rom.B1],
        [Cs, np.zeros((N, N)), np.zeros((N, N))]])
    return np.log(np.max(np.abs(np.linalg.eigvals(Phi)))) / dt


@pytest.mark.parametrize("V, kind", [(1.0, "decay"), (2.2, "divergence")])
def test_linear_double_reproduces_sampled_loop_growth_rate(V, kind):
    dt = 2e-3
    s = ModalStructure(OMEGA2, ZETA2, alpha=1.3)
    rom = LinearARX(0.3, 0.7 * DF2, np.zeros((2, 2)), np.zeros(2), dt)
    sim = simulate_loop(rom, s, V, 6000, xs0=[0.01, 0.0, 0.0, 0.05], window=0.5, blowup=1e12)
    sigma = _sampled_loop_growth(rom, s, V)
    assert sim.kind == kind
    assert sim.modes.growth_rate == pytest.approx(sigma, rel=5e-3)


def test_linear_double_close_to_continuous_loop_for_small_dt():
    """The sampled-data loop approaches ΣAE(V) (static Σf = Df) as dt → 0."""
    import control as ct
    from casflutter.aeroelastic import AeroelasticSystem
    s = ModalStructure(OMEGA2, ZETA2, alpha=1.3)
    V, dt = 2.2, 1e-4
    rom = LinearARX(0.0, DF2, np.zeros((2, 2)), np.zeros(2), dt)
    sysae = AeroelasticSystem.from_parts(ct.ss([], [], [], DF2), s)
    sigma_c = np.max(np.linalg.eigvals(sysae.state_matrix(V)).real)
    assert _sampled_loop_growth(rom, s, V) == pytest.approx(sigma_c, rel=0.02)


def _lco_case(dt=1e-3):
    omega, zeta, alpha, V = 2 * np.pi * 5.0, 0.01, 1.0, 1.0
    eps = 0.6  # net negative damping: c αV² − 2ζω
    c = eps + 2 * zeta * omega
    A_target = 0.01
    c3 = 4 * eps / (3 * omega ** 2 * A_target ** 2)
    s = ModalStructure([omega], [zeta], alpha=alpha, Hs=[[2.0]], sensor="displacement")
    return s, Rayleigh(c, c3, 0.0, dt), V, omega, eps, A_target


@pytest.mark.parametrize("u0", [0.004, 0.02])
def test_lco_amplitude_and_frequency_match_harmonic_balance(u0):
    """Rayleigh oscillator ü + ω²u = ε u̇ − β u̇³: harmonic balance A = √(4ε / (3 β ω²))."""
    s, rom, V, omega, eps, A = _lco_case()
    sim = simulate_loop(rom, s, V, 30000, xs0=[u0, 0.0], window=0.3)
    assert sim.kind == "lco"
    # harmonic balance is exact to O((ε/ω)²) ≈ 4e-4 here; sampling adds O((ω dt)²) ≈ 1e-3
    assert_allclose(sim.modes.amplitude[0], A, rtol=2e-3)
    assert_allclose(sim.sensors.amplitude[0], 2.0 * A, rtol=2e-3)
    assert_allclose(sim.modes.frequency_hz, omega / (2 * np.pi), rtol=2e-3)
    assert sim.sensors.kind == "lco"


def test_lco_about_a_static_flap_offset():
    """A held flap v0 shifts the mean by αV²e v0/ω² but leaves the LCO unchanged."""
    s, rom, V, omega, eps, A = _lco_case()
    rom.e, v0 = 1.0, 5.0
    sim = simulate_loop(rom, s, V, 30000, xs0=[0.004, 0.0], v=np.full(30000, v0))
    assert sim.kind == "lco"
    assert_allclose(sim.modes.amplitude[0], A, rtol=2e-3)
    assert_allclose(sim.u[-9000:, 0].mean(), v0 / omega ** 2, rtol=0.02)


def test_linear_negative_damping_diverges_and_positive_decays():
    s, rom, V, omega, eps, A = _lco_case()
    rom.c3 = 0.0
    sim = simulate_loop(rom, s, V, 20000, xs0=[0.01, 0.0], blowup=1.0)
    assert sim.kind == "divergence" and sim.stopped_early
    rom.c = 0.0
    sim = simulate_loop(rom, s, V, 20000, xs0=[0.01, 0.0])
    assert sim.kind == "decay"
    assert sim.modes.growth_rate == pytest.approx(-0.01 * omega, rel=0.02)


def test_controller_with_gain_schedule_suppresses_lco():
    """Velocity feedback v = −k u̇ through the flap adds damping k e αV²: after the gain is
    switched on the envelope decays at (k e − ε)/2."""
    s, rom, V, omega, eps, A = _lco_case()
    s = ModalStructure(s.omega, s.zeta, alpha=1.0, Hs=[[1.0]], sensor="velocity")
    rom.e = 1.0
    k = 2.0
    K = control.ss([], [], [], [[-k]])
    t_on = 15.0
    sim = simulate_loop(rom, s, V, 30000, xs0=[0.01, 0.0], controller=K,
                        gain=lambda t: float(t >= t_on), window=0.4)
    assert sim.kind == "decay"
    assert sim.modes.growth_rate == pytest.approx(-(k * rom.e - eps) / 2, rel=5e-3)
    before = analyze_response(sim.timepts[:15000], sim.u[:15000], window=0.3)
    assert before.kind == "lco"
    assert_allclose(sim.gain[[0, 14999, 15000, -1]], [0, 0, 1, 1])
    assert_allclose(sim.v[16000], -k * sim.zm[16000, 0])


def test_dimension_mismatch_names_both():
    s = ModalStructure(OMEGA2, ZETA2)
    rom = Rayleigh(1.0, 0.0, 0.0, 1e-3)
    with pytest.raises(DimensionError, match=r"n_modes=1.*2 modes"):
        simulate_loop(rom, s, 1.0, 10)


def test_hwl_rom_histories_match_its_own_free_run():
    """With V = 0 the structure is not forced, so the ROM inside the loop must reproduce the
    identification package's own free-run simulation driven by the recorded u and v (history
    before t = 0: u held at u0, y and v zero)."""
    model = random_hwl_model(2, dt=0.005, seed=3)
    s = ModalStructure([12.0, 30.0], [0.02, 0.02])
    rng = np.random.default_rng(11)
    v = rng.uniform(-1, 1, size=400)
    sim = simulate_loop(model, s, 0.0, 400, xs0=s.modal_state(u=[0.5, -0.8], udot=[0.0, 1.0]),
                        v=v)
    L = model.max_lag
    u_ext = np.vstack([np.tile(sim.u[0], (L, 1)), sim.u])
    v_ext = np.concatenate([np.zeros(L), v])
    y_ref = model.simulate(u_ext, v_ext, y0=np.zeros((L, 2)))[L:]
    assert_allclose(sim.y, y_ref, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("zeta", [0.0, 0.02, 1.0, 1.5])
@pytest.mark.parametrize("h", [1e-3, 0.05, 0.7])
def test_structure_step_is_the_matrix_exponential_with_held_and_ramping_force(zeta, h):
    """[Ad, B0, B1] against Van Loan's exponential of the structure with a held and a
    ramping input (scipy), under-, critically and over-damped."""
    from scipy.linalg import expm
    from casflutter.aeroelastic import structure_step
    s = ModalStructure([3.0, 40.0], [zeta, 0.01], alpha=1.7)
    nx, N = s.n_states, s.n_modes
    M = np.zeros((nx + 2 * N, nx + 2 * N))
    M[:nx, :nx], M[:nx, nx:nx + N], M[nx:nx + N, nx + N:] = s.As, s.Bs, np.eye(N) / h
    E = expm(M * h)
    Ad, B0, B1 = (np.asarray(X) for X in structure_step(s)(h))
    assert_allclose(Ad, E[:nx, :nx], rtol=0, atol=1e-12)
    assert_allclose(B0, E[:nx, nx:nx + N], rtol=0, atol=1e-12 * np.abs(B0).max())
    assert_allclose(B1, E[:nx, nx + N:], rtol=0, atol=1e-9 * np.abs(B1).max())


def _loop_growth(s, V, DF, dt, hold):
    """Growth rate of the sampled-data loop with the static ROM y_k = DF u_k, built here with
    scipy: zero-order hold, or predictive first-order hold (state [x_s, F_{k-1}])."""
    from scipy.linalg import expm
    nx, N = s.n_states, s.n_modes
    M = np.zeros((nx + 2 * N, nx + 2 * N))
    M[:nx, :nx], M[:nx, nx:nx + N], M[nx:nx + N, nx + N:] = s.As, s.Bs, np.eye(N) / dt
    E = expm(M * dt)
    Ad, B0, B1 = E[:nx, :nx], E[:nx, nx:nx + N], E[:nx, nx + N:]
    F = V ** 2 * DF @ s.Cs                     # F_k = V^2 DF u_k
    if hold == "zoh":
        Phi = Ad + B0 @ F
    else:
        Phi = np.block([[Ad + (B0 + B1) @ F, -B1], [F, np.zeros((N, N))]])
    return np.log(np.max(np.abs(np.linalg.eigvals(Phi)))) / dt


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_the_loop_steps_at_the_speeds_own_time_step_with_either_hold(hold):
    """With convective_V0 the loop is stepped at dt V0 / V: its growth rate is that of the
    sampled-data loop built with that step (scipy), for either hold.  Against the continuous
    ΣAE(V) the zero-order hold's half-step lag is an error of first order in the step and
    the first-order hold's of second order: halving the step halves the one and quarters the
    other."""
    from casflutter.aeroelastic import AeroelasticSystem
    s = ModalStructure(OMEGA2, ZETA2, alpha=1.3)
    dt, V0, V = 4e-3, 1.5, 2.2
    rom = LinearARX(0.0, DF2, np.zeros((2, 2)), np.zeros(2), dt)
    sim = simulate_loop(rom, s, V, 6000, xs0=[0.01, 0.0, 0.0, 0.05], window=0.5, blowup=1e12,
                        convective_V0=V0, hold=hold)
    h = dt * V0 / V
    assert sim.dt == pytest.approx(h) and sim.timepts[1] == pytest.approx(h)
    assert sim.kind == "divergence"
    assert sim.modes.growth_rate == pytest.approx(_loop_growth(s, V, DF2, h, hold), rel=5e-3)
    sigma_c = np.max(np.linalg.eigvals(AeroelasticSystem.from_parts(
        control.ss([], [], [], DF2), s).state_matrix(V)).real)
    ratio = (_loop_growth(s, V, DF2, 2e-3, hold) - sigma_c) / (
        _loop_growth(s, V, DF2, 1e-3, hold) - sigma_c)
    assert ratio == pytest.approx(2.0 if hold == "zoh" else 4.0, rel=0.1)


def test_the_speed_following_loop_and_hold_are_checked():
    s = ModalStructure(OMEGA2, ZETA2, alpha=1.3)
    rom = LinearARX(0.0, DF2, np.zeros((2, 2)), np.zeros(2), 1e-3)
    with pytest.raises(ConfigError, match="convective_V0 = -1"):
        simulate_loop(rom, s, 1.0, 10, convective_V0=-1.0)
    with pytest.raises(ConfigError, match="V = 0.0"):
        simulate_loop(rom, s, 0.0, 10, convective_V0=1.0)
    with pytest.raises(ConfigError, match="hold = 'linear'"):
        simulate_loop(rom, s, 1.0, 10, hold="linear")
