"""LCO branches of the typical section (Hodges & Pierce HP-1, Jones' Wagner lags) with a
polynomial pitch spring: against a one-harmonic balance written out here (Theodorsen's
forces with Jones' C(k), the cubic spring replaced by its describing function), against
long time simulations, and a subcritical spring with a fold and hysteresis."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import fsolve

from casflutter.lco import LCOSettings, lco_branch
from casflutter.truth import TypicalSection, TypicalSectionParams

from ._helpers import measure

KAPPA = 3.0          # hardening cubic pitch spring: moment r^2 theta (1 + KAPPA theta^2)


def jones_C(k):
    ik = 1j * k
    return 1 - 0.165 * ik / (ik + 0.0455) - 0.335 * ik / (ik + 0.3)


def forces(p, V, w, xi, th):
    """[-L/(m b w_th^2), M/(m b^2 w_th^2)] for harmonic motion e^{i w tau} (Theodorsen)."""
    a, mu = p.a, p.mu
    s = 1j * w
    Q = s * xi + V * th + (0.5 - a) * s * th
    C = jones_C(w / V)
    L = (s * s * xi + V * s * th - a * s * s * th) / mu + 2 / mu * V * C * Q
    M = (a * s * s * xi - V * (0.5 - a) * s * th - (0.125 + a * a) * s * s * th) / mu \
        + 2 / mu * V * (a + 0.5) * C * Q
    return np.array([-L, M])


def harmonic_balance(p, Theta, V0, w0):
    """One-harmonic balance: theta = Theta cos(w tau), theta^3 -> (3/4) Theta^2 theta, so the
    pitch stiffness is r^2 (1 + 3/4 KAPPA Theta^2); the cycle is where the equivalent linear
    section has a root on the imaginary axis, det(-w^2 M + K(Theta) - F(V, w)) = 0."""
    xt = p.e - p.a
    M = np.array([[1.0, xt], [xt, p.r2]])
    K = np.diag([p.sigma ** 2, p.r2 * (1 + 0.75 * KAPPA * Theta ** 2)])

    def res(z):
        F = np.array([forces(p, z[0], z[1], 1.0, 0.0), forces(p, z[0], z[1], 0.0, 1.0)]).T
        d = np.linalg.det(-z[1] ** 2 * M + K - F)
        return [d.real, d.imag]

    V, w = fsolve(res, [V0, w0], xtol=1e-13)
    assert np.max(np.abs(res([V, w]))) < 1e-10
    return V, w


@pytest.fixture(scope="module")
def cubic():
    truth = TypicalSection(TypicalSectionParams(kappa2=KAPPA))
    return truth, lco_branch(truth, (1.5, 2.8))


def test_supercritical_hopf_at_the_published_flutter_speed(cubic):
    truth, br = cubic
    h = br.hopf
    assert h.V == pytest.approx(2.170, rel=5e-3)                  # README: Jones, V_F = 2.170
    assert 2 * np.pi * h.freq_hz == pytest.approx(0.644, rel=5e-3)
    assert h.kind == "supercritical" and h.lyapunov < 0
    assert h.branch_direction == 1 and h.kind_from_branch == "supercritical" and h.consistent
    # the first orbit's speed offset is the normal form's at its amplitude
    assert h.normal_form_agreement == pytest.approx(1.0, abs=0.01)
    assert br.completed and not br.folds
    assert all(p.stable for p in br.points)
    assert all(p.trivial_error < 1e-5 for p in br.points)
    assert set(br.outputs) == {"plunge", "pitch", "h/b", "theta"}
    assert br.unit_of("theta") == "rad"


def test_against_one_harmonic_balance(cubic):
    """Pitch amplitudes up to 0.3 rad: speed and frequency within 0.5 % of the one-harmonic
    balance, the gap growing like the neglected third harmonic (amplitude squared)."""
    _, br = cubic
    gaps = []
    for p in br.points:
        Th = p.amplitude["theta"]
        if Th > 0.3:
            break
        V, w = harmonic_balance(TypicalSectionParams(kappa2=KAPPA), Th, p.V,
                                2 * np.pi * p.freq_hz)
        assert V == pytest.approx(p.V, rel=5e-3)
        assert w == pytest.approx(2 * np.pi * p.freq_hz, rel=5e-3)
        gaps.append((Th, abs(V / p.V - 1)))
    gaps = np.array(gaps)
    assert gaps[-1, 0] > 0.25 and len(gaps) > 5
    small = gaps[gaps[:, 0] < 0.05]
    assert np.all(small[:, 1] < 2e-5)                             # agree at small amplitude


def test_against_time_simulation(cubic):
    """From a small release, the simulated LCO has the branch's amplitude and frequency
    (2 % target) at two speeds on the stable branch."""
    truth, br = cubic
    for target in (2.3, 2.6):
        p = min(br.points, key=lambda q: abs(q.V - target))
        t = np.arange(0.0, 900.0, 0.05)
        sim = truth.simulate(t, [0.0, 0.02, 0.0, 0.0], p.V)
        theta = sim.u @ truth.modal_structure().Hs[1]
        amp, freq = measure(t, theta)
        assert amp == pytest.approx(p.amplitude["theta"], rel=0.02)
        assert freq == pytest.approx(p.freq_hz, rel=0.02)
        assert amp == pytest.approx(p.amplitude["theta"], rel=2e-3)   # measured: ~1e-4
        assert freq == pytest.approx(p.freq_hz, rel=2e-3)


def test_subcritical_spring_has_a_fold_and_hysteresis():
    """A softening cubic with a hardening quintic: subcritical Hopf, the unstable branch
    turns at a fold where a multiplier passes 1, and between the fold and the Hopf point a
    simulation started just inside the unstable cycle decays while one started just outside
    goes to the stable cycle (its amplitude within 2 %)."""
    truth = TypicalSection(TypicalSectionParams(kappa2=-3.0, kappa4=10.0))
    br = lco_branch(truth, (1.5, 2.6))
    h = br.hopf
    assert h.kind == "subcritical" and h.lyapunov > 0 and h.consistent
    assert h.branch_direction == -1
    assert len(br.folds) == 1
    fold = br.folds[0]
    assert fold.located and abs(fold.max_multiplier - 1.0) < 1e-4
    assert fold.V < h.V
    i = fold.index
    assert not br.points[i].stable and br.points[i + 1].stable
    # an unstable cycle between fold and Hopf, and the stable one at the same speed
    pu = next(p for p in br.points[:i] if not p.stable and fold.V + 0.05 < p.V < h.V - 0.05)
    t = np.arange(0.0, 600.0, 0.05)
    rows = truth.modal_structure().Hs[1]
    inside = truth.simulate(t, 0.95 * pu.state, pu.V)
    outside = truth.simulate(t, 1.05 * pu.state, pu.V)
    th_in, th_out = inside.u @ rows, outside.u @ rows
    assert np.max(np.abs(th_in[-2000:])) < 0.2 * pu.amplitude["theta"]
    amp, freq = measure(t, th_out)
    Vs = [p.V for p in br.points[i + 1:]]
    stable_amp = np.interp(pu.V, Vs, [p.amplitude["theta"] for p in br.points[i + 1:]])
    stable_f = np.interp(pu.V, Vs, [p.freq_hz for p in br.points[i + 1:]])
    assert amp == pytest.approx(stable_amp, rel=0.02)
    assert freq == pytest.approx(stable_f, rel=0.02)


def test_acceleration_sensors_are_the_second_derivative(cubic):
    """Sensors read as accelerations: near the Hopf point the cycle is nearly harmonic, so
    their amplitude is (2 pi f)^2 times the displacement amplitude (1 %)."""
    truth, disp = cubic
    acc = lco_branch(truth, (1.5, 2.8), LCOSettings(sensor_kind="acceleration", max_points=4))
    p = acc.points[-1]
    q = min(disp.points, key=lambda z: abs(z.V - p.V))
    assert q.V == pytest.approx(p.V, rel=1e-9)
    w2 = (2 * np.pi * p.freq_hz) ** 2
    assert p.amplitude["theta"] == pytest.approx(w2 * q.amplitude["theta"], rel=0.01)
    assert acc.unit_of("theta") == "rad/(1/omega_theta)^2"
