"""Plant families: the signals' roles, the gridded family's interpolation and its input errors,
and the paper's loop ΣAE(V) seen as a family.

Truth used: the grid's own matrices at the grid speeds, the exact affine interpolation between
them (computed here by hand), and :meth:`AeroelasticLoop.statespace` for the loop family.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import FamilySignals, GriddedFamily, TruthLoop
from casflutter.errors import ConfigError, DimensionError
from casflutter.truth import SeedWing


def _grid(k=4, n=3, m=2, p=2, seed=0):
    rng = np.random.default_rng(seed)
    speeds = np.linspace(10.0, 40.0, k)
    return speeds, [rng.standard_normal((k,) + s) for s in ((n, n), (n, m), (p, n), (p, m))]


def test_gridded_family_is_the_grid_at_its_speeds_and_affine_between_them():
    speeds, (A, B, C, D) = _grid()
    fam = GriddedFamily(speeds, A, B, C, D)
    for j, V in enumerate(speeds):
        P = fam.plant(V)
        for M, Mj in zip((P.A, P.B, P.C, P.D), (A[j], B[j], C[j], D[j])):
            assert_allclose(M, Mj, rtol=0, atol=1e-14)
    V = 0.25 * speeds[1] + 0.75 * speeds[2]
    assert_allclose(fam.state_matrix(V), 0.25 * A[1] + 0.75 * A[2], rtol=1e-14, atol=1e-14)
    assert fam.breakpoints == tuple(speeds[1:-1])
    assert fam.speed_range == (10.0, 40.0)
    assert fam.speed_degree == 1 and fam.feedback == "negative" and fam.feedback_sign == -1.0


def test_signals_roles_and_control_plant_by_name():
    speeds, mats = _grid(m=3, p=3)
    sig = FamilySignals(["aileron", "gust", "elevator"], ["q", "az", "alpha"],
                        controls=["elevator", "aileron"], measurements=["az", "q"])
    fam = GriddedFamily(speeds, *mats, sig)
    assert sig.disturbances == ("gust",)
    P = fam.control_plant(20.0)
    full = fam.plant(20.0)
    assert list(P.input_labels) == ["elevator", "aileron"]
    assert list(P.output_labels) == ["az", "q"]
    assert_allclose(P.B, np.asarray(full.B)[:, [2, 0]])
    assert_allclose(P.C, np.asarray(full.C)[[1, 0], :])
    assert_allclose(P.D, np.asarray(full.D)[np.ix_([1, 0], [2, 0])])


@pytest.mark.parametrize("kw, match", [
    (dict(controls=["elevatr"]), "did you mean 'elevator'"),
    (dict(measurements=["nz"]), "not among the outputs"),
    (dict(inputs=["a", "a"]), "more than once"),
    (dict(input_units=["rad"]), "one unit per signal"),
    (dict(inputs=["elevator ", "gust"]), r"the names \['elevator '\] have blanks around them.*"
                                        r"\['elevator'\]"),
    (dict(measurements=[" q"]), r"measurements: the names \[' q'\] have blanks"),
])
def test_signals_errors_name_the_problem(kw, match):
    args = dict(inputs=["elevator", "gust"], outputs=["q", "az"])
    args.update(kw)
    with pytest.raises(ConfigError, match=match):
        FamilySignals(**args)


def test_gridded_family_refuses_bad_arrays_before_any_work():
    speeds, (A, B, C, D) = _grid()
    with pytest.raises(ConfigError, match="strictly increasing"):
        GriddedFamily(speeds[::-1], A, B, C, D)
    bad = A.copy()
    bad[2, 1, 0] = np.nan
    with pytest.raises(DimensionError, match=r"A\[2, 1, 0\] is nan"):
        GriddedFamily(speeds, bad, B, C, D)
    with pytest.raises(DimensionError, match="same size at every speed"):
        GriddedFamily(speeds, A, B[:, :2, :], C, D)
    with pytest.raises(DimensionError, match="ragged"):
        GriddedFamily(speeds, [A[0], A[1][:2]], B[:2], C[:2], D[:2])
    with pytest.raises(ConfigError, match="feedback"):
        GriddedFamily(speeds, A, B, C, D, feedback="plus")
    fam = GriddedFamily(speeds, A, B, C, D)
    with pytest.raises(ConfigError, match="outside the range"):
        fam.plant(41.0)


def test_gridded_family_without_states_is_refused_with_the_fix():
    # a static plant (D only) has no poles: no flutter to find, and the analyses need A
    speeds, (_, _, _, D) = _grid()
    k, p, m = D.shape
    with pytest.raises(DimensionError, match=r"A has shape \(4, 0, 0\): the family has no "
                                             r"states \(a static plant, D only\).*n >= 1"):
        GriddedFamily(speeds, np.zeros((k, 0, 0)), np.zeros((k, 0, m)), np.zeros((k, p, 0)), D)


def test_the_wing_loop_is_a_family_with_named_sensors_and_one_flap():
    fam = TruthLoop(SeedWing(), 251.3)
    sig = fam.signals
    assert sig.controls == ("v",) and len(sig.disturbances) == 5
    assert sig.measurements == tuple(SeedWing().modal_structure().sensor_names)
    P, lp = fam.plant(1.2), fam.loop(1.2).statespace()
    for M, N in zip((P.A, P.B, P.C, P.D), (lp.A, lp.B, lp.C, lp.D)):
        assert_allclose(M, N, rtol=0, atol=0)
    assert fam.feedback == "positive" and fam.speed_degree == 2
