"""Gridded plant-family files: the round trip through .npz and MATLAB .mat, the MATLAB
layouts (pages, speed first, cell arrays, cellstr and char-matrix names; a warning and the
``layout`` key when both fit), names stripped of blanks alike in the data file and the
problem file, and every input error (a family without states among them) named before any
work.

Truth used: the arrays written are the arrays read back (bit for bit), and scipy's own
``savemat`` writes the MATLAB files the way MATLAB stores them.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from numpy.testing import assert_array_equal
from scipy.io import savemat

from casflutter.data import FamilyFile, read_family_arrays, read_family_file
from casflutter.errors import ConfigError, DataError, DataWarning, DimensionError

K, N, M, P = 5, 4, 2, 3


def _record(**kw):
    rng = np.random.default_rng(7)
    args = dict(speeds=np.linspace(10.0, 50.0, K), A=rng.standard_normal((K, N, N)),
                B=rng.standard_normal((K, N, M)), C=rng.standard_normal((K, P, N)),
                D=rng.standard_normal((K, P, M)), speed_unit="m/s", feedback="negative",
                name="demo", input_names=("elevon", "gust"), output_names=("q", "az", "nz"),
                controls=("elevon",), measurements=("q", "nz"),
                input_units=("rad", "m/s"), output_units=("rad/s", "m/s^2", "g"),
                reference={"flutter": {"speed": 31.5}})
    args.update(kw)
    return FamilyFile(**args)


def _toml(path, data_file, **extra):
    lines = ['kind = "plant_family"', f'file = "{data_file}"', 'speed_unit = "m/s"',
             'feedback = "negative"'] + [f"{k} = {v}" for k, v in extra.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_round_trip_keeps_arrays_names_roles_and_units(tmp_path, fmt):
    rec = _record()
    toml = rec.write(tmp_path / "fam.toml", format=fmt)
    assert (tmp_path / f"fam.{fmt}").is_file()
    back = read_family_file(toml)
    for key in ("speeds", "A", "B", "C", "D"):
        assert_array_equal(getattr(back, key), getattr(rec, key))
    for key in ("input_names", "output_names", "controls", "measurements", "input_units",
                "output_units", "speed_unit", "time_unit", "feedback", "interpolation",
                "name", "reference"):
        assert getattr(back, key) == getattr(rec, key), key
    assert back.data_path == tmp_path / f"fam.{fmt}" and back.path == toml
    assert "5 speeds [10, 50] m/s" in back.describe()


def test_mat_layouts_pages_speed_first_cells_and_name_forms(tmp_path):
    rec = _record()
    want = {key: getattr(rec, key) for key in ("A", "B", "C", "D")}
    pages = {key: np.moveaxis(v, 0, -1) for key, v in want.items()}      # n x n x k
    cells = np.empty((1, K), dtype=object)
    for j in range(K):
        cells[0, j] = rec.A[j]
    char_matrix = np.array(["q ", "az", "nz"])                             # padded rows
    cellstr = np.empty((1, M), dtype=object)
    cellstr[0, :] = ["elevon", "gust"]
    cases = {"pages": pages, "first": want, "cells": {**pages, "A": cells}}
    for name, arrays in cases.items():
        path = tmp_path / f"{name}.mat"
        savemat(path, {"speeds": rec.speeds[:, None], **arrays, "input_names": cellstr,
                       "output_names": char_matrix})
        got = read_family_arrays(path)
        for key in want:
            assert_array_equal(got[key], want[key], err_msg=f"{name}: {key}")
        assert got["input_names"] == ("elevon", "gust")
        assert got["output_names"] == ("q", "az", "nz")


def test_single_input_output_mat_keeps_its_singleton_axes(tmp_path):
    rec = _record(B=np.ones((K, N, 1)), D=np.zeros((K, 1, 1)), C=np.ones((K, 1, N)),
                  input_names=("flap",), output_names=("acc",), controls=None,
                  measurements=None, input_units=(), output_units=())
    back = read_family_file(rec.write(tmp_path / "siso.toml", format="mat"))
    assert back.B.shape == (K, N, 1) and back.D.shape == (K, 1, 1)
    assert back.input_names == ("flap",) and back.output_names == ("acc",)


def test_default_names_and_time_unit(tmp_path):
    np.savez(tmp_path / "g.npz", speeds=[1.0, 2.0], A=np.zeros((2, 2, 2)) - np.eye(2),
             B=np.ones((2, 2, 1)), C=np.ones((2, 1, 2)), D=np.zeros((2, 1, 1)))
    rec = read_family_file(_toml(tmp_path / "problem.toml", "g.npz"))
    assert rec.input_names == ("u1",) and rec.output_names == ("y1",)
    assert rec.time_unit == "s" and rec.interpolation == "linear"
    assert rec.name == tmp_path.name                  # problem.toml: named by its folder


def test_a_problem_toml_given_relative_to_its_folder_is_named_by_the_folder(tmp_path,
                                                                              monkeypatch):
    np.savez(tmp_path / "g.npz", speeds=[1.0, 2.0], A=-np.ones((2, 1, 1)), B=np.ones((2, 1, 1)),
             C=np.ones((2, 1, 1)), D=np.zeros((2, 1, 1)))
    _toml(tmp_path / "problem.toml", "g.npz")
    monkeypatch.chdir(tmp_path)
    assert read_family_file("problem.toml").name == tmp_path.name     # not ""


def test_npz_names_stored_as_bytes_read_as_text(tmp_path):
    np.savez(tmp_path / "g.npz", speeds=[1.0, 2.0], A=-np.ones((2, 1, 1)), B=np.ones((2, 1, 1)),
             C=np.ones((2, 1, 1)), D=np.zeros((2, 1, 1)), input_names=np.array([b"aileron"]),
             output_names=np.array(["q"]))
    rec = read_family_file(_toml(tmp_path / "f.toml", "g.npz"))
    assert rec.input_names == ("aileron",) and rec.output_names == ("q",)


def _npz(tmp_path, **change):
    rec = _record()
    arrays = dict(speeds=rec.speeds, A=rec.A, B=rec.B, C=rec.C, D=rec.D,
                  input_names=np.array(rec.input_names), output_names=np.array(rec.output_names))
    arrays.update(change)
    np.savez(tmp_path / "g.npz", **{k: v for k, v in arrays.items() if v is not None})
    return _toml(tmp_path / "f.toml", "g.npz")


@pytest.mark.parametrize("change, match", [
    (dict(speeds=[10.0, 20.0, 20.0, 30.0, 40.0]), r"speeds\[2\] = 20 follows speeds\[1\] = 20"),
    (dict(A=np.where(np.arange(N) == 1, np.nan, 0.0) * np.ones((K, N, N))),
     r"A\[0, 0, 1\] is nan"),
    (dict(B=np.ones((K, N + 1, M))), r"B has shape \(5, 5, 2\); it must be \(5, 4, cols\)"),
    (dict(input_names=np.array(["elevon"])), "input_names has 1 names for 2 inputs"),
    (dict(D=None), "no variable 'D'"),
    (dict(A=np.array([np.eye(2), np.eye(3)], dtype=object)), "A is an object array"),
    (dict(C=np.ones((K, P, N)).astype(complex)), "C has dtype complex128"),
])
def test_npz_errors_name_the_array(tmp_path, change, match):
    with pytest.raises(DataError, match=match):
        read_family_file(_npz(tmp_path, **change))


def test_mat_state_dimension_changing_along_the_grid_is_named(tmp_path):
    cells = np.empty((1, 3), dtype=object)
    cells[0, 0], cells[0, 1], cells[0, 2] = np.eye(2), np.eye(2), np.eye(3)
    savemat(tmp_path / "g.mat", {"speeds": [1.0, 2.0, 3.0], "A": cells,
                                 "B": np.ones((2, 1, 3)), "C": np.ones((1, 2, 3)),
                                 "D": np.zeros((1, 1, 3))})
    with pytest.raises(DataError, match=r"A\{3\} is 3 x 3 but A\{1\} is 2 x 2 \(the state "
                                        r"dimension changes along the grid\)"):
        read_family_file(_toml(tmp_path / "f.toml", "g.mat"))


def test_mat_arrays_that_fit_no_layout(tmp_path):
    savemat(tmp_path / "g.mat", {"speeds": [1.0, 2.0, 3.0], "A": np.ones((2, 2, 4)),
                                 "B": np.ones((2, 1, 3)), "C": np.ones((1, 2, 3)),
                                 "D": np.zeros((1, 1, 3))})
    with pytest.raises(DataError, match="do not fit 3 speeds in either layout"):
        read_family_file(_toml(tmp_path / "f.toml", "g.mat"))


def test_mat_v73_is_refused_with_the_fix(tmp_path):
    head = b"MATLAB 7.3 MAT-file".ljust(124, b" ") + b"\x00\x02IM"
    (tmp_path / "g.mat").write_bytes(head + b"\x00" * 512)
    with pytest.raises(DataError, match=r"v7.3 \(HDF5\).*-v7"):
        read_family_file(_toml(tmp_path / "f.toml", "g.mat"))


@pytest.mark.parametrize("extra, match", [
    (dict(feedbak='"positive"'), "unknown key 'feedbak'; did you mean 'feedback'"),
    (dict(interpolation='"cubic"'), "interpolation = 'cubic'; allowed: 'linear'"),
    (dict(controls='"elevon"'), "controls = 'elevon' must be a list of strings"),
    (dict(time_unit="1"), "time_unit = 1 must be a string"),
])
def test_toml_errors_before_the_data_file_is_read(tmp_path, extra, match):
    # the data file does not exist: the key errors come first
    with pytest.raises(ConfigError, match=match):
        read_family_file(_toml(tmp_path / "f.toml", "absent.npz", **extra))


def test_missing_keys_files_and_problem_table(tmp_path):
    (tmp_path / "f.toml").write_text('kind = "plant_family"\nfile = "g.npz"\n'
                                     'speed_unit = "m/s"\n')
    with pytest.raises(ConfigError, match="key 'feedback' is missing.*negative.*positive"):
        read_family_file(tmp_path / "f.toml")
    sub = tmp_path / "sub"
    sub.mkdir()
    with pytest.raises(DataError, match=r"file = 'g.npz': .*sub/g.npz not found \(a relative "
                                        r"path is taken from the problem file's folder\)"):
        read_family_file(_toml(sub / "f.toml", "g.npz"))
    path = _toml(tmp_path / "p.toml", "g.npz")
    path.write_text(path.read_text() + '[problem]\nnmae = "x"\n')
    with pytest.raises(ConfigError, match="unknown key problem.'nmae'; did you mean 'name'"):
        read_family_file(path)
    with pytest.raises(DataError, match="unknown suffix '.csv'"):
        read_family_arrays(tmp_path / "g.csv")


def test_writer_refuses_bad_format_and_names(tmp_path):
    rec = _record()
    with pytest.raises(ConfigError, match="format = 'hdf5'"):
        rec.write(tmp_path / "f.toml", format="hdf5")
    with pytest.raises(ConfigError, match="must be a file name"):
        rec.write(tmp_path / "f.toml", data_file="sub/x.npz")
    with pytest.raises(ConfigError, match="feedback = 'plus'"):
        _record(feedback="plus")
    assert not list(tmp_path.iterdir())                       # nothing written


def test_a_family_without_states_is_refused_with_the_fix(tmp_path):
    static = dict(A=np.zeros((K, 0, 0)), B=np.zeros((K, 0, M)), C=np.zeros((K, P, 0)))
    match = r"A has shape \(5, 0, 0\): the family has no states.*static plant.*n >= 1"
    with pytest.raises(DimensionError, match=match):
        _record(**static)
    with pytest.raises(DataError, match=r"g.npz: " + match):
        read_family_file(_npz(tmp_path, **static))


def _square(k=4, seed=3):
    """n = m = p = k: arrays that fit both .mat layouts, saved speed first."""
    rng = np.random.default_rng(seed)
    return {"speeds": np.linspace(40.0, 200.0, k),
            **{key: rng.standard_normal((k, k, k)) for key in ("A", "B", "C", "D")}}


def test_mat_arrays_fitting_both_layouts_warn_and_the_layout_key_decides(tmp_path):
    arrays = _square()
    savemat(tmp_path / "g.mat", arrays)                       # speed first
    with pytest.warns(DataWarning, match=r"g.mat: the arrays fit 4 speeds both as MATLAB pages "
                                         r"and speed first.*read as pages.*"
                                         r"layout = \"speed_first\""):
        rec = read_family_file(_toml(tmp_path / "f.toml", "g.mat"))
    assert_array_equal(rec.A, np.moveaxis(arrays["A"], -1, 0))     # the documented rule
    for layout, want in (("speed_first", arrays), ("pages", {
            key: np.moveaxis(arrays[key], -1, 0) for key in ("A", "B", "C", "D")})):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            rec = read_family_file(_toml(tmp_path / "f.toml", "g.mat", layout=f'"{layout}"'))
        for key in ("A", "B", "C", "D"):
            assert_array_equal(getattr(rec, key), want[key], err_msg=f"{layout}: {key}")


def test_mat_arrays_fitting_one_layout_or_all_cells_do_not_warn(tmp_path):
    rec = _record()                                           # k = 5, n = 4: unambiguous
    cells = np.empty((1, 4), dtype=object)
    arrays = _square()
    for j in range(4):
        cells[0, j] = arrays["A"][j]
    cases = {"first": {key: getattr(rec, key) for key in ("speeds", "A", "B", "C", "D")},
             "cells": {**arrays, **{key: cells for key in ("A", "B", "C", "D")}}}
    for name, data in cases.items():
        savemat(tmp_path / f"{name}.mat", data)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            read_family_arrays(tmp_path / f"{name}.mat")


def test_mat_writer_says_pages_so_a_square_family_reads_back_without_warning(tmp_path):
    arrays = _square()
    rec = FamilyFile(**arrays, speed_unit="m/s", feedback="negative")
    toml = rec.write(tmp_path / "sq.toml", format="mat")
    assert 'layout = "pages"' in toml.read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_family_file(toml)
    for key in ("A", "B", "C", "D"):
        assert_array_equal(getattr(back, key), arrays[key])
    assert "layout =" not in rec.write(tmp_path / "sq2.toml", format="npz").read_text()


def test_layout_errors_name_the_fix(tmp_path):
    with pytest.raises(ConfigError, match="layout = 'cubes'; allowed: 'pages', 'speed_first'"):
        read_family_file(_toml(tmp_path / "f.toml", "absent.mat", layout='"cubes"'))
    with pytest.raises(ConfigError, match="an .npz data file is stored speed first"):
        read_family_file(_toml(tmp_path / "f.toml", "absent.npz", layout='"pages"'))
    rec = _record()
    savemat(tmp_path / "g.mat", {key: getattr(rec, key) for key in ("speeds", "A", "B", "C",
                                                                     "D")})
    with pytest.raises(DataError, match="layout = 'pages', but the arrays do not fit 5 speeds "
                                        "stacked as MATLAB pages.*they do fit 'speed_first'"):
        read_family_file(_toml(tmp_path / "f.toml", "g.mat", layout='"pages"'))


def test_names_with_blanks_are_stripped_in_the_data_file_and_the_problem_file(tmp_path):
    path = _npz(tmp_path, input_names=np.array([" elevon ", "gust"]),
                output_names=np.array(["q", "az ", "nz"]))
    path.write_text(path.read_text() + 'controls = ["elevon "]\nmeasurements = [" q", "az"]\n')
    rec = read_family_file(path)
    assert rec.input_names == ("elevon", "gust") and rec.output_names == ("q", "az", "nz")
    assert rec.controls == ("elevon",) and rec.measurements == ("q", "az")
