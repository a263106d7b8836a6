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


def test_levels_and_channel_amplitudes_cover_an_amplitude_range():
    """Per-channel amplitudes scale each record's motion, the levels repeat the chirp at
    each amplitude in turn; with a linear truth the forces scale with the motion exactly."""
    s = RecordSettings(V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))
    ts = TypicalSection()
    ref = truth_records(ts, s)
    amps = (0.5, 2.0, 0.1)
    stepped = truth_records(ts, s, amplitude=amps, levels=(0.2, 1.0))
    K = ref.records[0].n_samples
    assert stepped.records[0].n_samples == 2 * K
    assert stepped.meta["amplitude"] == amps and stepped.meta["levels"] == (0.2, 1.0)
    for j, (a, b) in enumerate(zip(ref.records, stepped.records)):
        w_ref = a.u[:, j] if j < 2 else a.v
        w = b.u[:, j] if j < 2 else b.v
        # the second chirp of the record is the single chirp at the channel's amplitude
        # (0.01 by default), the first the same at a fifth of it
        assert_allclose(w[K:], amps[j] / 0.01 * w_ref, rtol=1e-9, atol=1e-12 * abs(amps[j]))
        assert_allclose(w[:K], 0.2 * amps[j] / 0.01 * w_ref, rtol=1e-9, atol=1e-12 * abs(amps[j]))
        # the forces of the second chirp are the single chirp's scaled, up to what the end of
        # the first leaves in the BDF2 stencil and the aerodynamic lags (it ends at rest)
        err = np.abs(b.y[K:] - amps[j] / 0.01 * a.y).max(axis=1) / np.abs(b.y[K:]).max()
        assert err[20:].max() < 1e-3 and err[K // 2:].max() < 1e-6


@pytest.mark.parametrize("changes, words", [
    ({"amplitude": (0.1, -0.2)}, "every amplitude must be > 0"),
    ({"amplitude": 0.0}, "amplitude = 0.0: must be > 0"),
    ({"levels": ()}, "levels"),
    ({"levels": (1.0, 0.0)}, "every factor must be > 0"),
    ({"dt": -0.1}, "dt = -0.1: must be > 0"),
    ({"duration": 0.2}, "at least 200"),
    ({"taper": 0.7}, "taper"),
    ({"coupling_delay": -1}, "coupling_delay"),
    ({"band": ("a", 1.0)}, "band"),
])
def test_bad_settings_name_the_field(changes, words):
    with pytest.raises(ConfigError, match=words):
        RecordSettings(**changes)


def test_channel_amplitudes_must_match_the_channels():
    with pytest.raises(ConfigError, match="amplitude has 2 entries for 3 channels"):
        truth_records(TypicalSection(), V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0),
                      amplitude=(0.1, 0.2))
