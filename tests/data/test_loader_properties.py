"""Property-based tests: random, truncated and corrupted files, random shapes, dtypes and
sampling times fed to every loader.  The only exceptions allowed out are casflutter's own
(:class:`~casflutter.errors.CasflutterError`); whatever loads is a consistent record set.

Examples are derandomised (the same ones on every run, no example database), so the suite
is deterministic.
"""

from __future__ import annotations

import io
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from casflutter.data import IOData
from casflutter.errors import CasflutterError

SETTINGS = settings(max_examples=120, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


def _consistent(d: IOData) -> None:
    """What every successful load guarantees."""
    assert isinstance(d, IOData) and d.dt > 0 and np.isfinite(d.dt)
    for r in d.records:
        assert r.y.ndim == 2 and r.y.dtype == float and r.y.shape[0] >= 1
        assert np.all(np.isfinite(r.y))
        assert r.u is not None or r.v is not None
        if r.u is not None:
            assert r.u.shape == r.y.shape and r.u.dtype == float and np.all(np.isfinite(r.u))
        if r.v is not None:
            assert r.v.shape == (r.y.shape[0],) and np.all(np.isfinite(r.v))


def _load(kind: str, path: Path) -> IOData:
    if kind == "npz":
        return IOData.from_npz(path)
    if kind == "csv":
        return IOData.from_csv(path, y=["y1", "y2"], u=["u1", "u2"])
    return IOData.from_mat(path, y="y", u="u", fs="Fs")


def _only_ours(kind: str, data: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"f.{kind}"
        path.write_bytes(data)
        try:
            d = _load(kind, path)
        except CasflutterError:
            return
        _consistent(d)


def _valid_bytes(kind: str) -> bytes:
    rng = np.random.default_rng(0)
    y, u = rng.standard_normal((30, 2)), rng.standard_normal((30, 2))
    buf = io.BytesIO()
    if kind == "npz":
        np.savez(buf, y=y, u=u, dt=0.01)
    elif kind == "mat":
        scipy.io.savemat(buf, {"y": y, "u": u, "Fs": 100.0})
    else:
        t = 0.01 * np.arange(30)
        buf.write(b"t,y1,y2,u1,u2\n")
        for row in np.column_stack([t, y, u]):
            buf.write((",".join(f"{x:.6g}" for x in row) + "\n").encode())
    return buf.getvalue()


VALID = {k: _valid_bytes(k) for k in ("npz", "mat", "csv")}


@pytest.mark.parametrize("kind", ["npz", "mat", "csv"])
def test_the_valid_files_load(kind):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"f.{kind}"
        path.write_bytes(VALID[kind])
        d = _load(kind, path)
    _consistent(d)
    assert d.n_samples == 30 and d.dt == pytest.approx(0.01)


@pytest.mark.parametrize("kind", ["npz", "mat", "csv"])
@SETTINGS
@given(data=st.binary(max_size=3000))
def test_random_bytes(kind, data):
    _only_ours(kind, data)


@pytest.mark.parametrize("kind", ["npz", "mat", "csv"])
@SETTINGS
@given(cut=st.floats(0.0, 1.0))
def test_truncated_files(kind, cut):
    blob = VALID[kind]
    _only_ours(kind, blob[: int(cut * len(blob))])


@pytest.mark.parametrize("kind", ["npz", "mat", "csv"])
@SETTINGS
@given(flips=st.lists(st.tuples(st.floats(0.0, 1.0, exclude_max=True), st.integers(0, 255)),
                      min_size=1, max_size=6))
def test_corrupted_bytes(kind, flips):
    blob = bytearray(VALID[kind])
    for where, value in flips:
        blob[int(where * len(blob))] = value
    _only_ours(kind, bytes(blob))


# ------------------------------------------------------------------- shapes and dtypes

_DTYPES = st.sampled_from([np.float64, np.float32, np.int64, np.bool_, np.complex128,
                           np.dtype("<U3"), np.dtype("datetime64[s]")])


def _arrays():
    return st.one_of(
        st.none(),
        _DTYPES.flatmap(lambda dt: hnp.arrays(dt, hnp.array_shapes(min_dims=0, max_dims=3,
                                                                   min_side=0, max_side=5))),
        st.lists(st.lists(st.floats(allow_nan=False, width=32), max_size=3), max_size=4),
    )


_DT = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 3),
                st.text(max_size=3), st.booleans(), st.none(), st.complex_numbers(max_magnitude=2),
                hnp.arrays(np.float64, hnp.array_shapes(min_dims=0, max_dims=2, max_side=2)))


@SETTINGS
@given(y=_arrays(), u=_arrays(), v=_arrays(), dt=_DT)
def test_from_arrays_shapes_dtypes_and_dt(y, u, v, dt):
    try:
        d = IOData.from_arrays(y=y, u=u, v=v, dt=dt)
    except CasflutterError:
        return
    _consistent(d)
    assert d.dt == float(np.asarray(dt).reshape(()))


@SETTINGS
@given(y=_arrays(), u=_arrays(), dt=_DT)
def test_npz_of_random_arrays(y, u, dt):
    buf = io.BytesIO()
    try:
        arrays = {k: np.asarray(a) for k, a in (("y", y), ("u", u), ("dt", dt)) if a is not None}
        np.savez(buf, **arrays)
    except (ValueError, TypeError):  # NumPy itself cannot write it (ragged): nothing to load
        return
    _only_ours("npz", buf.getvalue())


_MAT_VALUES = st.one_of(
    hnp.arrays(st.sampled_from([np.float64, np.int32, np.uint8, np.bool_, np.complex128]),
               hnp.array_shapes(min_dims=1, max_dims=3, min_side=0, max_side=5)),
    st.text(max_size=5), st.floats(allow_nan=True, allow_infinity=True),
    st.dictionaries(st.sampled_from(["a", "b"]), st.floats(-1, 1), max_size=2),
    st.lists(st.one_of(st.text(max_size=2), st.floats(-1, 1)), min_size=1, max_size=3),
)


@SETTINGS
@given(variables=st.dictionaries(st.sampled_from(["y", "u", "Fs", "x"]), _MAT_VALUES,
                                 max_size=4))
def test_mat_of_random_variables(variables):
    buf = io.BytesIO()
    try:
        scipy.io.savemat(buf, variables)
    except (ValueError, TypeError):  # SciPy itself cannot write it: nothing to load
        return
    _only_ours("mat", buf.getvalue())


_CELL = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                  st.integers(-5, 5).map(str), st.sampled_from(["", "x", "nan", " 1", "1e400"]))


@SETTINGS
@given(header=st.lists(st.sampled_from(["t", "y1", "y2", "u1", "u2", "z", ""]), max_size=6),
       rows=st.lists(st.lists(_CELL, max_size=6), max_size=6))
def test_csv_of_random_tables(header, rows):
    text = ",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in rows)
    _only_ours("csv", text.encode())


# ------------------------------------------------ MAT v5 layouts that crash scipy's parser

def _fs_file() -> bytes:
    buf = io.BytesIO()
    scipy.io.savemat(buf, {"y": np.ones((30, 2)), "u": np.ones((30, 2)), "Fs": 100.0})
    return buf.getvalue()


def _flip(blob: bytes, where: int, value: int) -> bytes:
    b = bytearray(blob)
    b[where] = value
    return bytes(b)


@pytest.mark.parametrize("case", ["small element claims 171 bytes", "complex flag, no imaginary"])
def test_layouts_that_crash_scipy_are_refused_in_a_subprocess(tmp_path, case):
    """One-byte corruptions of a valid file that scipy's compiled MAT v5 parser trusts: the
    type word of Fs's data tag turned into a 171-byte "small" element (scipy.io.loadmat 1.17
    dies with SIGSEGV on it), and the complex bit set in Fs's array flags with no imaginary
    part (scipy reads past the variable; with other flips beside it, the fuzz runs crashed).
    The layout check refuses both with a DataError; run in a child process so that a
    regression crashes the child, not the test run."""
    blob = _fs_file()
    end = len(blob)  # Fs is the last variable: flags at end-48, its data tag at end-16
    bad = _flip(blob, end - 15, 171) if case.startswith("small") else _flip(blob, end - 47, 0x08)
    path = tmp_path / "bad.mat"
    path.write_bytes(bad)
    code = ("import sys\nfrom casflutter.data import IOData\nfrom casflutter.errors import "
            "DataError\ntry:\n    IOData.from_mat(sys.argv[1], y='y', u='u')\n"
            "except DataError as e:\n    print('DataError:', e)\n")
    proc = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, (proc.returncode, proc.stderr[-500:])
    assert "DataError:" in proc.stdout and "corrupt MAT v5 layout" in proc.stdout
