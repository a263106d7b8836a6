"""summary.json's ``lco`` record (and its speed-following comparisons) gives a frequency and amplitudes only for a cycle.

A rig whose HWL ROM diverges above flutter printed ``freq_hz = 0.053`` and amplitudes of
9e11 as its "LCO" (probe of a user's nata_wagner rig).  Truth used: the response analysis
of two records made here, a growing sine (a divergence) and a sine of constant amplitude
(a cycle), through :func:`casflutter.data.analyze_response`.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from casflutter.data import analyze_response
from casflutter.lco import LcoComparison
from casflutter.pipeline import RunResult


def _analysis(growth: float):
    t = np.arange(0.0, 20.0, 0.002)
    y = np.exp(growth * t) * np.sin(2 * np.pi * 2.5 * t)
    return analyze_response(t, y[:, None])


def _summary(rom, truth):
    sim = SimpleNamespace(sensors=rom, modes=rom)
    tr = SimpleNamespace(V=1.2, freq_hz=truth.frequency_hz, amplitude=truth.amplitude,
                         kind=truth.kind)
    lco = SimpleNamespace(rom=sim, truth=tr, V=1.1, V_hopf_exact_order=1.0, V_hopf_loop=1.0,
                          truth_branch=None, rom_branch=None, speed_following=())
    return RunResult._lco_summary(SimpleNamespace(lco=lco))


def test_a_divergence_has_no_lco_frequency_or_amplitude():
    growing, cycle = _analysis(0.8), _analysis(0.0)
    assert (growing.kind, cycle.kind) == ("divergence", "lco")
    s = _summary(growing, cycle)
    assert s["kind"] == "divergence" and s["freq_hz"] is None and s["amplitude"] is None
    # the truth's cycle keeps its numbers: 2.5 Hz, unit amplitude (2 % of the sampling)
    assert s["truth_kind"] == "lco"
    assert abs(s["truth_freq_hz"] - 2.5) < 0.05 and abs(s["truth_amplitude"][0] - 1.0) < 0.02
    s = _summary(cycle, growing)
    assert s["freq_hz"] is not None and s["truth_freq_hz"] is None
    assert s["truth_amplitude"] is None


def test_a_speed_following_comparison_gives_a_divergence_no_amplitude_or_frequency():
    growing, cycle = _analysis(0.8), _analysis(0.0)
    truth = SimpleNamespace(kind=cycle.kind, amplitude=cycle.amplitude,
                            freq_hz=cycle.frequency_hz)
    rec = LcoComparison(1.05, 1.1, SimpleNamespace(sensors=growing), truth).record()
    assert rec["rom_kind"] == "divergence"
    assert rec["rom_amplitude"] is None and rec["rom_freq_hz"] is None
    assert rec["amplitude_error_percent"] == [None]
    assert abs(rec["truth_freq_hz"] - 2.5) < 0.05 and abs(rec["truth_amplitude"][0] - 1) < 0.02
    # two cycles: the error is the amplitudes' ratio, 0 % for the same record
    rec = LcoComparison(1.05, 1.1, SimpleNamespace(sensors=cycle), truth).record()
    assert abs(rec["rom_freq_hz"] - 2.5) < 0.05 and abs(rec["amplitude_error_percent"][0]) < 1e-9
