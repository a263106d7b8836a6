"""Flutter of a plant family: every crossing, located to tolerance, on continuous and gridded
families; the shipped grids against the models they were sampled from.

Truths used:

- an analytic family whose complex pair has ``Re λ = ε − (V − 1)²`` (a hump that crosses and
  re-crosses inside one grid interval, at ``1 ± √ε``) and a real eigenvalue ``V − 1.5``;
- :func:`find_flutter`, the package's branch tracking with Brent's method, on the Goland
  wing's linearisation (no repeated eigenvalues, so it is fast there);
- the guardian map of a complex-pair crossing, ``det(2A(t) ⊙ I) = 0``: on each segment of a
  linearly interpolated grid ``A(t) = A_j + t (A_{j+1} − A_j)`` is affine, so every crossing
  speed is a real generalised eigenvalue of the bialternate-sum pencil, computed here with
  scipy independently of the tracking;
- first-order perturbation theory for the grids sampled from a model quadratic in V: on the
  grid interval ``[V_j, V_{j+1}]`` the linear interpolant differs from the model by exactly
  ``E(V) = (V − V_j)(V_{j+1} − V) A₂`` (``A₂`` the model's second-order coefficient), so the
  flutter eigenvalue moves by ``w E r / (w r)`` and the crossing by
  ``ΔV = −Re(w E r / w r) / (d Re λ / dV)`` to first order; since
  ``(V − V_j)(V_{j+1} − V) ≤ h²/4`` the shift is at most ``h²/4 |Re(w A₂ r / w r)| / |d Re λ/dV|``.
  The second-order remainder is of relative size ``O(‖E‖)``: 1 % on both shipped grids;
  the tests allow 5 %.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from numpy.testing import assert_allclose

from casflutter._resources import problems_dir
from casflutter.aeroelastic import (FamilySignals, FlapWingFamily, GriddedFamily, PlantFamily,
                                    TruthLoop, family_flutter, find_flutter, load_family)
from casflutter.data import read_family_file
from casflutter.errors import ConfigError
from casflutter.report import family_branches
from casflutter.truth import GolandParams, GolandWing, SeedWing
from casflutter.verify import bialternate_sum

EPS, OMEGA = 1e-4, 3.0


class _Hump(PlantFamily):
    """``Re λ = ε − (V − 1)²`` at ``±3i``, a real eigenvalue ``V − 1.5``: quadratic in V."""

    speed_range = (0.0, 2.0)
    speed_degree = 2
    name = "hump"

    @property
    def signals(self):
        return FamilySignals(["u"], ["y"])

    def plant(self, V):
        import control
        s = EPS - (V - 1.0) ** 2
        A = np.array([[s, OMEGA, 0.0], [-OMEGA, s, 0.0], [0.0, 0.0, V - 1.5]])
        return control.ss(A, np.ones((3, 1)), np.ones((1, 3)), 0.0)


def test_a_hump_inside_one_interval_and_a_divergence_are_found_exactly():
    fam = _Hump()
    speeds = [0.0, 0.7, 1.4, 2.0]       # Re λ < 0 at every grid speed: only the derivatives
    res = family_flutter(fam, speeds=speeds)
    got = [(c.kind, c.direction) for c in res.crossings]
    assert got == [("flutter", "destabilizing"), ("flutter", "stabilizing"),
                   ("divergence", "destabilizing")]
    assert_allclose([c.V for c in res.crossings], [1 - EPS ** 0.5, 1 + EPS ** 0.5, 1.5],
                    rtol=1e-10)
    assert_allclose([c.omega for c in res.crossings], [OMEGA, OMEGA, 0.0], atol=1e-9)
    assert_allclose(res.flutter.slope, 2 * EPS ** 0.5, rtol=1e-6)   # d Re λ/dV = −2 (V − 1)
    assert res.status == "flutter" and res.Vf == res.crossings[0].V
    assert all(c.converged for c in res.crossings) and not res.unstable_at_start
    # without the bisections the hump stays hidden between the grid speeds
    assert [c.kind for c in family_flutter(fam, speeds=speeds, max_depth=0).crossings] == \
        ["divergence"]


def test_the_onsets_line_names_each_destabilising_crossing_and_an_unstable_start():
    """What a run prints for the open loop: the hump's flutter onset (the stabilising
    crossing left out) and the divergence; and a family already unstable at its first speed,
    which crosses nowhere, says so instead of 'no crossing'."""
    res = family_flutter(_Hump(), speeds=[0.0, 0.7, 1.4, 2.0])
    assert res.onsets("m/s") == (f"flutter at {1 - EPS ** 0.5:.5g} m/s (3 rad/s); "
                                 "divergence at 1.5 m/s")
    V = np.array([0.0, 1.0, 2.0])
    unstable = GriddedFamily(V, [[[0.2]]] * 3, np.ones((3, 1, 1)), np.ones((3, 1, 1)),
                             np.zeros((3, 1, 1)))
    res = family_flutter(unstable)
    assert res.status == "no_crossing" and res.unstable_at_start
    assert res.onsets("m/s") == ("no crossing into instability in the range; unstable already "
                                 "at 0 m/s (spectral abscissa 0.2 /s)")


def _pair_grid(re):
    """A gridded family at speeds 0, 1, 2 whose pair is ``re(V) ± 5i`` at the grid speeds."""
    V = np.array([0.0, 1.0, 2.0])
    A = [np.array([[re(v), 5.0], [-5.0, re(v)]]) for v in V]
    return GriddedFamily(V, A, np.ones((3, 2, 1)), np.ones((3, 1, 2)), np.zeros((3, 1, 1)))


@pytest.mark.parametrize("re, want", [
    (lambda v: v - 1.0, [(1.0, "destabilizing")]),        # through zero at a grid speed
    (lambda v: 1.0 - v, [(1.0, "stabilizing")]),
    (lambda v: -v, []),                                    # undamped at the first speed only
])
def test_crossings_at_grid_speeds_count_once_and_a_neutral_start_does_not(re, want):
    res = family_flutter(_pair_grid(re))
    assert [(c.V, c.direction) for c in res.crossings] == want
    assert_allclose([c.omega for c in res.crossings], [5.0] * len(want), rtol=1e-14)


def test_the_same_crossings_as_find_flutter_on_a_truth_loop():
    loop = TruthLoop(GolandWing(), 2 * np.pi * 40)
    grid = np.linspace(0.5, 3.0, 51)
    want = find_flutter(loop, V_grid=grid)
    got = family_flutter(loop, speeds=grid)
    assert [c.kind for c in got.crossings] == [c.kind for c in want.crossings]
    assert_allclose([c.V for c in got.crossings], [c.V for c in want.crossings], rtol=1e-9)
    assert_allclose([c.omega for c in got.crossings], [c.omega for c in want.crossings],
                    rtol=1e-9)


def _pencil_crossings(fam):
    """Complex-pair crossings of a gridded family from the bialternate pencils, per segment."""
    A, V = fam.arrays[0], fam.speeds
    out = []
    for j in range(V.size - 1):
        A0, A1 = A[j], A[j + 1] - A[j]
        t = sla.eigvals(bialternate_sum(A0), -bialternate_sum(A1))
        t = t[np.isfinite(t)]
        t = t[(np.abs(t.imag) <= 1e-8 * np.maximum(1.0, np.abs(t))) & (t.real > 0)
              & (t.real < 1)].real
        for tt in t:          # λ_i + λ_j = 0 also holds for ±x real pairs: keep ±iω only
            lam = np.linalg.eigvals(A0 + tt * A1)
            k = np.argmin(np.abs(lam.real) + 1e9 * (np.abs(lam.imag) < 1e-9))
            if abs(lam[k].real) < 1e-7 * np.max(np.abs(lam)):
                out.append((V[j] + tt * (V[j + 1] - V[j]), abs(lam[k].imag)))
    return sorted(out)


def _check_against_pencils(fam):
    res = family_flutter(fam)
    got = [(c.V, c.omega) for c in res.crossings if c.kind == "flutter"]
    want = _pencil_crossings(fam)
    assert len(got) == len(want) >= 1
    assert_allclose(np.array(got), np.array(want), rtol=1e-8)


def test_every_crossing_of_a_small_grid_is_the_exact_pencil_one(tmp_path):
    small = TruthLoop(GolandWing(GolandParams(n_bending=2, n_torsion=2)), 2 * np.pi * 40)
    V = np.linspace(1.0, 3.0, 21)
    P = [small.plant(v) for v in V]
    fam = GriddedFamily(V, [p.A for p in P], [p.B for p in P], [p.C for p in P],
                        [p.D for p in P])
    _check_against_pencils(fam)


@pytest.mark.slow
def test_every_crossing_of_the_seed_wing_grid_is_the_exact_pencil_one():
    _check_against_pencils(load_family(problems_dir() / "seed_wing_family"))


def _first_order_shift(source, grid, Vs, lam_s):
    """(predicted ΔV at Vs, its bound over the interval) for the grid's interpolation error."""
    j = int(np.searchsorted(grid, Vs)) - 1
    a, b = grid[j], grid[j + 1]
    h = b - a
    A2 = (source.state_matrix(a) - 2 * source.state_matrix(0.5 * (a + b))
          + source.state_matrix(b)) / (2 * (h / 2) ** 2)
    lam, R = np.linalg.eig(source.state_matrix(Vs))
    k = int(np.argmin(np.abs(lam - lam_s)))
    W = np.linalg.inv(R)
    r, w = R[:, k], W[k]                                   # w r = 1
    dA = (source.state_matrix(Vs + 1e-5) - source.state_matrix(Vs - 1e-5)) / 2e-5
    slope = (w @ dA @ r).real
    g = (w @ A2 @ r).real
    return -(Vs - a) * (b - Vs) * g / slope, h * h / 4 * abs(g / slope)


@pytest.mark.parametrize("name, source, window", [
    ("goland_4flaps", FlapWingFamily(), (130.0, 150.0)),
    ("seed_wing_family", TruthLoop(SeedWing(), 251.3), (1.0, 1.2)),
])
def test_shipped_grid_flutter_against_its_source_within_the_interpolation_error(
        name, source, window):
    fam = load_family(problems_dir() / name)
    grid = family_flutter(fam)
    exact = family_flutter(source, speeds=np.linspace(*window, 21))
    assert grid.status == exact.status == "flutter"
    assert len([c for c in grid.crossings if c.kind == "flutter"]) == 1
    assert not grid.unstable_at_start                          # stable below the flutter
    shift, bound = _first_order_shift(source, fam.speeds, exact.Vf, exact.flutter.eigenvalue)
    dV = grid.Vf - exact.Vf
    assert abs(dV) <= 1.05 * bound
    assert_allclose(dV, shift, rtol=0.05)
    # the file's reference value is the source's flutter (rounded to 1e-6 when written)
    ref = read_family_file(problems_dir() / name / "problem.toml").reference["flutter"]
    speed = ref["speed"] if "speed" in ref else ref["speed_index"]
    assert_allclose([speed, ref["omega_rad_s"]], [exact.Vf, exact.omega_f], atol=1e-6)


def test_branches_drawn_are_the_light_oscillatory_ones_and_the_crossing_one():
    fam = load_family(problems_dir() / "goland_4flaps")
    res = family_flutter(fam)
    bs = family_branches(res)
    lam = res.tracking.eigenvalues
    assert res.flutter.branch in bs
    assert np.all(lam[0, bs].imag > 0)                       # one of each pair
    assert np.all(np.min(res.tracking.damping_ratio[:, bs], axis=0) < 0.5)
    actuators = np.isclose(np.abs(lam[0]), 2 * np.pi * 25, rtol=1e-9)
    assert actuators.any() and not set(np.flatnonzero(actuators)) & set(bs)


@pytest.mark.parametrize("kw, match", [
    (dict(speeds=[50.0, 100.0]), "outside the range"),
    (dict(speeds=[100.0, 90.0]), "strictly increasing"),
    (dict(xtol=0.1), "xtol"),
    (dict(min_score=1.5), "min_score"),
    (dict(subdivide=0), "subdivide"),
])
def test_settings_are_checked_first(kw, match):
    fam = load_family(problems_dir() / "goland_4flaps")
    with pytest.raises(ConfigError, match=match):
        family_flutter(fam, **kw)


def test_an_open_range_needs_speeds():
    with pytest.raises(ConfigError, match="open speed range .* give the speeds"):
        family_flutter(TruthLoop(SeedWing(), 251.3))
