"""Records used not as meant are said before the work: a CSV column no channel names (the
fit would go on without an input), and chirp records whose band and length miss the
problem's lowest mode (settings in seconds applied to a problem in nondimensional time)."""

import warnings

import numpy as np
import pytest

import casflutter as cf
from casflutter.cli import main
from casflutter.data import IOData
from casflutter.errors import DataWarning


@pytest.fixture()
def csv_with_a_flap(tmp_path):
    rng = np.random.default_rng(0)
    n = 400
    t = np.arange(n) * 0.01
    u, v = rng.standard_normal(n), rng.standard_normal(n)
    y = 0.5 * u + 0.3 * np.roll(v, 1)
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([t, y, u, v]), delimiter=",", header="t,F1,q1,flap",
               comments="")
    return path


def test_a_csv_column_no_channel_names_is_warned_about(csv_with_a_flap):
    with pytest.warns(DataWarning, match=r"column\(s\) \['flap'\] are not used") as rec:
        d = IOData.from_csv(csv_with_a_flap, y=["F1"], u=["q1"])
    assert "name it (u=, v=" in str(rec[0].message) and not d.has_v
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)      # every column named: no word
        assert IOData.from_csv(csv_with_a_flap, y=["F1"], u=["q1"], v="flap").has_v
        IOData.from_csv(csv_with_a_flap, y=["F1"], u=["q1"], v="flap", dt=0.01)  # t unused


def test_identify_says_it_before_the_fit(csv_with_a_flap, capsys):
    main(["identify", str(csv_with_a_flap), "--y", "F1", "--u", "q1", "--orders",
          "1,0,0,0,1,1"])
    err = capsys.readouterr().err
    assert "casflutter: warning:" in err and "['flap'] are not used" in err


def test_seconds_applied_to_the_typical_sections_time_are_warned_about():
    """The seed wing's record settings (dt 2 ms, 8 s, 0.2-60 Hz) on the typical section,
    whose time is 1/omega_theta: its plunge mode (0.063 cycles per unit) lies below the band
    and a record holds half a period."""
    ts = cf.load_problem("typical_section")
    with pytest.warns(DataWarning, match=r"plunge.*does not hold it.*not seconds"):
        cf.truth_records(ts, V0=1.8)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        cf.truth_records(ts, V0=1.8, dt=0.1, duration=300.0, band=(0.002, 1.0))
        cf.truth_records(cf.load_problem("seed_wing"), V0=0.69)
