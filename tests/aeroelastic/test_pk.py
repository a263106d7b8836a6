"""p-k flutter solution on a Q(ik) table: against the independent strip-theory flutter
determinant (exact Theodorsen), against the eigenvalues of the truth's state space (Jones),
against the published Goland values, and the in-vacuo limit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import PKResult, find_flutter, pk_flutter
from casflutter.data import GAFTable
from casflutter.errors import ConfigError, ConvergenceError, DataError, DimensionError
from casflutter.structure import ModalStructure
from casflutter.truth import GolandParams, GolandWing, problem_definition
from truth.test_goland import C_theodorsen, Strips

REF = problem_definition("goland")["reference"]["flutter"]
K_GRID = np.concatenate([np.linspace(0.0, 0.2, 9), np.linspace(0.25, 2.0, 36)])
SPEEDS = np.linspace(100.0, 170.0, 15)


@pytest.fixture(scope="module")
def wing():
    return GolandWing()


@pytest.fixture(scope="module")
def structure(wing):
    ms = wing.modal_structure()
    return ms.with_sensors(kind="displacement")


@pytest.fixture(scope="module")
def exact(wing, structure):
    t = GAFTable.from_truth(wing, K_GRID)
    return t, pk_flutter(t, structure, SPEEDS, modes=(0, 1))


def test_pk_equals_the_independent_strip_determinant(exact):
    """At g = 0 p-k solves det(-w^2 M + K - q Q(ik)) = 0: the independent strip model of
    test_goland (exact Theodorsen, its own shapes and quadrature) gives the same point; the
    difference is the cubic spline of Q between the tabulated k."""
    _, pk = exact
    U, w = Strips(GolandParams()).flutter(C_theodorsen, 137.0, 70.0)
    assert pk.found and pk.mode_names[pk.modes.index(pk.flutter_mode)] == "torsion 1"
    assert_allclose([pk.flutter_speed, pk.flutter_omega], [U, w], rtol=2e-6)
    assert_allclose(pk.flutter_k, w * 0.9144 / U, rtol=2e-6)


def test_pk_matches_published_goland(exact):
    _, pk = exact
    assert_allclose(pk.flutter_speed, REF["airspeed"], rtol=0.01)
    assert_allclose(pk.flutter_omega, REF["frequency"], rtol=0.01)


def test_pk_on_jones_table_equals_the_truth_eigenvalues(wing, structure):
    """With Jones' C(k) the table is the truth's own aerodynamics: p-k's flutter point is the
    imaginary-axis crossing of the truth's state matrix."""
    t = GAFTable.from_truth(wing, K_GRID, theodorsen="jones")
    pk = pk_flutter(t, structure, SPEEDS, modes=(0, 1))
    ft = find_flutter(wing.state_matrix, (100.0 / t.U_ref, 170.0 / t.U_ref), n_grid=29)
    assert_allclose([pk.flutter_speed, pk.flutter_omega], [ft.Vf * t.U_ref, ft.omega_f],
                    rtol=2e-6)


def test_vg_vf_branches(exact):
    """V-g / V-f data: the torsion branch is damped below the flutter speed and undamped
    above; frequencies start near the in-vacuo values and coalesce."""
    _, pk = exact
    assert pk.eigenvalues.shape == pk.g.shape == pk.k.shape == (SPEEDS.size, 2)
    j = pk.modes.index(pk.flutter_mode)
    below, above = SPEEDS < pk.flutter_speed, SPEEDS > pk.flutter_speed
    assert np.all(pk.g[below, j] < 0) and np.all(pk.g[above, j] > 0)
    assert np.all(pk.omega[:, 1] > pk.omega[:, 0])
    assert_allclose(pk.k, pk.omega * 0.9144 / SPEEDS[:, None], rtol=1e-12)
    with pytest.raises(dataclasses.FrozenInstanceError):
        pk.flutter_speed = 0.0


def test_in_vacuo_limit():
    """Q = 0: the roots are the damped structural poles, g = 2 Re/Im = -2 zeta / sqrt(1-zeta^2),
    at every speed, and nothing flutters."""
    om, ze = np.array([10.0, 25.0]), np.array([0.02, 0.05])
    st = ModalStructure(om, ze, alpha=1.0)
    t = GAFTable([0.0, 1.0, 2.0], np.zeros((3, 2, 2), complex), 0.1, U_ref=10.0)
    pk = pk_flutter(t, st, [5.0, 10.0, 20.0])
    assert isinstance(pk, PKResult) and not pk.found and "no tracked mode" in pk.message
    assert_allclose(pk.eigenvalues, np.tile(-ze * om + 1j * om * np.sqrt(1 - ze ** 2), (3, 1)),
                    rtol=1e-12)
    assert_allclose(pk.g, np.tile(-2 * ze / np.sqrt(1 - ze ** 2), (3, 1)), rtol=1e-12)


def test_errors(exact, structure):
    t, _ = exact
    with pytest.raises(DataError, match=r"mode 3 \('torsion 2'\) at U = 100 m/s needs "
                                        r"k = 2.2.*track fewer modes"):
        pk_flutter(t, structure, SPEEDS, modes=(0, 1, 2))
    small = ModalStructure([1.0, 2.0], [0.0, 0.0])
    with pytest.raises(DimensionError, match=r"table has 7 modes but the structure has 2"):
        pk_flutter(t, small, SPEEDS)
    with pytest.raises(ConfigError, match=r"increasing positive airspeeds"):
        pk_flutter(t, structure, [150.0, 120.0])
    with pytest.raises(ConfigError, match=r"distinct indices in 0..6"):
        pk_flutter(t, structure, SPEEDS, modes=(0, 7))
    bare = GAFTable(t.k, t.Q, t.b)
    with pytest.raises(ConfigError, match=r"U_ref .* is needed"):
        pk_flutter(bare, structure, SPEEDS)
    with pytest.raises(ConvergenceError, match=r"p-k did not converge for mode 1 \("):
        pk_flutter(t, structure, SPEEDS, modes=(0,), max_iter=1)
