"""Exact stability interval of A0 + δ A1 (bialternate-sum guardian map) against analytic
cases and a dense eigenvalue sweep; small-gain interval against its formula."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError, DimensionError
from casflutter.verify import (NotHurwitzError, bialternate_sum, small_gain_interval,
                               speed_interval, stability_interval)


def _abscissa(A):
    return np.max(np.linalg.eigvals(A).real)


def _random_family(seed, n):
    rng = np.random.default_rng(seed)
    A0 = rng.standard_normal((n, n))
    A0 -= (_abscissa(A0) + rng.uniform(0.1, 1.0)) * np.eye(n)
    A1 = rng.standard_normal((n, n))
    return A0, A1


def test_bialternate_sum_eigenvalues_are_pairwise_sums():
    A = np.random.default_rng(3).standard_normal((7, 7))
    lam = np.linalg.eigvals(A)
    ref = np.array([lam[i] + lam[j] for i in range(7) for j in range(i)])
    ev = np.linalg.eigvals(bialternate_sum(A))
    assert ev.size == 21
    # multiset equality through nearest matches both ways
    assert max(np.min(np.abs(ev - r)) for r in ref) < 1e-10
    assert max(np.min(np.abs(ref - e)) for e in ev) < 1e-10
    # linear in A
    B = np.random.default_rng(4).standard_normal((7, 7))
    assert_allclose(bialternate_sum(2 * A - B), 2 * bialternate_sum(A) - bialternate_sum(B),
                    atol=1e-12)


def test_two_by_two_analytic():
    """s² + (1 - δ/2) s + (2 + δ): Hurwitz iff -2 < δ < 2 (real root through 0 at -2,
    complex pair ±2j at +2)."""
    A0 = np.array([[0.0, 1.0], [-2.0, -1.0]])
    A1 = np.array([[0.0, 0.0], [-1.0, 0.5]])
    si = stability_interval(A0, A1)
    assert_allclose([si.lower, si.upper], [-2.0, 2.0], rtol=1e-12)
    assert si.crossing_lower == "real through 0" and si.crossing_upper == "complex pair"
    assert si.method == "bialternate"
    assert si.contains(0.0) and not si.contains(2.0)


def test_shift_family_has_one_sided_interval():
    """A0 - δ I is Hurwitz iff δ > α(A0): lower end analytic, upper end infinite."""
    A0, _ = _random_family(5, 6)
    si = stability_interval(A0, -np.eye(6))
    assert_allclose(si.lower, _abscissa(A0), rtol=1e-10)
    assert si.upper == math.inf and math.isnan(si.abscissa_upper)


@pytest.mark.parametrize("seed,n,nominal", [(s, n, 0.0) for s, n in
                                            [(0, 3), (1, 4), (2, 6), (3, 8), (4, 10), (5, 5),
                                             (6, 7), (7, 12)]] + [(8, 6, 0.3), (9, 4, -0.2)])
def test_random_family_matches_dense_sweep(seed, n, nominal):
    A0, A1 = _random_family(seed, n)
    A0 = A0 - nominal * A1          # so that A(nominal) is the Hurwitz matrix built above
    si = stability_interval(A0, A1, nominal=nominal)
    assert si.lower < nominal < si.upper
    # dense sweep: first unstable grid point on each side
    h = 1e-3
    for sign, end in ((+1, si.upper), (-1, si.lower)):
        d = nominal
        while abs(d - nominal) < 50 and _abscissa(A0 + d * A1) < 0:
            d += sign * h
        if math.isinf(end):
            assert abs(d - nominal) >= 50
        else:
            assert abs(d - end) <= h + 1e-12
            # and sharply: stable just inside, not stable just outside
            eps = 1e-7 * max(1.0, abs(end))
            assert _abscissa(A0 + (end - sign * eps) * A1) < 0
            assert _abscissa(A0 + (end + sign * eps) * A1) > 0
            assert abs(_abscissa(A0 + end * A1)) < 1e-8
    assert all(np.isfinite(si.candidates))


def test_not_hurwitz_and_bad_shapes():
    with pytest.raises(NotHurwitzError, match="not Hurwitz"):
        stability_interval(np.eye(2), np.eye(2))
    with pytest.raises(DimensionError, match="square"):
        stability_interval(-np.eye(2), np.eye(3))


def test_small_gain_interval_formula():
    """eq. (10), (16): V ∈ (sqrt(max(0, Vf² - 1/γ)), sqrt(Vf² + 1/γ))."""
    assert_allclose(small_gain_interval(2.0, 1.2), (math.sqrt(1.44 - 0.5), math.sqrt(1.94)))
    assert small_gain_interval(0.5, 1.2) == (0.0, math.sqrt(1.44 + 2.0))   # 1/γ > Vf²
    assert small_gain_interval(math.inf, 1.2) == (1.2, 1.2)              # no certificate
    assert small_gain_interval(0.0, 1.2) == (0.0, math.inf)
    with pytest.raises(ConfigError):
        small_gain_interval(-1.0, 1.2)
    assert speed_interval(-3.0, math.inf, 1.0) == (0.0, math.inf)


def test_a_root_where_nothing_crosses_is_passed_over_even_with_a_huge_norm():
    """A candidate where no eigenvalue crosses (a numerical root of an ill-conditioned
    pencil, as the RFA loop of the Goland wing gives: ||A|| ~ 1e13) splits a stable piece
    and is not an end; the end is the true crossing of the damping term at δ = 1.  Before,
    an end was accepted wherever |spectral abscissa| <= 1e-6 ||A||, i.e. anywhere here."""
    from casflutter.verify._interval import _pick_ends

    A0 = np.zeros((3, 3))
    A0[0, 1], A0[1, 0], A0[1, 1], A0[2, 2] = 1.0, -1.0, -1.0, -1e13
    A1 = np.zeros((3, 3))
    A1[1, 1] = 1.0                       # damping 1 - δ: a complex pair crosses at δ = 1
    kinds = {-1e-6: "complex pair", 1e-6: "complex pair", 1.0: "complex pair"}
    r = _pick_ends(kinds, lambda t: A0 + t * A1, 0.0, "bialternate", 1e-6)
    assert r.upper == 1.0 and r.crossing_upper == "complex pair"
    assert r.lower == -np.inf
    # a crossing the candidates miss inside the first piece is found by bisection, on the
    # stable side
    r = _pick_ends({3.0: "complex pair"}, lambda t: A0 + t * A1, 0.0, "bialternate", 1e-9)
    assert 1.0 - 1e-8 < r.upper <= 1.0 and r.crossing_upper == "bisection"


def test_exact_interval_of_the_goland_rfa_loop_matches_a_dense_sweep():
    """The Goland wing's RFA loop (plant.json and controller.json of
    ``casflutter run problems/goland_gaf/run.toml``; ||A|| ~ 1e13 from nearly coincident lag
    roots) gave a degenerate 'exact' interval [Vf - 1e-6, Vf + 1e-6] before the ends were
    chosen by the stability of the pieces.  The exact ends must be where a dense eigenvalue
    sweep (an independent computation) changes sign, to the sweep's step."""
    from casflutter.verify import speed_sweep, verify_controller
    from casflutter.verify._io import load_controller, load_plant

    here = Path(__file__).parent / "data"
    p = load_plant(here / "goland_rfa_plant.json")
    K = load_controller(here / "goland_rfa_controller.json")
    rep = verify_controller(p.sys, K, p.nmeas, p.ncon, Vf=p.Vf, n_delta=p.n_delta)
    lo, hi = rep.exact_V
    assert rep.stable and lo < rep.small_gain_V[0] and hi > rep.small_gain_V[1]
    step = 1e-3
    for end in (lo, hi):
        V = np.array([end - step, end + step])
        a = speed_sweep(p.sys, K, p.nmeas, p.ncon, Vf=p.Vf, n_delta=p.n_delta,
                        V=V).spectral_abscissa
        inside = a[1] if end == lo else a[0]
        outside = a[0] if end == lo else a[1]
        assert inside < 0 < outside, (end, a)
    # the interval is wide: about (0.89, 1.37) Vf, not a point
    assert hi - lo > 0.4 * p.Vf


# ---- matrix polynomials in δ and plant families in V ---------------------------------

def _quadratic_family(seed=3):
    """A(δ) with a complex pair of real part (δ - 0.5)² - 1 (crossing at δ = -0.5 and 1.5),
    a real eigenvalue δ - 1.2 (through 0 at 1.2) and a fixed stable block, in a random basis:
    the exact interval around 0 is (-0.5, 1.2)."""
    rng = np.random.default_rng(seed)
    T = rng.standard_normal((5, 5)) + 5 * np.eye(5)
    Ti = np.linalg.inv(T)

    def blocks(c0, c1, c2):
        M = np.zeros((5, 5))
        M[0, 0] = M[1, 1] = c0
        M[2, 2] = c1
        return M

    # real part (δ-0.5)²-1 = δ² - δ - 0.75; real eigenvalue δ - 1.2
    A0 = blocks(-0.75, -1.2, 0)
    A0[0, 1], A0[1, 0] = 3.0, -3.0
    A0[3:, 3:] = [[-2.0, 1.0], [0.0, -4.0]]
    A1 = blocks(-1.0, 1.0, 0)
    A2 = blocks(1.0, 0.0, 0)
    return [T @ M @ Ti for M in (A0, A1, A2)]


def test_polynomial_interval_known_quadratic():
    from casflutter.verify import polynomial_stability_interval
    r = polynomial_stability_interval(_quadratic_family(), nominal=0.0)
    assert r.method == "bialternate-polynomial"
    assert r.lower == pytest.approx(-0.5, abs=1e-8)
    assert r.upper == pytest.approx(1.2, abs=1e-8)
    assert r.crossing_lower == "complex pair" and r.crossing_upper == "real through 0"
    # the same family seen from another nominal value inside the interval
    r2 = polynomial_stability_interval(_quadratic_family(), nominal=0.9)
    assert (r2.lower, r2.upper) == pytest.approx((-0.5, 1.2), abs=1e-8)


def test_polynomial_interval_degree_one_is_the_affine_interval():
    from casflutter.verify import polynomial_stability_interval
    rng = np.random.default_rng(11)
    A0 = rng.standard_normal((6, 6)) - 4 * np.eye(6)
    A1 = rng.standard_normal((6, 6))
    a = stability_interval(A0, A1)
    p = polynomial_stability_interval([A0, A1])
    assert (p.lower, p.upper) == pytest.approx((a.lower, a.upper), rel=1e-9)


def test_polynomial_interval_refuses_bad_input():
    from casflutter.verify import polynomial_stability_interval
    with pytest.raises(DimensionError):
        polynomial_stability_interval([np.eye(2)])
    with pytest.raises(DimensionError):
        polynomial_stability_interval([-np.eye(2), np.eye(3)])
    with pytest.raises(NotHurwitzError):
        polynomial_stability_interval([np.eye(2), np.eye(2)], nominal=0.0)


def _scan_interval(fam, K, nominal, lo, hi, n=4001):
    """Independent reference: dense eigenvalue scan of python-control's closed loop, then
    bisection of the two sign changes next to ``nominal``."""
    import control

    def ab(V):
        return np.max(control.feedback(fam(V), K, sign=1).poles().real)

    grid = np.linspace(lo, hi, n)
    vals = np.array([ab(V) for V in grid])
    i0 = int(np.argmin(np.abs(grid - nominal)))
    assert vals[i0] < 0
    ends = []
    for step in (1, -1):
        i = i0
        while 0 <= i + step < n and vals[i + step] < 0:
            i += step
        if not 0 <= i + step < n:
            ends.append(None)
            continue
        a, b = grid[i], grid[i + step]
        for _ in range(60):
            m = 0.5 * (a + b)
            a, b = (m, b) if ab(m) < 0 else (a, m)
        ends.append(0.5 * (a + b))
    return ends[1], ends[0]


def test_speed_family_interval_on_a_truth_matches_a_dense_scan():
    """The typical section's own linearisation (lags ∝ V, forces ∝ V²) closed by a small
    controller: the certified interval against a dense scan with bisection."""
    import control
    from casflutter.aeroelastic import TruthLoop
    from casflutter.truth import TypicalSection
    from casflutter.verify import speed_family_interval
    fam = TruthLoop(TypicalSection(), 5.0)

    def plant(V):
        return fam.loop(V).flap_to_sensors()

    K = control.ss([[-1.0]], [[0.3, -0.5]], [[0.4]], [[0.0, 0.0]])
    r = speed_family_interval(plant, K, 1.0)
    lo, hi = _scan_interval(plant, K, 1.0, 0.02, 4.0)
    assert r.lower == pytest.approx(lo, abs=1e-6) if lo is not None else r.lower < 0.02
    assert r.upper == pytest.approx(hi, abs=1e-6)


def test_speed_family_interval_refuses_a_loop_that_is_not_polynomial():
    import control
    from casflutter.errors import ConfigError
    from casflutter.verify import speed_family_interval

    def plant(V):
        return control.ss([[-1.0 + np.sqrt(V) * 0.1]], [[1.0]], [[1.0], [0.5]], [[0.0], [0.0]])

    K = control.ss([[-2.0]], [[0.1, 0.1]], [[0.1]], [[0.0, 0.0]])
    with pytest.raises(ConfigError, match="not a polynomial"):
        speed_family_interval(plant, K, 1.0)
    with pytest.raises(ConfigError, match="nominal"):
        speed_family_interval(plant, K, 0.0)
