"""Goland wing truth vs the published flutter point, in-vacuo frequencies, exact beam theory,
and an independent strip-by-strip Theodorsen/Jones evaluation written here."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq, fsolve
from scipy.special import hankel2

from casflutter.errors import ConfigError
from casflutter.truth import GolandParams, GolandWing, load_problem, theodorsen_T
from casflutter.aeroelastic import find_flutter

ROOT = Path(__file__).resolve().parents[2]
with open(ROOT / "problems" / "goland" / "problem.toml", "rb") as _fh:
    DEF = tomllib.load(_fh)
REF = DEF["reference"]


def C_theodorsen(k):
    H1, H0 = hankel2(1, k), hankel2(0, k)
    return H1 / (H1 + 1j * H0)


def C_jones(k):
    ik = 1j * k
    return 1 - 0.165 * ik / (ik + 0.0455) - 0.335 * ik / (ik + 0.3)


# ---- an independent strip-theory model -------------------------------------------------
class Strips:
    """Textbook clamped-free / torsion shapes on Gauss strips; Theodorsen's strip loads."""

    def __init__(self, p: GolandParams, nq: int = 300):
        self.p = p
        L = p.semispan
        xg, wg = np.polynomial.legendre.leggauss(nq)
        y0 = p.flap_span_start * L
        # two panels so the flap edge is a panel edge
        self.y = np.concatenate([0.5 * y0 * (xg + 1), y0 + 0.5 * (L - y0) * (xg + 1)])
        self.w = np.concatenate([0.5 * y0 * wg, 0.5 * (L - y0) * wg])
        self.chi = (self.y > y0).astype(float)
        roots = [brentq(lambda x: np.cos(x) * np.cosh(x) + 1, lo, lo + 3)
                 for lo in (1.0, 4.0, 7.0, 10.0)][:p.n_bending]
        phi = []
        for bl in roots:
            x = bl * self.y / L
            s = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
            f = np.cosh(x) - np.cos(x) - s * (np.sinh(x) - np.sin(x))
            phi.append(f / np.sqrt(np.sum(self.w * f * f) / L))
        self.roots = np.array(roots)
        self.phi = np.array(phi)
        gam = (2 * np.arange(1, p.n_torsion + 1) - 1) * np.pi / (2 * L)
        self.gam = gam
        self.th = np.sin(np.outer(gam, self.y))

    def structure(self):
        p = self.p
        w = self.w
        Phh = (self.phi * w) @ self.phi.T
        Pht = (self.phi * w) @ self.th.T
        Ptt = (self.th * w) @ self.th.T
        S = p.mass * (p.cg_chord - p.ea_chord) * p.chord
        M = np.block([[p.mass * Phh, S * Pht], [S * Pht.T, p.inertia * Ptt]])
        K = np.diag(np.concatenate([p.EI * (self.roots / p.semispan) ** 4 * p.semispan,
                                    p.GJ * self.gam ** 2 * p.semispan / 2]))
        return M, K

    def forces(self, U, w, ahat, bhat, beta, C):
        """Generalised forces [-int L phi, int M vartheta] for harmonic motion e^{i w t}."""
        p = self.p
        b, a, c, rho = p.chord / 2, 2 * p.ea_chord - 1, 1 - 2 * p.flap_chord, p.rho
        T = theodorsen_T(c)
        s = 1j * w
        h = ahat @ self.phi
        th = bhat @ self.th
        be = beta * self.chi
        Q = s * h + U * th + b * (0.5 - a) * s * th + U / np.pi * T["T10"] * be \
            + b / (2 * np.pi) * T["T11"] * s * be
        Ck = C(w * b / U)
        L = rho * b * b * (np.pi * s * s * h + np.pi * U * s * th - np.pi * b * a * s * s * th
                           - U * T["T4"] * s * be - b * T["T1"] * s * s * be) \
            + 2 * np.pi * rho * U * b * Ck * Q
        M = -rho * b * b * (np.pi * b * (0.5 - a) * U * s * th
                            + np.pi * b * b * (0.125 + a * a) * s * s * th
                            + (T["T4"] + T["T10"]) * U * U * be
                            + (T["T1"] - T["T8"] - (c - a) * T["T4"] + 0.5 * T["T11"])
                            * U * b * s * be
                            - (T["T7"] + (c - a) * T["T1"]) * b * b * s * s * be
                            - np.pi * a * b * s * s * h) \
            + 2 * np.pi * rho * U * b * b * (a + 0.5) * Ck * Q
        return np.concatenate([-(self.phi * self.w) @ L, (self.th * self.w) @ M])

    def flutter(self, C, U0, w0):
        M, K = self.structure()
        nb, nt = self.p.n_bending, self.p.n_torsion
        n = nb + nt

        def F(U, w):
            cols = []
            for j in range(n):
                e = np.zeros(n)
                e[j] = 1.0
                cols.append(self.forces(U, w, e[:nb], e[nb:], 0.0, C))
            return np.array(cols).T

        scale = np.linalg.det(K)

        def res(z):
            d = np.linalg.det(-z[1] ** 2 * M + K - F(z[0], z[1])) / scale
            return [d.real, d.imag]

        U, w = fsolve(res, [U0, w0], xtol=1e-12)
        assert np.max(np.abs(res([U, w]))) < 1e-9
        return U, w


@pytest.fixture(scope="module")
def wing():
    return GolandWing()


@pytest.fixture(scope="module")
def flutter_jones(wing):
    fp = find_flutter(wing, (1.0, 2.5), n_grid=30)
    assert fp.found
    return wing.airspeed(fp.Vf), fp.omega_f


# ---- published values ----------------------------------------------------------------
def test_problem_definition_matches_defaults():
    p = GolandParams()
    for name, value in DEF["parameters"].items():
        assert getattr(p, name) == pytest.approx(value, rel=1e-12), name
    assert p.b == pytest.approx(0.9144) and p.a == pytest.approx(-0.34)


def test_flutter_speed_jones_matches_published(flutter_jones):
    """Strip theory with Jones' Wagner lags: U_F = 137.2 m/s within 1.5%."""
    ref = REF["flutter"]
    assert_allclose(flutter_jones[0], ref["airspeed"], rtol=ref["rtol"])


@pytest.mark.xfail(strict=True, reason="Jones' two-lag C(k) puts the Goland flutter frequency "
                   "at 69.35 rad/s, 1.9% below the published 70.7 (exact Theodorsen on the "
                   "same model gives 70.02, see test_flutter_theodorsen_matches_published)")
def test_flutter_frequency_jones_matches_published(flutter_jones):
    ref = REF["flutter"]
    assert_allclose(flutter_jones[1], ref["frequency"], rtol=ref["rtol"])


def test_flutter_theodorsen_matches_published():
    """The independent strip model with the exact Theodorsen function: 137.2 m/s, 70.7 rad/s
    within 1.5%."""
    U, w = Strips(GolandParams()).flutter(C_theodorsen, 137.0, 70.0)
    ref = REF["flutter"]
    assert_allclose(U, ref["airspeed"], rtol=ref["rtol"])
    assert_allclose(w, ref["frequency"], rtol=ref["rtol"])


def test_state_space_flutter_equals_independent_strip_determinant(flutter_jones):
    """The eigenvalue crossing of state_matrix equals the independent strip-theory flutter
    determinant with Jones' C(k)."""
    U, w = Strips(GolandParams()).flutter(C_jones, 137.0, 69.0)
    assert_allclose(flutter_jones, [U, w], rtol=1e-6)


def test_flutter_at_rho_1_02():
    """The density pin: rho = 1.02 gives about 147 m/s (1.5%)."""
    m = GolandWing(GolandParams(rho=1.02))
    fp = find_flutter(m, (1.0, 2.5), n_grid=30)
    ref = REF["flutter_rho_1_02"]
    assert_allclose(m.airspeed(fp.Vf), ref["airspeed"], rtol=ref["rtol"])


def test_in_vacuo_frequencies(wing):
    ref = REF["in_vacuo"]
    assert_allclose(wing.modal_structure().omega[:4], ref["frequencies"], rtol=ref["rtol"])


def test_uncoupled_frequencies_exact_beam_theory():
    """With the centre of mass on the elastic axis the assumed modes are exact:
    beta_r^2 sqrt(EI/m) and (2s-1) pi/(2L) sqrt(GJ/I)."""
    p = GolandParams(cg_chord=0.33)
    ms = GolandWing(p).modal_structure()
    L = p.semispan
    bl = np.array([1.8751040687119611, 4.6940911329741746, 7.8547574382376126,
                   10.995540734875467])
    wb = (bl / L) ** 2 * np.sqrt(p.EI / p.mass)
    wt = (2 * np.arange(1, 4) - 1) * np.pi / (2 * L) * np.sqrt(p.GJ / p.inertia)
    assert_allclose(ms.omega, np.sort(np.concatenate([wb, wt])), rtol=1e-9)
    assert sorted(ms.mode_names) == sorted([f"bending {i}" for i in range(1, 5)]
                                           + [f"torsion {i}" for i in range(1, 4)])


def test_modes_converged():
    """More assumed modes move the flutter speed by less than 0.05%."""
    f1 = find_flutter(GolandWing(), (1.0, 2.5), n_grid=30)
    f2 = find_flutter(GolandWing(GolandParams(n_bending=6, n_torsion=6)), (1.0, 2.5),
                      n_grid=30)
    assert_allclose(f2.Vf, f1.Vf, rtol=5e-4)
    assert_allclose(f2.omega_f, f1.omega_f, rtol=5e-4)


def test_speed_index_convention(wing):
    p = wing.params
    wref = np.pi / (2 * p.semispan) * np.sqrt(p.GJ / p.inertia)
    assert_allclose(wing.speed_index(137.2), 137.2 / (p.b * wref))
    assert_allclose(wing.airspeed(wing.speed_index(99.0)), 99.0)
    # alpha V^2 = rho U^2 / m
    V = wing.speed_index(120.0)
    assert_allclose(wing.modal_structure().alpha * V * V, p.rho * 120.0 ** 2 / p.mass)


# ---- aero_forces against the independent strips --------------------------------------
def test_aero_forces_harmonic_steady_state(wing):
    """Harmonic modal motion + flap: y equals Phi^T f / (rho U^2 L), f from the strips."""
    p = wing.params
    ms = wing.modal_structure()
    U, w = 100.0, 60.0
    V = wing.speed_index(U)
    rng = np.random.default_rng(3)
    uhat = (rng.standard_normal(7) + 1j * rng.standard_normal(7)) * 1e-2
    bhat = 0.01 + 0.02j
    dt = 1e-3
    t = np.arange(0.0, 8.0, dt)
    E = np.exp(1j * w * t)
    y = wing.aero_forces(t, np.real(np.outer(E, uhat)), np.real(bhat * E), V)
    xhat = ms.shapes @ uhat
    f = Strips(p).forces(U, w, xhat[:4], xhat[4:], bhat, C_jones)
    yhat = ms.shapes.T @ f / (p.rho * U * U * p.semispan)
    sl = slice(int(6.0 / dt), len(t) - 20)  # lag transients (rate 0.0455 U/b) decayed
    assert_allclose(y[sl], np.real(np.outer(E, yhat))[sl], atol=1e-6 * np.max(np.abs(yhat)))


def test_closed_loop_with_aero_forces_reproduces_simulation(wing):
    """simulate() then aero_forces on its motion: u'' + omega^2 u = alpha V^2 y."""
    ms = wing.modal_structure()
    V = wing.speed_index(130.0)
    t = np.arange(0.0, 0.5, 2e-4)
    x0 = np.zeros(14)
    x0[:3] = [0.01, 0.002, -0.001]
    sim = wing.simulate(t, x0, V)
    assert sim.success
    lhs = sim.uddot + ms.omega ** 2 * sim.u
    # exact derivatives from the simulation: everywhere
    y = wing.aero_forces(t, sim.u, None, V, udot=sim.udot, uddot=sim.uddot)
    assert_allclose(ms.alpha * V * V * y, lhs, atol=1e-7 * np.max(np.abs(lhs)))
    # spline derivatives: away from the record ends (the spline's end conditions)
    y = wing.aero_forces(t, sim.u, None, V)
    sl = slice(10, -10)
    assert_allclose(ms.alpha * V * V * y[sl], lhs[sl], atol=1e-6 * np.max(np.abs(lhs)))


def test_statespace_shapes(wing):
    sys = wing.statespace(wing.speed_index(100.0))
    assert sys.ninputs == 1 + 7 and sys.noutputs == 7 + 4
    assert sys.nstates == 14 + 2 * 8 + 2  # [u, u'] + 2 lags x (7 modes + flap) + [v, v']
    # the flap enters: a step in flap acceleration moves the tip
    assert np.linalg.norm(sys.B[:, 0]) > 0


# ---- bad input -----------------------------------------------------------------------
def test_unknown_set_name_lists_valid_names():
    with pytest.raises(ConfigError, match=r"unknown parameter 'span'.*valid names: semispan"):
        load_problem("goland", ["span=3"])
    m = load_problem("goland", ["rho=1.02", "n_bending=3"])
    assert m.params.rho == 1.02 and m.n_modes == 6
    with pytest.raises(ConfigError, match="integer"):
        load_problem("goland", ["n_bending=2.5"])
    with pytest.raises(ConfigError, match="positive definite"):
        GolandParams(inertia=0.5)
