"""The seed wing's ROM reproduces the amplitude of the truth's LCO (issue 12, item 4): each
model a little above its own flutter point, the ROM's in the sampled-data loop it runs in,
the truth's in its continuous dynamics.  The ROM is the one of the shipped study (the
paper's records and orders); the truth's LCO is an independent long simulation."""

import numpy as np
import pytest

from casflutter.pipeline import default_config_path, load_config, run


@pytest.fixture(scope="module")
def lco_stage():
    cfg = load_config(default_config_path(), updates={"lco.branch_points": 18},
                      stages=["lco"])
    return run(cfg, quiet=True, write=False)


@pytest.mark.slow
def test_rom_lco_amplitude_within_25_percent_of_the_truths(lco_stage):
    lco = lco_stage.lco
    assert lco.rom.sensors.kind == "lco" and lco.truth.kind == "lco"
    f = lco_stage.config.lco.speed_factor
    assert lco.V == pytest.approx(f * lco.V_hopf_loop)
    assert lco.truth.V == pytest.approx(f * lco_stage.flutter_truth.Vf)
    rom, truth = np.asarray(lco.rom.sensors.amplitude), np.asarray(lco.truth.amplitude)
    assert np.all(np.abs(rom / truth - 1) <= 0.25), (rom, truth)
    # the LCO frequencies agree as well (the paper's 8.5 Hz against its wing)
    assert lco.rom.sensors.frequency_hz == pytest.approx(lco.truth.freq_hz, rel=0.05)


@pytest.mark.slow
def test_branches_pass_through_the_simulated_cycles(lco_stage):
    """Both continuations (the report's bifurcation diagrams) start at the flutter points the
    stage used and pass through the amplitudes of its simulations at the same speeds."""
    lco = lco_stage.lco
    for branch, V, amp in ((lco.rom_branch, lco.V, lco.rom.sensors.amplitude),
                           (lco.truth_branch, lco.truth.V, lco.truth.amplitude)):
        assert branch is not None and branch.hopf.kind == "supercritical"
        Vs = np.array([p.V for p in branch.points])
        assert Vs.max() > V, "the branch stops below the simulated speed"
        for name, a in zip(branch.outputs[-2:], amp):
            along = np.interp(V, Vs, branch.amplitude(name))
            assert along == pytest.approx(a, rel=0.03), name
    assert lco.rom_branch.hopf.V == pytest.approx(lco.V_hopf_loop, rel=1e-6)
    assert lco.truth_branch.hopf.V == pytest.approx(lco_stage.flutter_truth.Vf, rel=1e-4)


def _following_errors(lco_stage, factor: float) -> np.ndarray:
    (c,) = [c for c in lco_stage.lco.speed_following if c.speed_factor == factor]
    assert c.V == pytest.approx(factor * lco_stage.flutter_truth.Vf)
    assert c.truth.kind == "lco" and c.rom.sensors.kind == "lco"
    return np.asarray(c.amplitude_error_percent)


@pytest.mark.slow
def test_the_speed_following_roms_lco_within_15_percent_at_1_05_vf(lco_stage):
    """Issue 32 item 1: the ROM that follows the wing over speed, simulated at the truth's own
    speeds (1.05 times the truth's flutter speed), gives the truth's LCO amplitude within
    15 % on every sensor."""
    errors = _following_errors(lco_stage, 1.05)
    assert np.all(np.abs(errors) < 15.0), errors


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="issue 32 item 1 at 1.2 Vf: the ROM's polynomial "
                   "nonlinearity, fitted on chirps some 40 times smaller than this LCO, gives "
                   "an LCO 38-48 % smaller than the truth's")
def test_the_speed_following_roms_lco_within_15_percent_at_1_2_vf(lco_stage):
    errors = _following_errors(lco_stage, 1.2)
    assert np.all(np.abs(errors) < 15.0), errors
