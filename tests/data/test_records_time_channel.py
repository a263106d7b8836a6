"""The time column of a CSV record (:meth:`IOData.from_csv`): uniform up to the rounding of
its stamps (a single-precision time column is uniform), a non-uniform one refused with the
``dt`` that overrides it, a ``dt`` that contradicts it warned about; a channel named twice
among the outputs and inputs refused; a MAT file without a sampling time says how to give
one on the command line."""

import warnings

import numpy as np
import pytest
from scipy.io import savemat

from casflutter.data import IOData
from casflutter.errors import DataError, DataWarning

K, DT = 500, 0.004


def _csv(path, t, fmt="{:.9g}"):
    rng = np.random.default_rng(0)
    cols = {"t": t, "u": rng.standard_normal(K), "y": rng.standard_normal(K)}
    lines = ["t,u,y"] + [",".join(fmt.format(cols[c][k]) for c in cols) for k in range(K)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_single_precision_time_column_is_uniform(tmp_path):
    t32 = (np.arange(K) * DT + 3.0).astype(np.float32)   # written in full: 9 digits
    d = IOData.from_csv(_csv(tmp_path / "r.csv", t32), y=["y"], u=["u"])
    assert d.dt == pytest.approx(DT, rel=1e-7)


def test_a_time_column_rounded_in_writing_is_uniform(tmp_path):
    # 1/3 ms sampling written with 6 significant digits (steps 0.0003 or 0.0004 at t = 10):
    # the text's own rounding, averaged out by the least-squares step
    t = np.arange(K) / 3000.0 + 10.0
    d = IOData.from_csv(_csv(tmp_path / "r.csv", t, "{:.6g}"), y=["y"], u=["u"])
    assert d.dt == pytest.approx(1 / 3000.0, rel=1e-4)


def test_a_non_uniform_time_column_names_the_override(tmp_path):
    t = np.arange(K) * DT + np.random.default_rng(1).uniform(-1e-5, 1e-5, K)
    with pytest.raises(DataError) as info:
        IOData.from_csv(_csv(tmp_path / "r.csv", t), y=["y"], u=["u"])
    msg = str(info.value)
    assert "not uniformly sampled" in msg and "resample" in msg
    assert "dt = 0.004" in msg and "--dt" in msg and "records.dt" in msg and "overrides" in msg


def test_resolution_follows_the_stored_type():
    from casflutter.data._sampling import stamp_resolution, uniform_step

    t = np.array([0.0, 8.0])
    assert stamp_resolution(t, np.float32) == pytest.approx(np.spacing(np.float32(8.0)))
    assert stamp_resolution(t, np.float64) == pytest.approx(np.spacing(8.0))
    assert stamp_resolution(t, np.int64) == 0.0
    # exact float64 steps keep their median (no change for data that passed before)
    t64 = np.arange(K) * DT
    assert uniform_step(t64, stamp_resolution(t64, np.float64)) == float(np.median(np.diff(t64)))
    jitter = t64 + 1e-5 * (np.arange(K) % 2)
    assert uniform_step(jitter, stamp_resolution(jitter, np.float32)) is None


def test_dt_contradicting_the_time_column_is_warned_about(tmp_path):
    path = _csv(tmp_path / "r.csv", np.arange(K) * DT)
    with pytest.warns(DataWarning, match=r"dt = 0\.002 s, contradicts the time channel 't'"):
        d = IOData.from_csv(path, y=["y"], u=["u"], dt=0.002)
    assert d.dt == 0.002
    for dt, t in [(DT, np.arange(K) * DT), (DT, np.arange(K) * DT * 1e3)]:   # s, ms: agree
        with warnings.catch_warnings():
            warnings.simplefilter("error", DataWarning)
            IOData.from_csv(_csv(tmp_path / "r.csv", t), y=["y"], u=["u"], dt=dt)


def test_a_time_column_of_another_name_is_checked_too(tmp_path):
    path = _csv(tmp_path / "r.csv", np.arange(K) * DT)
    path.write_text(path.read_text().replace("t,u,y", "Time,u,y", 1))
    with pytest.warns(DataWarning, match="'Time'") as rec:
        IOData.from_csv(path, y=["y"], u=["u"], dt=0.01)
    assert not any("not used" in str(r.message) for r in rec)


def test_a_channel_named_twice_is_refused(tmp_path):
    path = _csv(tmp_path / "r.csv", np.arange(K) * DT)
    with pytest.raises(DataError, match=r"\['u', 'y'\] named more than once.*name each "
                                        "channel once"):
        IOData.from_csv(path, y=["y", "y"], u=["u", "u"])


def test_a_mat_file_without_a_sampling_time_says_how_to_give_one(tmp_path):
    path = tmp_path / "r.mat"
    savemat(path, {"y": np.ones((50, 1)), "u": np.ones((50, 1))})
    with pytest.raises(DataError) as info:
        IOData.from_mat(path, y="y", u="u")
    msg = str(info.value)
    assert "--dt" in msg and "--fs" in msg and "variable" in msg
