"""Bad files and arrays give a DataError that names the file or signal, the problem and the
fix -- never a raw NumPy/SciPy/zipfile exception, never silently changed data."""

from __future__ import annotations

import os
import zipfile

import numpy as np
import pytest
import scipy.io

from casflutter.data import IOData, Record
from casflutter.errors import DataError

K = 40


def _good(n=2, k=K, seed=0):
    rng = np.random.default_rng(seed)
    return rng.standard_normal((k, n)), rng.standard_normal((k, n))


def _v73_file(path):
    """The layout MATLAB writes for ``save -v7.3``: a 128-byte MAT header (version 0x0200,
    'IM') in a 512-byte user block, then the HDF5 signature."""
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 " \
           b"HDF5 schema 1.00 ."
    head = text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM"
    path.write_bytes(head.ljust(512, b"\x00") + b"\x89HDF\r\n\x1a\n" + bytes(range(256)))


# --------------------------------------------------------------------------------- npz

def _npz_cases(tmp):
    y, u = _good()
    cases = {}
    (tmp / "empty.npz").write_bytes(b"")
    cases["empty.npz"] = "empty file"
    (tmp / "random.npz").write_bytes(np.random.default_rng(1).bytes(300))
    cases["random.npz"] = "not an .npz archive"
    with zipfile.ZipFile(tmp / "zip.npz", "w") as z:
        z.writestr("notes.txt", "not arrays")
    cases["zip.npz"] = "zip archive without .npy arrays"
    np.save(tmp / "single.npy", y)
    os.replace(tmp / "single.npy", tmp / "single.npz")
    cases["single.npz"] = "single .npy array"
    (tmp / "folder.npz").mkdir()
    cases["folder.npz"] = "is a folder"
    np.savez(tmp / "emptydt.npz", y=y, u=u, dt=np.array([]))
    cases["emptydt.npz"] = "'dt' must hold one number"
    np.savez(tmp / "textdt.npz", y=y, u=u, dt=np.array("0.1"))
    cases["textdt.npz"] = "'dt' is not a real number"
    np.savez(tmp / "zerodt.npz", y=y, u=u, dt=0.0)
    cases["zerodt.npz"] = "positive finite number"
    np.savez(tmp / "text.npz", y=np.array([["a", "b"]] * K), u=u, dt=0.1)
    cases["text.npz"] = "signal y holds text"
    np.savez(tmp / "u3.npz", y=y, u=u[:, :, None], dt=0.1)
    cases["u3.npz"] = r"u must be \(samples, modal inputs\), got shape \(40, 2, 1\)"
    np.savez(tmp / "complex.npz", y=y + 1j, u=u, dt=0.1)
    cases["complex.npz"] = "signal y is complex"
    np.savez(tmp / "objects.npz", y=np.array([1, "a", None] * K, dtype=object), u=u, dt=0.1)
    cases["objects.npz"] = "object \\(pickled\\) arrays"
    good = tmp / "good.npz"
    np.savez(good, y=y, u=u, dt=0.1)
    (tmp / "truncated.npz").write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    cases["truncated.npz"] = "cannot be read as an .npz archive"
    np.savez(tmp / "empty_y.npz", y=np.zeros((0, 2)), u=np.zeros((0, 2)), dt=0.1)
    cases["empty_y.npz"] = "has no samples"
    return cases


def test_bad_npz_files_name_the_file_the_problem_and_the_fix(tmp_path):
    for name, match in _npz_cases(tmp_path).items():
        with pytest.raises(DataError, match=match) as err:
            IOData.from_npz(tmp_path / name)
        assert str(tmp_path / name) in str(err.value), name
    with pytest.raises(DataError, match="file not found"):
        IOData.from_npz(tmp_path / "missing.npz")


# --------------------------------------------------------------------------------- csv

@pytest.mark.parametrize("text, match", [
    ("t,y1,u1\n", "no data rows"),
    ("", "empty file"),
    ("t,y1,u1\n0,1,2\n0.1,1\n", "line 3 has 2 fields but the header has 3"),
    ("t,y1,u1\n0,1,2\n0.1,x,2\n", r"line 3, column 'y1': 'x' is not a number"),
    ("t,y1,u1\n0,1,2\n0.1,,2\n", r"line 3, column 'y1': '' is not a number"),
    ("t,y1,u1\n0,1,2\n", "one data row"),
    ("t,y1,u1\n0.2,1,2\n0.1,1,2\n0.0,1,2\n", "not increasing"),
    ("t,y1,y1,u1\n0,1,1,2\n0.1,1,1,2\n", "more than once"),
    ("t,y1,u1\n0,1,2\n0.1,nan,2\n", "NaN/inf"),
])
def test_bad_csv_files(tmp_path, text, match):
    f = tmp_path / "r.csv"
    f.write_text(text)
    with pytest.raises(DataError, match=match) as err:
        IOData.from_csv(f, y=["y1"], u=["u1"])
    assert str(f) in str(err.value)


def test_csv_binary_folder_and_bom(tmp_path):
    f = tmp_path / "b.csv"
    f.write_bytes(b"t,y1,u1\n\xff\xfe\x00\x01\n")
    with pytest.raises(DataError, match="not a UTF-8 text file"):
        IOData.from_csv(f, y=["y1"], u=["u1"])
    f.write_bytes(b"t,y1,u1\n0,1\x002\n")
    with pytest.raises(DataError, match=str(f)):
        IOData.from_csv(f, y=["y1"], u=["u1"])
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(DataError, match="is a folder"):
        IOData.from_csv(tmp_path / "d.csv", y=["y1"], u=["u1"])
    with pytest.raises(DataError, match="no output column"):
        IOData.from_csv(f, y=[], u=["u1"])
    # a byte-order mark (Excel's "CSV UTF-8") does not hide the first column's name
    f.write_bytes("\ufefft,y1,u1\n0,1,2\n0.1,3,4\n".encode("utf-8"))
    d = IOData.from_csv(f, y=["y1"], u=["u1"])
    assert d.dt == pytest.approx(0.1) and d.records[0].y[:, 0].tolist() == [1.0, 3.0]


# --------------------------------------------------------------------------------- mat

def _mat_cases(tmp):
    rng = np.random.default_rng(2)
    y, u = rng.standard_normal((K, 1)), rng.standard_normal((K, 1))
    cases = {}
    scipy.io.savemat(tmp / "text.mat", {"y": "hello", "u": u, "Fs": 10.0})
    cases["text.mat"] = "variable 'y' holds text"
    cell = np.empty(2, dtype=object)
    cell[0], cell[1] = np.zeros(3), "a"
    scipy.io.savemat(tmp / "cell.mat", {"y": cell, "u": u, "Fs": 10.0})
    cases["cell.mat"] = "variable 'y' is a cell array"
    scipy.io.savemat(tmp / "struct.mat", {"y": {"data": y}, "u": u, "Fs": 10.0})
    cases["struct.mat"] = r"variable 'y' is a struct \(fields \['data'\]\)"
    scipy.io.savemat(tmp / "nothing.mat", {})
    cases["nothing.mat"] = "holds no variables"
    scipy.io.savemat(tmp / "fs0.mat", {"y": y, "u": u, "Fs": 0.0})
    cases["fs0.mat"] = r"sampling frequency 'Fs' = 0"
    scipy.io.savemat(tmp / "fsvec.mat", {"y": y, "u": u, "Fs": np.array([10.0, 20.0])})
    cases["fsvec.mat"] = "must hold one number"
    scipy.io.savemat(tmp / "complex.mat", {"y": y + 1j, "u": u, "Fs": 10.0})
    cases["complex.mat"] = "variable 'y' is complex"
    scipy.io.savemat(tmp / "cube.mat", {"y": np.zeros((K, 2, 2)), "u": u, "Fs": 10.0})
    cases["cube.mat"] = "is 3-D"
    scipy.io.savemat(tmp / "emptyvar.mat", {"y": np.zeros((0, 0)), "u": u, "Fs": 10.0})
    cases["emptyvar.mat"] = "variable 'y' is empty"
    _v73_file(tmp / "v73.mat")
    cases["v73.mat"] = r"MATLAB v7.3 \(HDF5\) file.*'-v7'"
    (tmp / "empty.mat").write_bytes(b"")
    cases["empty.mat"] = "empty file"
    (tmp / "random.mat").write_bytes(np.random.default_rng(3).bytes(700))
    cases["random.mat"] = "cannot be read as a MAT-file"
    return cases


def test_bad_mat_files_name_the_file_the_problem_and_the_fix(tmp_path):
    for name, match in _mat_cases(tmp_path).items():
        with pytest.raises(DataError, match=match) as err:
            IOData.from_mat(tmp_path / name, y="y", u="u", fs="Fs")
        assert str(tmp_path / name) in str(err.value), name


# ------------------------------------------------------------------------ arrays (API)

def test_arrays_that_would_change_meaning_are_refused():
    y, u = _good()
    with pytest.raises(DataError, match="signal y is not a rectangular array"):
        IOData.from_arrays(y=[[1.0, 2.0], [3.0]], u=u[:2], dt=0.1)
    with pytest.raises(DataError, match=r"u must be \(samples, modal inputs\).*\(40, 2, 1\)"):
        IOData.from_arrays(y=y, u=u[:, :, None], dt=0.1)
    with pytest.raises(DataError, match="signal u is complex.*np.real"):
        IOData.from_arrays(y=y, u=u * (1 + 1e-3j), dt=0.1)
    with pytest.raises(DataError, match="signal v holds text"):
        IOData.from_arrays(y=y[:, :1], v=np.array(["1"] * K), dt=0.1)
    with pytest.raises(DataError, match="signal y has no samples"):
        IOData.from_arrays(y=np.zeros((0, 2)), u=np.zeros((0, 2)), dt=0.1)
    with pytest.raises(DataError, match="at least one output"):
        Record(np.zeros((K, 0)), np.zeros((K, 0)))
    with pytest.raises(DataError, match="single number"):
        Record(1.0, 1.0)
    with pytest.raises(DataError, match="dates or durations"):
        Record(np.arange(K).astype("datetime64[s]"), u[:, 0])
    with pytest.raises(DataError, match="Python objects"):
        Record(np.array([1.0, "a"] * 20, dtype=object), u[:, 0])
    for dt in ("0.1", True, 1j, np.array([0.1, 0.2]), None):
        with pytest.raises(DataError, match="dt="):
            IOData.from_arrays(y=y, u=u, dt=dt)
    with pytest.raises(DataError, match="records must be Record objects"):
        IOData((y,), 0.1)
    # integer and boolean arrays are numbers: accepted as floats
    d = IOData.from_arrays(y=np.arange(K)[:, None], u=np.ones((K, 1), dtype=bool), dt=1)
    assert d.records[0].y.dtype == float and d.records[0].u.dtype == float


def test_window_to_nothing_is_a_data_error():
    y, u = _good()
    d = IOData.from_arrays(y=y, u=u, dt=0.1)
    with pytest.raises(DataError, match="no samples"):
        d.window(K, K)
