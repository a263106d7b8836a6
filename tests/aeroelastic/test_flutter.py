"""Flutter / divergence search and eigenvector-continuity tracking."""

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import AeroelasticSystem, find_flutter, track_eigenvalues
from casflutter.structure import ModalStructure
from casflutter import truth
from casflutter.errors import ConfigError

from ._cases import binary_system, spectral_abscissa_bisection


@pytest.mark.parametrize("dynamic", [False, True])
def test_flutter_speed_matches_independent_bisection(dynamic):
    sysae = binary_system(dynamic=dynamic)
    res = find_flutter(sysae, (0.0, 3.0), n_grid=61)
    assert res.status == "flutter" and res.found
    assert not res.unstable_at_start
    lo = res.flutter.bracket[0] - 0.2  # a stable point below, found independently of the tracker
    Vf_ref = spectral_abscissa_bisection(sysae.state_matrix, max(lo, 0.0), 3.0)
    assert_allclose(res.Vf, Vf_ref, rtol=1e-8)
    lam = np.linalg.eigvals(sysae.state_matrix(res.Vf))
    k = np.argmin(np.abs(lam - res.flutter.eigenvalue))
    assert abs(lam[k].real) < 1e-8 * abs(lam[k])
    assert_allclose(res.omega_f, abs(lam[k].imag), rtol=1e-8)
    assert_allclose(res.frequency_hz, res.omega_f / (2 * np.pi), rtol=1e-14)
    assert res.flutter.converged and res.flutter.slope > 0


def test_binary_flutter_matches_routh_hurwitz():
    """Static two-mode case: the quartic's Hurwitz determinant Δ3 vanishes at Vf."""
    from scipy.optimize import brentq
    sysae = binary_system(dynamic=False)

    def delta3(V):
        a = np.poly(sysae.state_matrix(V))  # monic a0 s^4 + a1 s^3 + ... + a4
        return a[1] * a[2] * a[3] - a[1] ** 2 * a[4] - a[3] ** 2

    res = find_flutter(sysae, (0.0, 3.0), n_grid=31)
    Vrh = brentq(delta3, res.flutter.bracket[0], res.flutter.bracket[1], xtol=1e-14, rtol=1e-14)
    assert_allclose(res.Vf, Vrh, rtol=1e-8)


def _analytic_blocks(V):
    """Hump mode a(V) = −(V−1)(V−2) at ω = 7 and a real eigenvalue V − 2.5."""
    a = -(V - 1.0) * (V - 2.0)
    A = np.zeros((5, 5))
    A[:2, :2] = [[a, 7.0], [-7.0, a]]
    A[2, 2] = V - 2.5
    A[3:, 3:] = [[-0.5, 3.0], [-3.0, -0.5]]
    T = np.array([[1, 2, 0, 0, 1], [0, 1, 1, 0, 0], [1, 0, 1, 1, 0], [0, 0, 0, 1, 2], [1, 0, 0, 0, 1.0]])
    return T @ A @ np.linalg.inv(T)  # hide the block structure


def test_every_crossing_reported_on_a_generic_callable():
    res = find_flutter(_analytic_blocks, (0.0, 3.0), n_grid=41)
    kinds = [(c.kind, c.direction) for c in res.crossings]
    assert kinds == [("flutter", "destabilizing"), ("flutter", "stabilizing"),
                     ("divergence", "destabilizing")]
    assert_allclose([c.V for c in res.crossings], [1.0, 2.0, 2.5], rtol=1e-10)
    assert_allclose(res.crossings[0].omega, 7.0, rtol=1e-10)
    assert res.crossings[2].omega == 0.0
    assert res.Vf == pytest.approx(1.0, rel=1e-10)
    assert res.divergence.V == pytest.approx(2.5, rel=1e-10)
    assert (res.origin == -1).all()  # no structural information given


def test_static_divergence_single_mode_analytic():
    """ü + 2ζωu̇ + (ω² − αV²d) u = 0 diverges at V = ω/√(αd)."""
    w, z, alpha, d = 4.0, 0.05, 2.0, 3.0
    sysae = AeroelasticSystem.from_parts(control.ss([], [], [], [[d]]), ModalStructure([w], [z], alpha=alpha))
    res = find_flutter(sysae, (0.0, 3.0), n_grid=31)
    assert res.status == "divergence" and res.Vf is None
    assert res.divergence.kind == "divergence"
    assert_allclose(res.divergence.V, w / np.sqrt(alpha * d), rtol=1e-8)
    assert res.divergence.origin_mode == 0


def test_no_crossing_is_reported_as_such():
    sysae = binary_system()
    res = find_flutter(sysae, (0.0, 1.0), n_grid=21)
    assert res.status == "no_crossing"
    assert res.Vf is None and res.omega_f is None and res.flutter is None and not res.found
    assert res.crossings == ()
    assert "no flutter" in res.message


def test_unstable_at_start_is_flagged():
    s = ModalStructure([3.0], [0.05])
    with pytest.warns(RuntimeWarning):
        sysae = AeroelasticSystem.from_parts(control.ss([[0.2]], [[1.0]], [[1.0]], [[0.0]]), s)
    with pytest.warns(RuntimeWarning, match="unstable already"):
        res = find_flutter(sysae, (0.0, 1.0), n_grid=11)
    assert res.unstable_at_start and res.spectral_abscissa_start > 0


def test_tracking_follows_eigenvectors_through_frequency_crossing():
    """Uncoupled modes whose frequencies cross: sorting would swap them, tracking must not."""
    s = ModalStructure([5.0, 8.0], [0.01, 0.01], alpha=1.0)
    sysae = AeroelasticSystem.from_parts(control.ss([], [], [], np.diag([-30.0, 30.0])), s)
    V = np.linspace(0.0, 1.3, 27)  # ω1² + 30 V² and ω2² − 30 V² cross at V² = 39/60
    tr = track_eigenvalues(sysae, V)
    w1 = np.sqrt(25.0 + 30.0 * tr.V ** 2)
    for b in range(4):
        E = np.abs(tr.eigenvectors[:, :, b]) ** 2
        mode0 = E[:, :2].sum(axis=1) > 0.5
        assert mode0.all() or (~mode0).all()  # each branch stays in one mode
    up = tr.upper_branches()
    assert up.size == 2
    b0 = next(b for b in up if np.abs(tr.eigenvectors[0, :2, b]).sum() > 0.5)
    wd = np.sqrt(w1 ** 2 - (0.01 * 5.0) ** 2)
    assert_allclose(tr.frequency[:, b0], wd, rtol=1e-10)
    assert_allclose(tr.damping_ratio[:, b0], 0.05 / np.sqrt(25.0 + 30.0 * tr.V ** 2) * 1.0, rtol=1e-8)
    res = find_flutter(sysae, V_grid=V)
    assert_allclose(np.sort(res.origin[up]), [0, 1])


def test_origin_mode_of_binary_flutter_by_participation_and_frequency_agree():
    sysae = binary_system(dynamic=True)
    res_p = find_flutter(sysae, (0.0, 3.0), n_grid=31)
    res_w = find_flutter(sysae.state_matrix, (0.0, 3.0), n_grid=31, omega=sysae.structure.omega)
    assert res_p.flutter_mode in (0, 1)
    assert res_p.flutter_mode == res_w.flutter_mode
    up = res_p.tracking.upper_branches()  # two aerodynamic lags (real) and two structural pairs
    assert sorted(res_p.origin[up]) == [-1, -1, 0, 1]
    assert_allclose(res_p.Vf, res_w.Vf, rtol=1e-10)


def test_bad_ranges():
    with pytest.raises(ConfigError):
        find_flutter(_analytic_blocks, (2.0, 1.0))
    with pytest.raises(ConfigError):
        track_eigenvalues(_analytic_blocks, [0.0, 0.0, 1.0])


def test_truth_typical_section_hp1_published_values():
    """Hodges & Pierce HP-1 typical section (truth simulator's own state_matrix, Jones
    aerodynamics): published V_F = 2.170, Ω_F/ω_θ = 0.644 (rtol 0.005) and the analytic
    divergence speed √(μ r²/(1 + 2a)) = √8."""
    m = truth.load_problem("typical_section")
    ref = truth.problem_definition("typical_section")["reference"]
    N = m.n_modes
    res = find_flutter(m, (0.05, 3.2), n_grid=64, mode_states=[[i, N + i] for i in range(N)],
                       omega=m.modal_structure().omega)
    assert res.status == "flutter"
    assert_allclose(res.Vf, ref["jones"]["flutter_speed"], rtol=ref["jones"]["rtol"])
    assert_allclose(res.omega_f, ref["jones"]["flutter_frequency_ratio"], rtol=ref["jones"]["rtol"])
    assert_allclose(res.divergence.V, np.sqrt(8.0), rtol=1e-8)
    by_freq = find_flutter(m.state_matrix, (0.05, 3.2), n_grid=64, omega=m.modal_structure().omega)
    assert res.flutter_mode == by_freq.flutter_mode == 1  # the pitch mode (nearest-frequency check)
    Vb = spectral_abscissa_bisection(m.state_matrix, 0.05, 2.5)
    assert_allclose(res.Vf, Vb, rtol=1e-8)


def test_truth_goland_wing_tracking_agrees_with_bisection():
    """30-state Goland wing (7 modes, Jones lags): tracked Vf equals the independent
    spectral-abscissa bisection to 1e-8; the critical branch comes from the first torsion mode."""
    m = truth.load_problem("goland")
    ms = m.modal_structure()
    N = m.n_modes
    res = find_flutter(m, (0.05, 6.0), n_grid=120, mode_states=[[i, N + i] for i in range(N)],
                       omega=ms.omega)
    assert res.status == "flutter" and res.flutter.converged
    Vb = spectral_abscissa_bisection(m.state_matrix, 0.05, res.flutter.bracket[1])
    assert_allclose(res.Vf, Vb, rtol=1e-8)
    assert ms.mode_names[res.flutter_mode] == "torsion 1"
    assert [c.V for c in res.crossings] == sorted(c.V for c in res.crossings)


def test_adaptive_refinement_keeps_branch_identity_on_a_coarse_grid():
    """Five grid points across a frequency crossing: refinement inserts points where the
    eigenvector match is poor, and branches keep their modes."""
    s = ModalStructure([5.0, 8.0], [0.01, 0.01], alpha=1.0, Hs=None)
    A0 = AeroelasticSystem.from_parts(control.ss([], [], [], np.diag([-30.0, 30.0])), s).state_matrix
    rng = np.random.default_rng(5)
    T = np.eye(4) + 0.3 * rng.standard_normal((4, 4))  # dense coordinates
    fn = lambda V: T @ A0(V) @ np.linalg.inv(T)  # noqa: E731
    tr = track_eigenvalues(fn, np.linspace(0.0, 1.3, 5), min_score=0.999)
    assert tr.n_refined > 0 and tr.V.size > 5 and tr.n_unresolved == 0
    assert np.all(tr.scores >= 0.999)
    # each branch's eigenvalue stays on one analytic mode: ω1² = 25 + 30V², ω2² = 64 − 30V²
    for b in range(4):
        lam = tr.eigenvalues[:, b]
        k2 = (lam * lam.conj()).real  # |λ|² = ω_eff² for a viscous mode
        on1 = np.allclose(k2, 25 + 30 * tr.V ** 2, rtol=1e-9)
        on2 = np.allclose(k2, 64 - 30 * tr.V ** 2, rtol=1e-9)
        assert on1 != on2


def test_truth_supplies_its_own_mode_states_and_frequencies():
    """A truth passed as it is: the origin modes come from its own state layout and
    frequencies, the same as when they are given explicitly."""
    T = truth.TypicalSection()
    res = find_flutter(T, (0.5, 3.0), n_grid=61)
    assert T.modal_structure().mode_names[res.flutter_mode] == "pitch"
    N = T.n_modes
    ref = find_flutter(T.state_matrix, (0.5, 3.0), n_grid=61,
                       mode_states=[np.array([i, N + i]) for i in range(N)],
                       omega=T.modal_structure().omega)
    assert res.Vf == ref.Vf and np.array_equal(res.origin, ref.origin)
