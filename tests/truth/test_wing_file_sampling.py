"""A wing file's records against their sampling: time stamps in milliseconds refused by the
modes' Nyquist check, a single-precision time channel accepted as uniform, ``records.dt``
that contradicts a time channel and channels that ``[records]`` leaves out warned about."""

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from casflutter.errors import ConfigError, DataError, DataWarning
from casflutter.truth import WingProblem, load_problem

K, DT = 400, 0.004


def _wing(tmp_path: Path, fmt: str = "npz", t=None, records: str = 'time = "t"',
          flap: bool = True, extra=None) -> Path:
    """A two-mode wing (2 and 5 Hz) with two records in ``fmt``; ``t`` the time channel
    (default uniform 4 ms, float64), ``extra`` further channels of the files."""
    rng = np.random.default_rng(0)
    t = np.arange(K) * DT if t is None else t
    for j in range(2):
        ch = {"t": t, "u1": rng.standard_normal(K) * (j == 0),
              "u2": rng.standard_normal(K) * (j == 1), "flap": rng.standard_normal(K),
              "Q1": rng.standard_normal(K), "Q2": rng.standard_normal(K), **(extra or {})}
        path = tmp_path / f"rec{j}.{fmt}"
        if fmt == "npz":
            np.savez(path, **ch)
        elif fmt == "mat":
            savemat(path, ch)
        else:
            names = list(ch)
            cells = [[f"{np.asarray(ch[c])[k]:.9g}" for c in names] for k in range(K)]
            path.write_text(",".join(names) + "\n" + "\n".join(map(",".join, cells)) + "\n")
    path = tmp_path / "wing.toml"
    path.write_text(f"""kind = "wing"
[modes]
frequencies_hz = [2.0, 5.0]
damping = [0.01, 0.01]
alpha = 1.0
[speed]
U_ref = 10.0
[sensors]
rows = [[1.0, 0.3]]
[records]
V0 = 1.0
files = ["rec0.{fmt}", "rec1.{fmt}"]
{records}
displacements = ["u1", "u2"]
{'flap = "flap"' if flap else ''}
forces = ["Q1", "Q2"]
""")
    return path


def _load(path: Path) -> WingProblem:
    return load_problem(str(path))


@pytest.mark.parametrize("fmt", ["npz", "mat", "csv"])
def test_time_in_milliseconds_is_refused_by_the_modes_nyquist(tmp_path, fmt):
    path = _wing(tmp_path, fmt, t=np.arange(K) * DT * 1e3)
    with pytest.raises(DataError) as info:
        _load(path)
    msg = str(info.value)
    for part in ("dt = 4 s", "Nyquist frequency 0.125 Hz", "5 Hz", "milliseconds",
                 "dt = 0.004 s", "records.dt = 0.004", "seconds"):
        assert part in msg, (part, msg)


def test_records_dt_in_milliseconds_is_refused_before_any_record_is_read(tmp_path):
    path = _wing(tmp_path, records="dt = 4.0")
    for f in tmp_path.glob("rec*.npz"):
        f.unlink()   # no record file: the refusal comes before they are read
    with pytest.raises(ConfigError, match=r"records\.dt.*Nyquist.*records\.dt = 0\.004"):
        _load(path)


def test_records_too_coarse_even_in_milliseconds_say_so(tmp_path):
    path = _wing(tmp_path, records="dt = 1000.0")   # 1 s in milliseconds: still too coarse
    with pytest.raises(ConfigError, match="cannot identify these modes"):
        _load(path)


def test_the_example_wing_loads_quietly():
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        w = load_problem("example_wing")
    f_max = w.structure.omega.max() / (2 * np.pi)
    assert w.records.dt == pytest.approx(0.004, rel=1e-12) and f_max == pytest.approx(38.09)
    assert f_max < 0.5 / w.records.dt


@pytest.mark.parametrize("fmt", ["npz", "mat", "csv"])
def test_a_single_precision_time_channel_is_uniform(tmp_path, fmt):
    t32 = (np.arange(K) * DT).astype(np.float32)
    steps = np.diff(t32.astype(float))
    assert not np.allclose(steps, np.median(steps), rtol=1e-6)   # what was refused
    w = _load(_wing(tmp_path, fmt, t=t32))
    assert w.records.dt == pytest.approx(DT, rel=1e-7)


@pytest.mark.parametrize("fmt", ["npz", "csv"])
def test_a_jittered_time_channel_is_refused_with_the_override(tmp_path, fmt):
    t = np.arange(K) * DT + np.random.default_rng(1).uniform(-1e-5, 1e-5, K)
    with pytest.raises(DataError) as info:
        _load(_wing(tmp_path, fmt, t=t))
    msg = str(info.value)
    assert "not uniformly sampled" in msg and "resample" in msg and "records.dt" in msg


def test_records_dt_contradicting_the_time_channel_is_warned_about_once(tmp_path):
    path = _wing(tmp_path, records="dt = 0.002")
    with pytest.warns(DataWarning) as rec:
        w = _load(path)
    msgs = [str(r.message) for r in rec if "contradicts" in str(r.message)]
    assert len(msgs) == 1 and "records.dt = 0.002" in msgs[0] and "'t'" in msgs[0]
    assert "steps by 0.004" in msgs[0] and "1 more" in msgs[0] and w.records.dt == 0.002


@pytest.mark.parametrize("scale", [1.0, 1e3])
def test_records_dt_agreeing_with_the_time_channel_is_quiet(tmp_path, scale):
    # the time channel in seconds, or in milliseconds (records.dt given for that reason)
    path = _wing(tmp_path, t=np.arange(K) * DT * scale, records="dt = 0.004")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        assert _load(path).records.dt == 0.004


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_a_channel_left_out_of_records_is_warned_about(tmp_path, fmt):
    path = _wing(tmp_path, fmt, flap=False, extra={"dt": np.array(DT)})
    with pytest.warns(DataWarning, match=r"channel\(s\) \['flap'\].*not used") as rec:
        w = _load(path)
    assert len(rec) == 1 and not w.records.has_v   # once for the files; the scalar dt is no channel
