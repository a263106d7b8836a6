"""Q(ik) tables: the NPZ / CSV / .mat layouts round-trip exactly, bad files and arrays give a
DataError naming the array and the fix, the spline in k against the exact strip-theory Q, and
the conversion from NASTRAN's dynamic-pressure form."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.io import savemat

from casflutter.data import GAFTable, load_gaf
from casflutter.errors import DataError
from casflutter.truth import GolandParams, GolandWing


@pytest.fixture(scope="module")
def wing():
    return GolandWing(GolandParams(n_bending=2, n_torsion=2))


@pytest.fixture(scope="module")
def table(wing):
    return GAFTable.from_truth(wing, np.linspace(0.0, 1.5, 16))


def _same(a: GAFTable, b: GAFTable):
    assert_array_equal(a.k, b.k)
    assert_array_equal(a.Q, b.Q)
    assert (a.b, a.U_ref, a.rho, a.mode_names, a.source) == (b.b, b.U_ref, b.rho, b.mode_names,
                                                             b.source)


# ---- round trips ----------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".npz", ".csv", ".mat"])
def test_round_trip_with_flap_and_metadata(table, tmp_path, suffix):
    path = table.save(tmp_path / f"goland{suffix}")
    back = load_gaf(path)
    _same(table, back)
    assert back.has_flap and back.input_names[-1] == "flap"


@pytest.mark.parametrize("suffix", [".npz", ".csv", ".mat"])
def test_round_trip_minimal_table(tmp_path, suffix):
    rng = np.random.default_rng(0)
    Q = rng.standard_normal((3, 2, 2)) + 1j * rng.standard_normal((3, 2, 2))
    t = GAFTable([0.0, 0.1, 0.4], Q, 0.5)
    back = load_gaf(t.save(tmp_path / f"t{suffix}"))
    _same(t, back)
    assert back.U_ref is None and back.rho is None and not back.has_flap
    assert back.mode_names == ("mode 1", "mode 2")


def test_single_frequency_mat(tmp_path):
    """MATLAB drops a trailing singleton dimension: one N x M page is one frequency."""
    t = GAFTable([0.3], np.array([[[1 + 2j, 3j], [0.5, -1j]]]), 1.0)
    _same(t, load_gaf(t.save(tmp_path / "one.mat")))


def test_without_flap(table):
    t = table.without_flap()
    assert t.n_inputs == t.n_modes == table.n_modes and not t.has_flap
    assert_array_equal(t.Q, table.Q[:, :, :table.n_modes])


# ---- interpolation --------------------------------------------------------------------------
def test_spline_matches_the_exact_q_between_the_nodes(wing):
    """Cubic spline on a 0.05 grid against the exact strip theory at the midpoints.

    Away from k = 0 (where Theodorsen's C(k) has its k log k branch point and a spline
    needs a denser grid) the error is far below the RFA fit errors of interest."""
    t = GAFTable.from_truth(wing, np.linspace(0.0, 1.5, 31))
    mid = 0.5 * (t.k[1:] + t.k[:-1])
    mid = mid[mid > 0.3]
    exact = wing.generalized_aero_forces(mid)
    err = np.abs(t.interpolate(mid) - exact) / np.max(np.abs(exact), axis=0)
    assert err.max() < 2e-5
    assert_allclose(t.interpolate(t.k[5]), t.Q[5], rtol=1e-13, atol=1e-15)


def test_interpolation_refuses_to_extrapolate(table):
    with pytest.raises(DataError, match=r"outside the table \[0, 1.5\].*extend"):
        table.interpolate(1.6)


# ---- NASTRAN's dynamic-pressure form ----------------------------------------------------------
def test_from_dynamic_pressure_recovers_eq6_form(wing, table):
    """M u'' + K u = q_dyn Q_N u with generalised masses m L (physical modes) gives back eq. (6).

    For the truth, y = Phi^T f / (rho U^2 L) and Phi^T f = q_dyn Q_N u, so Q_N = 2 L Q."""
    p = wing.params
    Q_N = 2.0 * p.semispan * table.Q
    back = GAFTable.from_dynamic_pressure(table.k, Q_N, p.b, generalized_mass=p.mass * p.semispan,
                                          alpha=wing.alpha, U_ref=wing.airspeed(1.0), rho=p.rho)
    assert_allclose(back.Q, table.Q, rtol=1e-12, atol=1e-14)
    diag = GAFTable.from_dynamic_pressure(table.k, Q_N, p.b,
                                          generalized_mass=np.full(table.n_modes,
                                                                   p.mass * p.semispan),
                                          alpha=wing.alpha, U_ref=wing.airspeed(1.0), rho=p.rho)
    assert_allclose(diag.Q, table.Q, rtol=1e-12, atol=1e-14)


# ---- bad arrays -------------------------------------------------------------------------------
Q2 = np.ones((3, 2, 3), complex)


@pytest.mark.parametrize("kwargs, pattern", [
    (dict(k=[0.0, 0.2, 0.1], Q=Q2), r"strictly increasing: k\[2\] = 0.1 follows.*sort"),
    (dict(k=[0.0, 0.2, 0.2], Q=Q2), r"strictly increasing"),
    (dict(k=[-0.1, 0.2, 0.3], Q=Q2), r"negative"),
    (dict(k=[0.0, np.nan, 0.3], Q=Q2), r"k has NaN/inf at index 1"),
    (dict(k=[0.0, 0.1, 0.3], Q=Q2.real), r"real dtype.*must be complex.*1j"),
    (dict(k=[0.0, 0.1], Q=Q2), r"3 matrices but k has 2 values"),
    (dict(k=[0.0, 0.1, 0.3], Q=np.ones((3, 2, 4), complex)), r"2 x 4.*N x N.*N x \(N\+1\)"),
    (dict(k=[0.0, 0.1, 0.3], Q=np.ones((3, 6), complex)), r"shape \(nk, N, M\)"),
    (dict(k=[0.0, 0.1, 0.3], Q=np.where(np.arange(18).reshape(3, 2, 3) == 10, np.nan, 1) + 0j),
     r"NaN/inf entries, first Q\[1\] element \(2, 2\) at k = 0.1"),
    (dict(k=[0.0, 0.1, 0.3], Q=Q2, b=-1.0), r"b = -1.0 must be a positive"),
    (dict(k=[0.0, 0.1, 0.3], Q=Q2, b=None), r"b is missing"),
    (dict(k=[0.0, 0.1, 0.3], Q=Q2, U_ref=np.inf), r"U_ref = inf must be a positive"),
    (dict(k=[0.0, 0.1, 0.3], Q=Q2, mode_names=("a",)), r"1 names for N = 2 modes"),
])
def test_bad_arrays(kwargs, pattern):
    kwargs.setdefault("b", 1.0)
    with pytest.raises(DataError, match=pattern):
        GAFTable(**kwargs)


# ---- bad files --------------------------------------------------------------------------------
@pytest.mark.parametrize("missing", ["k", "Q", "b"])
def test_npz_missing_array(tmp_path, missing):
    arrays = {"k": np.array([0.0, 0.1]), "Q": np.ones((2, 1, 1), complex), "b": np.array(1.0)}
    del arrays[missing]
    np.savez(tmp_path / "t.npz", **arrays)
    with pytest.raises(DataError, match=rf"no array '{missing}'.*needs k \(nk,\), complex Q"):
        load_gaf(tmp_path / "t.npz")


def test_npz_real_q_names_the_file_and_the_fix(tmp_path):
    np.savez(tmp_path / "real.npz", k=[0.0, 0.1], Q=np.ones((2, 1, 1)), b=1.0)
    with pytest.raises(DataError, match=r"real\.npz: Q has real dtype.*complex"):
        load_gaf(tmp_path / "real.npz")


def test_mat_in_the_wrong_orientation(tmp_path):
    savemat(tmp_path / "t.mat", {"k": np.array([0.0, 0.1, 0.2, 0.3]),
                                 "Q": np.ones((4, 2, 2), complex), "b": 1.0})
    with pytest.raises(DataError, match=r"N x M x nk.*permute\(Q, \[2 3 1\]\)"):
        load_gaf(tmp_path / "t.mat")


def test_mat_missing_variable(tmp_path):
    savemat(tmp_path / "t.mat", {"k": np.array([0.0, 0.1]), "Q": np.ones((1, 1, 2), complex)})
    with pytest.raises(DataError, match=r"no variable 'b'"):
        load_gaf(tmp_path / "t.mat")


def _csv(tmp_path, text):
    path = tmp_path / "t.csv"
    path.write_text(text)
    return path


GOOD_HEAD = "# b = 1.0\nk,row,col,real,imag\n"


@pytest.mark.parametrize("text, pattern", [
    ("k,row,col,real,imag\n0,1,1,1,0\n", r"no '# b = <semichord>' line"),
    ("# b = 1.0\nk,r,c,re,im\n0,1,1,1,0\n", r"header .* must be \['k', 'row', 'col'"),
    ("# B = 1.0\n" + GOOD_HEAD + "0,1,1,1,0\n", r"unknown key 'B'"),
    ("# mode_names = [a, b]\n" + GOOD_HEAD + "0,1,1,1,0\n", r"not JSON.*double quotes"),
    (GOOD_HEAD + "0,1,1,1,0\n0,1,1,2,0\n", r"element \(1, 1\) at k = 0 appears twice"),
    (GOOD_HEAD + "0,1,1,1,0\n0,2,2,1,0\n0,1,2,1,0\n", r"element \(2, 1\) missing at k = 0"),
    (GOOD_HEAD + "0,1,1,x,0\n", r":3: non-numeric"),
    (GOOD_HEAD + "0,1,1,1\n", r":3: 4 fields, expected 5"),
    (GOOD_HEAD + "0,0,1,1,0\n", r"1-based"),
    (GOOD_HEAD, r"no data lines"),
    (GOOD_HEAD + "0,1,1,nan,0\n", r"NaN/inf entries"),
])
def test_bad_csv(tmp_path, text, pattern):
    with pytest.raises(DataError, match=pattern):
        load_gaf(_csv(tmp_path, text))


def test_unknown_suffix_and_missing_file(tmp_path, table):
    with pytest.raises(DataError, match=r"unknown suffix '.txt'; use .npz, .csv or .mat"):
        load_gaf(tmp_path / "q.txt")
    with pytest.raises(DataError, match=r"unknown suffix"):
        table.save(tmp_path / "q.json")
    with pytest.raises(DataError, match=r"no such file"):
        load_gaf(tmp_path / "absent.npz")
