"""Typical section truth vs Hodges & Pierce HP-1, analytic divergence, and an independent
frequency-domain Theodorsen/Jones evaluation written here from the textbook formulas."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve
from scipy.special import hankel2

from casflutter.errors import ConfigError, DataError, DimensionError
from casflutter.truth import (TypicalSection, TypicalSectionParams, load_problem,
                              strip_coefficients, theodorsen_T)
from casflutter.aeroelastic import find_flutter

ROOT = Path(__file__).resolve().parents[2]
with open(ROOT / "problems" / "typical_section" / "problem.toml", "rb") as _fh:
    DEF = tomllib.load(_fh)
REF = DEF["reference"]


# ---- independent textbook formulas (Hodges & Pierce ch. 5, Theodorsen 1935) --------------
def C_theodorsen(k):
    H1, H0 = hankel2(1, k), hankel2(0, k)
    return H1 / (H1 + 1j * H0)


def C_jones(k):
    ik = 1j * k
    return 1 - 0.165 * ik / (ik + 0.0455) - 0.335 * ik / (ik + 0.3)


def physical_forces(p, V, w, xi, th, beta, C):
    """Nondimensional [-L/(m b w_th^2), M/(m b^2 w_th^2)] for harmonic motion e^{i w tau}."""
    a, mu, c = p.a, p.mu, p.flap_hinge
    T = theodorsen_T(c)
    s = 1j * w
    Q = s * xi + V * th + (0.5 - a) * s * th + V / np.pi * T["T10"] * beta \
        + T["T11"] / (2 * np.pi) * s * beta
    k = w / V
    L = (s * s * xi + V * s * th - a * s * s * th - V / np.pi * T["T4"] * s * beta
         - T["T1"] / np.pi * s * s * beta) / mu + 2 / mu * V * C(k) * Q
    M = (a * s * s * xi - V * (0.5 - a) * s * th - (0.125 + a * a) * s * s * th) / mu \
        - ((T["T4"] + T["T10"]) * V * V * beta
           + (T["T1"] - T["T8"] - (c - a) * T["T4"] + 0.5 * T["T11"]) * V * s * beta
           - (T["T7"] + (c - a) * T["T1"]) * s * s * beta) / (np.pi * mu) \
        + 2 / mu * V * (a + 0.5) * C(k) * Q
    return np.array([-L, M])


def flutter_determinant(p, C, V0, w0):
    """Solve det(-w^2 M + K - F(w, V)) = 0 for (V, w) (Theodorsen's determinant)."""
    xt = p.e - p.a
    M = np.array([[1, xt], [xt, p.r2]])
    K = np.diag([p.sigma ** 2, p.r2])

    def F(V, w):
        cols = [physical_forces(p, V, w, 1.0, 0.0, 0.0, C),
                physical_forces(p, V, w, 0.0, 1.0, 0.0, C)]
        return np.array(cols).T

    def res(z):
        d = np.linalg.det(-z[1] ** 2 * M + K - F(z[0], z[1]))
        return [d.real, d.imag]

    V, w = fsolve(res, [V0, w0], xtol=1e-13)
    assert np.max(np.abs(res([V, w]))) < 1e-10
    return V, w


# ---- published values ----------------------------------------------------------------
def test_problem_definition_matches_defaults():
    p = TypicalSectionParams()
    for name, value in DEF["parameters"].items():
        assert getattr(p, name) == pytest.approx(value, rel=1e-12), name


def test_hp1_flutter_jones_matches_published():
    """HP-1 with Jones' Wagner approximation: V_F = 2.170, Omega/omega_theta = 0.644 (0.5%)."""
    fp = find_flutter(TypicalSection(), (0.5, 3.0), n_grid=60)
    assert fp.found
    ref = REF["jones"]
    assert_allclose(fp.Vf, ref["flutter_speed"], rtol=ref["rtol"])
    assert_allclose(fp.omega_f, ref["flutter_frequency_ratio"], rtol=ref["rtol"])


def test_state_space_flutter_equals_independent_jones_determinant():
    """The eigenvalue crossing equals the frequency-domain determinant with Jones' C(k)."""
    p = TypicalSectionParams()
    fp = find_flutter(TypicalSection(p), (0.5, 3.0), n_grid=60)
    V, w = flutter_determinant(p, C_jones, 2.2, 0.65)
    assert_allclose([fp.Vf, fp.omega_f], [V, w], rtol=1e-7)


def test_theodorsen_determinant_matches_published():
    """The same textbook formulas with the exact C(k): 2.185, 0.648, k = 0.297 (0.5%)."""
    p = TypicalSectionParams()
    V, w = flutter_determinant(p, C_theodorsen, 2.2, 0.65)
    ref = REF["theodorsen"]
    assert_allclose(V, ref["flutter_speed"], rtol=ref["rtol"])
    assert_allclose(w, ref["flutter_frequency_ratio"], rtol=ref["rtol"])
    assert_allclose(w / V, ref["reduced_frequency"], rtol=ref["rtol"])


def test_divergence_analytic():
    """A real eigenvalue crosses zero at V_D = sqrt(mu r^2 / (1 + 2a)) = 2.828."""
    m = TypicalSection()
    VD = find_flutter(m, (0.5, 3.0), n_grid=60).divergence.V
    p = m.params
    assert_allclose(VD, np.sqrt(p.mu * p.r2 / (1 + 2 * p.a)), rtol=1e-9)
    assert_allclose(VD, REF["divergence"]["speed"], rtol=REF["divergence"]["rtol"])
    lam = np.linalg.eigvals(m.state_matrix(VD))
    assert np.min(np.abs(lam)) < 1e-7


def test_modal_structure_eq6():
    """Modes diagonalise the structure; alpha = 1/(pi mu); names; uncoupled when e = a."""
    m = TypicalSection()
    ms = m.modal_structure()
    Mh, Kh = m._structure_matrices()
    assert_allclose(ms.shapes.T @ Mh @ ms.shapes, np.eye(2), atol=1e-12)
    assert_allclose(ms.shapes.T @ Kh @ ms.shapes, np.diag(ms.omega ** 2), atol=1e-12)
    assert_allclose(ms.alpha, 1 / (np.pi * 20.0))
    assert ms.mode_names == ("plunge", "pitch")
    # e = a: uncoupled, omega = (sigma, 1)
    mu = TypicalSection(TypicalSectionParams(e=-0.2)).modal_structure()
    assert_allclose(mu.omega, [0.4, 1.0], rtol=1e-12)
    As, Bs = ms.As, ms.Bs
    assert_allclose(np.sort(np.abs(np.linalg.eigvals(As).imag)),
                    np.sort(np.repeat(ms.omega, 2)), rtol=1e-12)
    assert_allclose(Bs[1, 0], ms.alpha)


# ---- aero_forces against the independent frequency-domain formulas -------------------
@pytest.mark.parametrize("pass_derivatives", [True, False])
def test_aero_forces_harmonic_steady_state(pass_derivatives):
    """Harmonic modal motion + flap: steady-state y equals the Jones transfer function."""
    p = TypicalSectionParams()
    m = TypicalSection(p)
    ms = m.modal_structure()
    V, w = 1.6, 0.55
    uhat = np.array([0.3 + 0.1j, -0.05 + 0.2j])
    bhat = 0.02 - 0.01j
    dt = 0.05
    t = np.arange(0.0, 450.0, dt)
    E = np.exp(1j * w * t)
    u = np.real(np.outer(E, uhat))
    v = np.real(bhat * E)
    kw = {}
    if pass_derivatives:
        kw = dict(udot=np.real(np.outer(1j * w * E, uhat)),
                  uddot=np.real(np.outer(-w * w * E, uhat)),
                  vdot=np.real(1j * w * bhat * E), vddot=np.real(-w * w * bhat * E))
    y = m.aero_forces(t, u, v, V, **kw)
    xhat = ms.shapes @ uhat
    fhat = physical_forces(p, V, w, xhat[0], xhat[1], bhat, C_jones)
    yhat = ms.shapes.T @ fhat / (ms.alpha * V * V)
    y_ref = np.real(np.outer(E, yhat))
    sl = slice(int(350 / dt), len(t) - 20)  # lag transients (rate 0.0455 V) have decayed
    assert_allclose(y[sl], y_ref[sl], atol=2e-6 * np.max(np.abs(yhat)))


def test_flap_coefficients_reduce_to_pitch_for_leading_edge_hinge():
    """A flap hinged at the leading edge (c = -1) is the whole airfoil pitching about a = -1."""
    sc = strip_coefficients(rho=1.3, b=0.7, U=11.0, a=-1.0, c=-1.0)
    assert_allclose([sc.Lb1, sc.Lb2, sc.Mb1, sc.Mb2, sc.Qb0, sc.Qb1],
                    [sc.La1, sc.La2, sc.Ma1, sc.Ma2, sc.Qa0, sc.Qa1], rtol=1e-12)
    assert abs(sc.Mb0) < 1e-12


def test_closed_loop_with_aero_forces_reproduces_simulation():
    """Integrating eq. (6) with the truth's own state space, then feeding the motion to
    aero_forces, satisfies u'' + omega^2 u = alpha V^2 y; and the linear simulation equals
    expm(A t) x0."""
    m = TypicalSection()
    ms = m.modal_structure()
    V = 1.8
    t = np.arange(0.0, 60.0, 0.02)
    x0 = np.array([0.02, -0.01, 0.0, 0.005])
    sim = m.simulate(t, x0, V)
    assert sim.success
    A = m.state_matrix(V)
    full0 = np.concatenate([x0, np.zeros(A.shape[0] - 4)])
    assert_allclose(sim.states[-1], expm(A * t[-1]) @ full0, atol=1e-8)
    for kw in ({"udot": sim.udot, "uddot": sim.uddot}, {}):
        y = m.aero_forces(t, sim.u, None, V, **kw)
        lhs = sim.uddot + ms.omega ** 2 * sim.u
        scale = np.max(np.abs(lhs))
        assert_allclose(ms.alpha * V * V * y[:-10], lhs[:-10], atol=2e-6 * scale)


def test_eigenvalues_satisfy_independent_transfer_function():
    """Every oscillatory eigenvalue s of state_matrix(V) makes the Laplace-domain flutter
    matrix (Jones' C continued to ik -> s b/U) singular."""
    p = TypicalSectionParams()
    m = TypicalSection(p)
    ms = m.modal_structure()
    V = 1.4
    xt = p.e - p.a
    M = np.array([[1, xt], [xt, p.r2]])
    K = np.diag([p.sigma ** 2, p.r2])
    lam = np.linalg.eigvals(m.state_matrix(V))
    osc = lam[np.abs(lam.imag) > 1e-3]
    assert osc.size == 4
    for s in osc:
        w = s / 1j  # complex frequency: e^{i w tau} = e^{s tau}
        F = np.array([physical_forces(p, V, w, 1, 0, 0, C_jones),
                      physical_forces(p, V, w, 0, 1, 0, C_jones)]).T
        D = s * s * M + K - F
        sv = np.linalg.svd(D, compute_uv=False)
        assert sv[-1] < 1e-9 * sv[0]
    assert ms.omega.size == 2


def test_omega_theta_scales_time():
    """omega_theta only rescales time: same V_F, omega_F x omega_theta, same y."""
    s = 7.0
    m1, m7 = TypicalSection(), TypicalSection(TypicalSectionParams(omega_theta=s))
    f1, f7 = find_flutter(m1, (0.5, 3.0), n_grid=60), find_flutter(m7, (0.5, 3.0), n_grid=60)
    assert_allclose(f7.Vf, f1.Vf, rtol=1e-8)
    assert_allclose(f7.omega_f, s * f1.omega_f, rtol=1e-8)
    t = np.arange(0, 40, 0.02)
    u = np.column_stack([np.sin(0.4 * t) * t / 40, 0.1 * np.cos(0.9 * t)])
    v = 0.01 * np.sin(0.3 * t)
    assert_allclose(m7.aero_forces(t / s, u, v, 1.3), m1.aero_forces(t, u, v, 1.3),
                    rtol=1e-6, atol=1e-9)


def test_statespace_flap_static_response():
    """DC gain from flap command equals the quasi-steady static aeroelastic solution."""
    p = TypicalSectionParams()
    m = TypicalSection(p)
    ms = m.modal_structure()
    V = 1.5
    sys = m.statespace(V, actuator_omega=5.0)
    assert sys.ninputs == 1 + 2 and sys.noutputs == 2 + 2
    g = np.asarray(sys.dcgain())[:, 0]
    T = theodorsen_T(p.flap_hinge)
    # static: sigma^2 xi = -(2/mu) V^2 (th + T10 b / pi);
    # r^2 th = -(T4+T10) V^2 b/(pi mu) + (2/mu) V^2 (a + 1/2)(th + T10 b / pi), b = 1
    q = 2 / p.mu * V * V
    th = (-(T["T4"] + T["T10"]) * V * V / (np.pi * p.mu) + q * (p.a + 0.5) * T["T10"] / np.pi) \
        / (p.r2 - q * (p.a + 0.5))
    xi = -q * (th + T["T10"] / np.pi) / p.sigma ** 2
    u_static = np.linalg.solve(ms.shapes, [xi, th])
    assert_allclose(g[:2], u_static, rtol=1e-9)
    assert_allclose(g[2:], [xi, th], rtol=1e-9)
    # poles: the aeroelastic eigenvalues plus the actuator's
    poles = np.sort_complex(sys.poles())
    ref = np.sort_complex(np.concatenate([np.linalg.eigvals(m.state_matrix(V)),
                                          np.roots([1, 2 * 0.7 * 5.0, 25.0])]))
    assert_allclose(poles, ref, rtol=1e-8, atol=1e-10)


# ---- nonlinear pitch stiffness -------------------------------------------------------
def test_lco_amplitude_matches_describing_function():
    """Hardening k(theta) = 1 + kappa2 theta^2 above V_F: a limit cycle whose pitch amplitude
    matches the describing-function (harmonic-balance) estimate within 2%."""
    kappa2 = 20.0
    base = TypicalSection()
    VF = find_flutter(base, (0.5, 3.0), n_grid=60).Vf
    V = 1.05 * VF
    m = base.with_updates(kappa2=kappa2)
    t = np.arange(0.0, 600.0, 0.1)
    sim = m.simulate(t, [0.0, 0.01, 0.0, 0.0], V)
    assert sim.success
    theta = (sim.u @ m.modal_structure().shapes.T)[:, 1]
    A_sim = np.max(np.abs(theta[t > 450]))
    assert_allclose(np.max(np.abs(theta[(t > 300) & (t <= 450)])), A_sim, rtol=1e-3)

    # harmonic balance: k_eff = 1 + 3/4 kappa2 A^2 is an equivalent linear section with
    # omega_theta' = sqrt(k_eff), sigma' = sigma / sqrt(k_eff), V' = V / sqrt(k_eff)
    def hb(keff):
        mk = base.with_updates(sigma=base.params.sigma / np.sqrt(keff))
        return find_flutter(mk, (1.0, 3.0), n_grid=20).Vf * np.sqrt(keff) - V

    keff = brentq(hb, 1.0, 1.3, xtol=1e-10)
    A_hb = np.sqrt((keff - 1) / (0.75 * kappa2))
    assert_allclose(A_sim, A_hb, rtol=0.02)


def test_nonlinear_simulation_satisfies_structure_with_aero_forces():
    """simulate() with polynomial pitch stiffness: its motion, fed to aero_forces, satisfies
    u'' + omega^2 u + Phi^T f_nl(Phi u) = alpha V^2 y with f_nl written here."""
    k = dict(kappa1=-3.0, kappa2=40.0, kappa3=-10.0, kappa4=100.0)
    m = TypicalSection().with_updates(**k)
    ms = m.modal_structure()
    p = m.params
    V = 2.0
    t = np.arange(0.0, 40.0, 0.01)
    sim = m.simulate(t, [0.01, 0.05, 0.0, 0.0], V)
    x = sim.u @ ms.shapes.T
    th = x[:, 1]
    fnl = p.r2 * th * (k["kappa1"] * th + k["kappa2"] * th ** 2 + k["kappa3"] * th ** 3
                       + k["kappa4"] * th ** 4)
    y = m.aero_forces(t, sim.u, None, V, udot=sim.udot, uddot=sim.uddot)
    lhs = sim.uddot + ms.omega ** 2 * sim.u + np.outer(fnl, ms.shapes[1])
    assert_allclose(ms.alpha * V * V * y, lhs, atol=1e-7 * np.max(np.abs(lhs)))


# ---- bad input -----------------------------------------------------------------------
def test_unknown_set_name_lists_valid_names():
    with pytest.raises(ConfigError, match=r"unknown parameter 'muu'.*valid names: a, e, mu"):
        load_problem("typical_section", ["muu=3"])
    with pytest.raises(ConfigError, match="name=value"):
        TypicalSectionParams.from_sets(["mu"])
    with pytest.raises(ConfigError, match="must be a number"):
        TypicalSectionParams.from_sets(["mu=abc"])
    with pytest.raises(ConfigError, match="unknown problem 'nope'.*typical_section"):
        load_problem("nope")


@pytest.mark.parametrize("change, match", [
    ({"mu": 0.0}, "mu"), ({"r2": 0.001}, "positive definite"), ({"a": 1.2}, "a = "),
    ({"zeta": -0.1}, "zeta"), ({"flap_hinge": 1.0}, "flap_hinge")])
def test_nonphysical_values_rejected(change, match):
    with pytest.raises(ConfigError, match=match):
        TypicalSectionParams().with_updates(**change)


def test_from_sets_applies_values():
    p = TypicalSectionParams.from_sets(["mu=30", "sigma = 0.5"])
    assert (p.mu, p.sigma, p.a) == (30.0, 0.5, -0.2)


def test_aero_forces_bad_input():
    m = TypicalSection()
    t = np.arange(0, 1, 0.1)
    with pytest.raises(DimensionError, match=r"\(K, N\)"):
        m.aero_forces(t, np.zeros((10, 3)), None, 1.0)
    with pytest.raises(DataError, match="uniformly spaced"):
        m.aero_forces(t ** 2, np.zeros((10, 2)), None, 1.0)
    with pytest.raises(ConfigError, match="positive"):
        m.aero_forces(t, np.zeros((10, 2)), None, 0.0)


def test_flap_driven_simulation_statespace_and_aero_forces_agree():
    """A smooth flap history: simulate(), the StateSpace (flap acceleration input) and
    aero_forces on the simulated motion tell the same story."""
    import control

    m = TypicalSection()
    ms = m.modal_structure()
    V = 1.7
    t = np.arange(0.0, 50.0, 0.01)
    w = 0.5
    env = 1 - np.exp(-((t / 5.0) ** 2))
    # v = 0.02 env sin(w t), with exact derivatives
    s, c = np.sin(w * t), np.cos(w * t)
    e1 = np.exp(-((t / 5.0) ** 2)) * 2 * t / 25.0
    e2 = np.exp(-((t / 5.0) ** 2)) * (2 / 25.0 - 4 * t * t / 625.0)
    v = 0.02 * env * s
    vd = 0.02 * (e1 * s + env * w * c)
    vdd = 0.02 * (e2 * s + 2 * e1 * w * c - env * w * w * s)
    sim = m.simulate(t, np.zeros(4), V, v=v)
    assert sim.success
    sys = m.statespace(V)
    resp = control.forced_response(sys, timepts=t, inputs=np.vstack([vdd, np.zeros((2, t.size))]))
    # forced_response holds the input piecewise linear: O(dt^2) error, 4e-5 relative here
    # (measured: 1.6e-4, 3.9e-5, 9.8e-6 for dt = 0.02, 0.01, 0.005)
    assert_allclose(resp.outputs[:2].T, sim.u, atol=1e-4 * np.max(np.abs(sim.u)))
    y = m.aero_forces(t, sim.u, v, V, udot=sim.udot, uddot=sim.uddot, vdot=vd, vddot=vdd)
    lhs = sim.uddot + ms.omega ** 2 * sim.u
    assert_allclose(ms.alpha * V * V * y, lhs, atol=1e-6 * np.max(np.abs(lhs)))
