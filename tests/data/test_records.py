"""Records and loaders (CSV, NPZ, MATLAB)."""

import numpy as np
import pytest
from scipy.io import savemat

from casflutter.data import IOData, chirp_excitation
from casflutter.errors import ConfigError, DataError


@pytest.fixture
def arrays():
    rng = np.random.default_rng(0)
    return rng.normal(size=(50, 2)), rng.normal(size=(50, 2)), rng.normal(size=50)


def test_npz_round_trip(tmp_path, arrays):
    y, u, v = arrays
    d = IOData.from_arrays(y=y, u=u, v=v, dt=0.01)
    d.to_npz(tmp_path / "d.npz")
    back = IOData.from_npz(tmp_path / "d.npz")
    assert back.dt == 0.01
    np.testing.assert_array_equal(back.records[0].y, y)
    np.testing.assert_array_equal(back.records[0].v, v)


def test_csv(tmp_path, arrays):
    y, u, v = arrays
    t = np.arange(50) * 0.02
    table = np.column_stack([t, y, u, v])
    path = tmp_path / "rec.csv"
    np.savetxt(path, table, delimiter=",", header="t,F1,F2,q1,q2,flap", comments="")
    d = IOData.from_csv(path, y=["F1", "F2"], u=["q1", "q2"], v="flap")
    assert d.dt == pytest.approx(0.02)
    assert d.output_names == ("F1", "F2") and d.v_name == "flap"
    np.testing.assert_allclose(d.records[0].u, u)
    with pytest.raises(DataError, match=r"column\(s\) \['F3'\] not in the header"):
        IOData.from_csv(path, y=["F3"], u=["q1"])
    t[10] += 0.005
    np.savetxt(path, np.column_stack([t, y, u, v]), delimiter=",",
               header="t,F1,F2,q1,q2,flap", comments="")
    with pytest.raises(DataError, match="not uniformly sampled"):
        IOData.from_csv(path, y=["F1", "F2"], u=["q1", "q2"])


def test_mat_channels_by_samples(tmp_path, arrays):
    y, _, v = arrays
    path = tmp_path / "rec.mat"
    savemat(path, {"Acc": y.T, "Force": v[None, :], "Fs": 400.0})
    d = IOData.from_mat(path, y="Acc", v="Force", fs="Fs")
    assert d.dt == pytest.approx(1 / 400)
    np.testing.assert_allclose(d.records[0].y, y)
    assert not d.has_u and d.has_v
    with pytest.raises(DataError, match="no variable 'Nope'"):
        IOData.from_mat(path, y="Nope", v="Force", fs="Fs")


def test_bad_dt_and_records(arrays):
    y, u, v = arrays
    with pytest.raises(DataError, match="positive"):
        IOData.from_arrays(y=y, u=u, dt=0.0)
    from casflutter.data import Record
    with pytest.raises(DataError, match="different inputs"):
        IOData((Record(y, u, None), Record(y, None, v)), 0.1)


def test_chirp_band_and_decorrelation():
    dt = 0.005
    x = chirp_excitation(4000, dt, 3, band=(1.0, 30.0), seed=1)
    assert x.shape == (4000, 3)
    f = np.fft.rfftfreq(4000, dt)
    P = np.abs(np.fft.rfft(x[:, 0])) ** 2
    inside = P[(f >= 0.5) & (f <= 35)].sum() / P.sum()
    assert inside > 0.98
    corr = np.corrcoef(x.T)
    assert np.abs(corr[np.triu_indices(3, 1)]).max() < 0.3
    np.testing.assert_array_equal(x, chirp_excitation(4000, dt, 3, band=(1.0, 30.0), seed=1))
    with pytest.raises(ConfigError, match="Nyquist"):
        chirp_excitation(100, 0.1, 1, band=(0.1, 6.0))
