"""Chirp records of a truth simulator (the paper's CFD runs on a stand-in)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError
from casflutter.truth import RecordSettings, TypicalSection, truth_records


@pytest.fixture(scope="module")
def ts_data():
    return truth_records(TypicalSection(), V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))


def test_records_one_per_input(ts_data):
    assert len(ts_data.records) == 3 and ts_data.has_v and ts_data.n_modes == 2
    # the first record moves mode 1 only
    assert np.all(ts_data.records[0].u[:, 1] == 0) and np.all(ts_data.records[0].v == 0)


def test_band_above_nyquist_is_refused():
    with pytest.raises(ConfigError, match="Nyquist"):
        truth_records(TypicalSection(), V0=2.0, dt=0.5, duration=100.0, band=(0.01, 2.0))


def test_coupling_delay_shifts_the_forces_by_whole_samples(ts_data):
    """The CFD coupling delay: the forces of the delayed records are the undelayed ones one
    sample later, the motion unchanged."""
    s = RecordSettings(V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))
    late = truth_records(TypicalSection(), s, coupling_delay=1)
    for a, b in zip(ts_data.records, late.records):
        assert_allclose(b.u, a.u, rtol=0, atol=0)
        assert_allclose(b.y[1:], a.y[:-1], rtol=0, atol=0)
        assert np.all(b.y[0] == 0)


@pytest.mark.parametrize("changes, words", [
    ({"dt": -0.1}, "dt = -0.1: must be > 0"),
    ({"duration": 0.2}, "at least 200"),
    ({"taper": 0.7}, "taper"),
    ({"coupling_delay": -1}, "coupling_delay"),
    ({"band": ("a", 1.0)}, "band"),
])
def test_bad_settings_name_the_field(changes, words):
    with pytest.raises(ConfigError, match=words):
        RecordSettings(**changes)
