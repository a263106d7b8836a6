"""The certified stable interval of a controller on a plant family, piece by piece.

Two certificates that share nothing but the closed-loop map must give the same end: the
eigenvalue-inclusion chain and the guardian map (bialternate pencils, with the Y channel of a
rational closed loop), on seeded families that flutter (affine pieces of a grid, pieces of
degree 2 between breakpoints, strictly proper controllers and controllers with a
feed-through).  A dense eigenvalue scan of the loop closed by python-control then confirms
stability below the end and instability just above it.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from casflutter.aeroelastic import FamilySignals, GriddedFamily, TruthLoop
from casflutter.errors import ConfigError
from casflutter.truth import SeedWing
from casflutter.verify import certified_interval, load_controller, speed_family_interval

from family_helpers import (SERVO, WITNESSES, QuadraticFamily, abscissa, random_family,
                             seed_wing_grid, small_controller)


def _certify(fam, K, method="auto", **kw):
    s = fam.signals
    return certified_interval(fam, K, s.controls, s.measurements, fam.feedback_sign,
                              fam.speed_range, method=method, **kw)


def _check_against_scan(fam, K, cert, n=600):
    lo, hi = fam.speed_range
    below = np.linspace(lo, cert.upper, n)[:-1]
    assert max(abscissa(fam, K, V) for V in below) < 0
    if cert.loss is not None:
        assert cert.upper <= cert.loss <= cert.upper + 1e-6 * (hi - lo)
        assert abscissa(fam, K, min(hi, cert.loss + 1e-6 * (hi - lo))) > 0


@pytest.mark.parametrize("with_d", [False, True], ids=["strictly proper", "feed-through"])
@pytest.mark.parametrize("seed", [0, 1, 3])
def test_inclusion_chain_and_guardian_map_agree_on_a_grid(seed, with_d):
    fam = random_family(seed, with_d=with_d)
    K = small_controller(np.random.default_rng(100 + seed), 2, 2, 2, gain=0.05,
                         with_d=with_d)
    chain, guard = _certify(fam, K), _certify(fam, K, "guardian")
    assert chain.lower == guard.lower == fam.speed_range[0] and chain.stable_at_start
    assert {p.method for p in chain.pieces} == {"inclusion"}
    assert {p.method for p in guard.pieces} == {"guardian"}
    # the same loss of stability, to far below the interpolation of a grid
    assert chain.loss == pytest.approx(guard.loss, rel=1e-9)
    assert chain.crossing == guard.crossing == "complex pair"
    assert chain.omega == pytest.approx(guard.omega, rel=1e-6)
    _check_against_scan(fam, K, chain)


@pytest.mark.parametrize("with_d", [False, True], ids=["strictly proper", "feed-through"])
@pytest.mark.parametrize("seed", [1, 2])
def test_pieces_of_degree_two_between_breakpoints(seed, with_d):
    fam = QuadraticFamily(seed, with_d=with_d)
    K = small_controller(np.random.default_rng(200 + seed), 1, 2, 2, gain=0.05,
                         with_d=with_d)
    chain, guard = _certify(fam, K), _certify(fam, K, "guardian")
    assert [p.lower for p in chain.pieces][:2] == [0.1, 0.6]   # pieces meet at breakpoints
    assert chain.loss == pytest.approx(guard.loss, rel=1e-9)
    _check_against_scan(fam, K, chain)


def test_the_seed_wing_truth_from_v_0_matches_the_polynomial_interval():
    """A loop family from V = 0 (marginally stable there: the lag states ∝ V) is certified by
    the guardian map from the start, as :func:`speed_family_interval` certifies it."""
    fam = TruthLoop(SeedWing(), SERVO)
    K = load_controller(WITNESSES / "truth_interval_controller_order4.json")
    cert = certified_interval(fam, K, ("v",), fam.signals.measurements, 1.0, (0.0, 3.0))
    ref = speed_family_interval(lambda V: fam.loop(V).flap_to_sensors(), K, 1.2)
    assert cert.lower == 0.0 and not cert.stable_at_start
    assert cert.upper == pytest.approx(ref.upper, rel=1e-8)
    assert cert.pieces[0].method == "guardian"


@pytest.mark.slow
def test_the_seed_wing_grid_chain_against_the_guardian_map():
    fam = seed_wing_grid(np.linspace(0.1, 3.0, 30))
    K = load_controller(WITNESSES / "truth_interval_controller_order4.json")
    chain, guard = _certify(fam, K), _certify(fam, K, "guardian")
    assert chain.loss == pytest.approx(guard.loss, rel=1e-9)
    # the grid's interpolation moves the wing's end (2.41256) only a little
    assert 2.40 < chain.upper < 2.42
    _check_against_scan(fam, K, chain, n=300)


def _oscillator_family(speeds):
    """Eigenvalues ``V - 1 ± 5j``: a crossing at exactly V = 1."""
    A = [np.array([[v - 1.0, 5.0], [-5.0, v - 1.0]]) for v in speeds]
    B = [np.array([[1.0], [0.0]])] * len(speeds)
    C = [np.array([[1.0, 0.0]])] * len(speeds)
    D = [np.zeros((1, 1))] * len(speeds)
    return GriddedFamily(speeds, A, B, C, D, FamilySignals(["u"], ["y"]))


def test_a_crossing_at_a_grid_speed():
    fam = _oscillator_family([0.5, 1.0, 1.5])
    cert = _certify(fam, np.zeros((1, 1)))
    assert cert.loss == pytest.approx(1.0, abs=1e-9)
    assert cert.upper <= cert.loss and cert.omega == pytest.approx(5.0, rel=1e-6)
    assert not cert.holds_range and not cert.covers(0.5, 1.0) and cert.covers(0.5, 0.999)


def test_a_range_held_to_its_end():
    fam = _oscillator_family([0.1, 0.5, 0.9])
    cert = _certify(fam, np.zeros((1, 1)))
    assert cert.holds_range and cert.loss is None and cert.upper == 0.9
    assert cert.covers(0.1, 0.9) and math.isnan(cert.omega)


def test_unstable_at_the_start():
    fam = _oscillator_family([1.5, 2.0])
    cert = _certify(fam, np.zeros((1, 1)))
    assert cert.lower is None and cert.upper is None and cert.loss == 1.5
    assert not cert.covers(1.5, 1.6)


def test_a_family_without_a_degree_or_with_a_wrong_one_is_refused():
    fam = QuadraticFamily(1)
    K = control.ss([], [], [], np.zeros((1, 2)))
    with pytest.raises(ConfigError, match="not a polynomial of degree 1"):
        certified_interval(fam, K, ("u",), ("y0", "y1"), -1.0, (0.1, 1.5), degree=1)
    fam.speed_degree = None
    with pytest.raises(ConfigError, match="speed_degree is None"):
        certified_interval(fam, K, ("u",), ("y0", "y1"), -1.0, (0.1, 1.5))
    with pytest.raises(ConfigError, match="finite range"):
        certified_interval(fam, K, ("u",), ("y0", "y1"), -1.0, (0.1, math.inf), degree=2)


def test_the_open_loop_of_the_50_state_family_matches_its_flutter_search():
    """With no controller, the certified interval of ``goland_4flaps`` (50 states, 41 speeds)
    ends at the grid's flutter speed as :func:`casflutter.aeroelastic.family_flutter` finds it
    (eigenvalue derivatives and Newton steps: a computation that shares nothing with the
    certificate)."""
    from casflutter.aeroelastic import family_flutter, load_family

    fam = load_family("goland_4flaps")
    s = fam.signals
    cert = certified_interval(fam, np.zeros((4, 8)), s.controls, s.measurements,
                              fam.feedback_sign, fam.speed_range)
    ref = family_flutter(fam)
    assert cert.loss == pytest.approx(ref.Vf, rel=1e-8)
    assert cert.omega == pytest.approx(ref.omega_f, rel=1e-6)
    assert {p.method for p in cert.pieces} == {"inclusion"}
