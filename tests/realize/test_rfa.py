"""Rational-function approximations of Q(ik): exact recovery of rational data (Jones' lags,
a synthetic minimum-state Q), the fit error per element against the exact Theodorsen Q,
more lag roots never fitting worse, and the Goland flutter through RFA -> ΣAE(U) against the
published values and against p-k on the same Q(ik)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import (AeroelasticSystem, RFASystem, build_lft, find_flutter,
                                    pk_flutter)
from casflutter.data import GAFTable
from casflutter.errors import ConfigError, ConvergenceError, DataError, DimensionError
from casflutter.realize import RFASettings, fit_minimum_state, fit_rfa, fit_roger
from casflutter.truth import JONES_B, GolandParams, GolandWing, problem_definition

REF = problem_definition("goland")["reference"]["flutter"]
#: reduced frequencies of the Goland tables: dense near k = 0 (Theodorsen's branch point)
K_GRID = np.concatenate([np.linspace(0.0, 0.2, 9), np.linspace(0.25, 2.0, 36)])


def _structure(wing, sensor="displacement"):
    ms = wing.modal_structure()
    return ms.with_sensors(kind=sensor)


@pytest.fixture(scope="module")
def wing():
    return GolandWing()


@pytest.fixture(scope="module")
def table(wing):
    return GAFTable.from_truth(wing, K_GRID)


@pytest.fixture(scope="module")
def roger(table):
    """Roger fits with 2..4 lag roots on the exact-Theodorsen Goland table."""
    return {n: fit_roger(table, n) for n in (2, 3, 4)}


@pytest.fixture(scope="module")
def small():
    """Goland with two bending and one torsion mode (N = 3, flap: M = 4), a coarser table."""
    w = GolandWing(GolandParams(n_bending=2, n_torsion=1))
    k = np.concatenate([np.linspace(0.0, 0.2, 5), np.linspace(0.3, 1.5, 13)])
    return w, GAFTable.from_truth(w, k)


# ---- exact recovery --------------------------------------------------------------------------
def test_roger_recovers_jones_lags_and_the_truth_flutter(wing):
    """Strip theory with Jones' C(k) is exactly a 2-lag Roger form with the lag roots 0.0455
    and 0.3: the fit finds them, and its ΣAE(U) is the truth's state space (same flutter)."""
    t = GAFTable.from_truth(wing, K_GRID, theodorsen="jones")
    r = fit_roger(t, 2)
    assert_allclose(r.gamma, JONES_B, rtol=1e-7)
    assert r.fit_error < 1e-10 and r.error_rel.max() < 1e-10
    sys = RFASystem(r, _structure(wing), t.U_ref)
    fr = find_flutter(sys, (60.0, 200.0), n_grid=57)
    ft = find_flutter(wing.state_matrix, (60.0 / t.U_ref, 200.0 / t.U_ref), n_grid=57)
    assert_allclose([fr.Vf, fr.omega_f], [ft.Vf * t.U_ref, ft.omega_f], rtol=1e-9)


def test_minimum_state_recovers_a_rational_q():
    """Q(p) = A0 + A1 p + A2 p^2 + D (pI - R)^-1 E p with known roots: recovered exactly."""
    rng = np.random.default_rng(7)
    N, M, gam = 3, 4, np.array([0.08, 0.4, 1.2])
    A = rng.standard_normal((3, N, M))
    D, E = rng.standard_normal((N, 3)), rng.standard_normal((3, M))
    k = np.linspace(0.0, 2.0, 30)
    p = 1j * k[:, None, None]
    Q = A[0] + p * A[1] + p * p * A[2] + np.einsum("ij,nj,jl->nil", D,
                                                   1j * k[:, None] / (1j * k[:, None] + gam), E)
    t = GAFTable(k, Q, 1.0)
    r = fit_minimum_state(t, 3)
    assert_allclose(r.gamma, gam, rtol=1e-6)
    assert r.fit_error < 1e-8
    kv = np.linspace(0.05, 1.95, 11)                      # off the fitted grid
    pv = 1j * kv[:, None, None]
    Qv = A[0] + pv * A[1] + pv * pv * A[2] + np.einsum(
        "ij,nj,jl->nil", D, 1j * kv[:, None] / (1j * kv[:, None] + gam), E)
    assert_allclose(r.evaluate(kv), Qv, rtol=0, atol=1e-7 * np.abs(Qv).max())
    assert r.n_lag_states == 3 and r.R.shape == (3,) and r.D.shape == (N, 3)


# ---- fit error on the exact Theodorsen Q ----------------------------------------------------
def test_fit_error_per_element_against_the_exact_q(wing, table, roger):
    """Per-element errors are reported for every (mode, input) and hold off the fitted grid:
    the exact Q at the midpoints of the table is matched to the level of the grid."""
    r = roger[4]
    assert r.error_rel.shape == r.error_max_rel.shape == (7, 8)
    assert r.error_rel.max() < 1e-3 and r.error_max_rel.max() < 3e-3
    assert_allclose(r.error_rms, np.sqrt(np.mean(np.abs(r.evaluate(table.k) - table.Q) ** 2,
                                                 axis=0)), rtol=1e-10)
    # off the grid: the midpoints, except the first interval (0, 0.025), where C(k)'s
    # k log k branch point at k = 0 is beyond any rational function
    mid = 0.5 * (K_GRID[2:] + K_GRID[1:-1])
    exact = wing.generalized_aero_forces(mid)
    scale = r.error_rms / np.maximum(r.error_rel, 1e-300)          # the per-element scales
    assert np.max(np.abs(r.evaluate(mid) - exact) / scale) < 1.5 * r.error_max_rel.max()
    assert "worst element" in r.summary()


def test_more_lag_roots_do_not_fit_worse(roger, small):
    errs = [roger[n].fit_error for n in (2, 3, 4)]
    worst = [roger[n].error_rel.max() for n in (2, 3, 4)]
    assert all(b <= a for a, b in zip(errs, errs[1:])), errs
    assert all(b <= a for a, b in zip(worst, worst[1:])), worst
    _, t = small
    ms = [fit_minimum_state(t, n).fit_error for n in (2, 3, 4, 5)]
    assert all(b <= a for a, b in zip(ms, ms[1:])), ms


# ---- Goland flutter -----------------------------------------------------------------------------
def test_goland_flutter_via_rfa_within_one_percent_and_agrees_with_pk(wing, table, roger):
    """Exact-Theodorsen Q(ik) -> Roger RFA (4 lags) -> ΣAE(U) -> flutter: within 1 % of the
    published 137.2 m/s and 70.7 rad/s, and within 5e-4 of p-k on the same Q(ik)."""
    sys = RFASystem(roger[4], _structure(wing), table.U_ref)
    fr = find_flutter(sys, (60.0, 200.0), n_grid=57)
    assert fr.status == "flutter" and fr.flutter.converged
    assert_allclose(fr.Vf, REF["airspeed"], rtol=0.01)
    assert_allclose(fr.omega_f, REF["frequency"], rtol=0.01)
    pk = pk_flutter(table, _structure(wing), np.linspace(100.0, 170.0, 15), modes=(0, 1))
    assert pk.found and pk.flutter_mode == fr.flutter_mode
    assert_allclose([fr.Vf, fr.omega_f], [pk.flutter_speed, pk.flutter_omega], rtol=5e-4)


@pytest.mark.slow
def test_goland_flutter_via_minimum_state(wing, table):
    """Minimum-state RFA with 8 lag states: flutter within 1 % of the published values and
    within 1e-3 of p-k."""
    r = fit_minimum_state(table, 8)
    fr = find_flutter(RFASystem(r, _structure(wing), table.U_ref), (60.0, 200.0), n_grid=57)
    assert_allclose(fr.Vf, REF["airspeed"], rtol=0.01)
    assert_allclose(fr.omega_f, REF["frequency"], rtol=0.01)
    pk = pk_flutter(table, _structure(wing), np.linspace(100.0, 170.0, 15), modes=(0, 1))
    assert_allclose([fr.Vf, fr.omega_f], [pk.flutter_speed, pk.flutter_omega], rtol=1e-3)


# ---- the state space ---------------------------------------------------------------------------
@pytest.mark.parametrize("sensor", ["displacement", "acceleration"])
def test_statespace_frequency_response_is_the_modal_equation(wing, table, roger, sensor):
    """(sI - A)^-1 B of statespace(U) at s = i w satisfies eq. (6) with the RFA's Q(ik):
    Z(w) u = alpha w and Z(w) u = alpha V^2 Q_flap v, Z = -w^2 + 2 i zeta w omega + omega^2
    - alpha V^2 Q_modes; the sensors read Hs u (or -w^2 Hs u)."""
    st = _structure(wing, sensor)
    ms = wing.modal_structure()
    sys = RFASystem(roger[3], st, table.U_ref)
    U, N = 125.0, st.n_modes
    ss = sys.statespace(U)
    A, B, C, D = (np.asarray(x) for x in (ss.A, ss.B, ss.C, ss.D))
    q = st.alpha * (U / table.U_ref) ** 2
    for om in (40.0, 90.0):
        Q = roger[3].evaluate(om * table.b / U)
        Z = -om ** 2 * np.eye(N) + np.diag(st.omega ** 2) - q * Q[:, :N]
        X = np.linalg.solve(1j * om * np.eye(A.shape[0]) - A, B)
        G = C @ X + D
        assert_allclose(Z @ G[:N, 1:], st.alpha * np.eye(N), atol=1e-9 * st.alpha)
        v = 1.0 / (-om ** 2)                                # flap angle per unit v''
        assert_allclose(Z @ G[:N, 0], q * Q[:, N] * v, rtol=1e-9,
                        atol=1e-12 * np.abs(q * Q[:, N] * v).max())
        factor = 1.0 if sensor == "displacement" else -om ** 2
        assert_allclose(G[N:], factor * ms.Hs @ G[:N], rtol=1e-9,
                        atol=1e-12 * np.abs(G[N:]).max())


# ---- the bridge to eq. 5-15 ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def proper(small):
    """A proper RFA (poly_order=0, the band k <= 1 where the flutter lies)."""
    w, t = small
    r = fit_rfa(t, RFASettings(n_lags=4, poly_order=0, k_max=1.0, lag_bounds=(0.002, 10.0),
                               min_separation=0.3))
    return w, t, r


def test_frozen_sigma_f_is_exact_at_the_freeze(proper):
    """from_parts(frozen_sigma_f(U_f)) at V_f = U_f / U_ref has the eigenvalues of the RFA
    system at U_f (plus Roger's flap-only lags at -gamma U_f / b), the same flutter point, and
    build_lft's nominal plant is that system."""
    w, t, r = proper
    st = _structure(w)
    sys = RFASystem(r, st, t.U_ref)
    fr = find_flutter(sys, (60.0, 200.0), n_grid=57)
    Uf = fr.Vf
    ae = AeroelasticSystem.from_parts(sys.frozen_sigma_f(Uf), st)
    Vf = sys.speed_index(Uf)
    lam_ae = np.linalg.eigvals(ae.state_matrix(Vf))
    lam_rfa = np.linalg.eigvals(sys.state_matrix(Uf))
    extra = -r.gamma * Uf / r.b
    expected = np.concatenate([lam_rfa, extra])
    assert lam_ae.size == expected.size
    for lam in expected:
        assert np.min(np.abs(lam_ae - lam)) < 1e-8 * max(abs(lam), 1.0)
    fa = find_flutter(ae, (0.8 * Vf, 1.2 * Vf), n_grid=41)
    assert_allclose([sys.airspeed(fa.Vf), fa.omega_f], [Uf, fr.omega_f], rtol=1e-8)
    lft = build_lft(ae, Vf)
    assert_allclose(np.sort_complex(np.linalg.eigvals(lft.A)), np.sort_complex(lam_ae),
                    rtol=1e-9, atol=1e-9)


def test_frozen_sigma_f_is_only_approximate_away_from_the_freeze(proper):
    """Frozen at 0.8 U_f (the paper's V^2 scaling with the lag rates of the freeze), the
    predicted flutter speed moves: the bridge is exact only at the speed it was frozen."""
    w, t, r = proper
    st = _structure(w)
    sys = RFASystem(r, st, t.U_ref)
    Uf = find_flutter(sys, (60.0, 200.0), n_grid=57).Vf
    ae = AeroelasticSystem.from_parts(sys.frozen_sigma_f(0.8 * Uf), st)
    fa = find_flutter(ae, (60.0 / t.U_ref, 200.0 / t.U_ref), n_grid=57)
    assert abs(sys.airspeed(fa.Vf) / Uf - 1.0) > 1e-3


def test_frozen_sigma_f_needs_a_proper_rfa(wing, table, roger):
    sys = RFASystem(roger[2], _structure(wing), table.U_ref)
    with pytest.raises(ConfigError, match=r"poly_order = 2.*refit with poly_order=0"):
        sys.frozen_sigma_f(130.0)


# ---- settings and errors ------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, pattern", [
    (dict(method="karpel"), r"method='karpel'.*\('roger', 'minimum_state'\)"),
    (dict(n_lags=0), r"n_lags=0 must be an integer in 1..40"),
    (dict(poly_order=3), r"poly_order=3 must be 0, 1 or 2"),
    (dict(lag_bounds=(1.0, 0.5)), r"0 < low < high"),
    (dict(n_lags=2, initial_lags=(0.1,)), r"n_lags = 2 positive numbers"),
    (dict(weighting="abs"), r"weighting='abs'"),
    (dict(min_separation=1.5), r"min_separation=1.5 must lie in \[0, 1\)"),
])
def test_bad_settings(kwargs, pattern):
    with pytest.raises(ConfigError, match=pattern):
        RFASettings(**kwargs)


def test_bad_inputs(small, wing, table, roger):
    w, t = small
    with pytest.raises(DataError, match=r"too few to fit"):
        fit_roger(GAFTable(t.k[:3], t.Q[:3], t.b), 3)
    with pytest.raises(ConfigError, match=r"must be a casflutter.data.GAFTable"):
        fit_rfa(t.Q)
    with pytest.raises(DimensionError, match=r"RFA has 7 modes.*structure has 3"):
        RFASystem(roger[2], _structure(w), table.U_ref)
    with pytest.raises(ConfigError, match=r"U_ref = -1"):
        RFASystem(roger[2], _structure(wing), -1.0)
    with pytest.raises(ConfigError, match=r"separated by a factor.*do not fit"):
        fit_roger(t, 4, lag_bounds=(0.1, 0.2), min_separation=0.5)


def test_non_convergence_is_an_error(small):
    _, t = small
    with pytest.raises(ConvergenceError, match=r"did not converge.*Maximum_Iterations") as exc:
        fit_roger(t, 3, max_iter=2)
    assert exc.value.result is not None and not exc.value.result.success
