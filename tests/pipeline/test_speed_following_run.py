"""The default run's ROM that follows the wing over speed, reported beside the paper's route.

Truth used: the seed wing's own flutter search and the control reversal of its flutter mode
on its own linearisation (flap behind the 40 Hz servo), both computed by the run from the
truth simulator, independently of the ROM.  Targets of issue 32: the ROM's flutter speed
within 2 % of the wing's (measured -1.4 %), its control reversal within 5 % (measured
+0.3 %); the paper's frozen loop of eq. 8 stays ``flutter`` (Table I, 10 % above the wing's).
"""

from __future__ import annotations

import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.pipeline import config_path, load_config, run


@pytest.fixture(scope="module")
def summary():
    return run(load_config(updates={"stages": []}), quiet=True).summary()


def test_the_speed_following_flutter_is_the_wings(summary):
    wing, following = summary["flutter_truth"]["V"], summary["flutter_convective"]["V"]
    assert following == pytest.approx(wing, rel=0.02)
    assert summary["flutter_convective"]["mode"] == summary["flutter_truth"]["mode"]
    # the paper's frozen route, kept for Table I, is unconservative by about 10 %
    assert summary["flutter"]["V"] / wing - 1 > 0.08


def test_the_control_reversal_follows_the_wings(summary):
    rev = summary["control_reversal_V"]
    assert rev["speed_following"] == pytest.approx(rev["truth"], rel=0.05)
    assert rev["rom"] / rev["truth"] - 1 > 0.2          # eq. 8 puts it 30 % late


def test_the_multispeed_design_is_made_on_the_loop_that_follows_the_wing(
        closed_loop_abscissa, caplog):
    """``controller.method = "multispeed"`` on the paper's (HWL) run designs on the
    speed-following ROM with the flap behind the servo, not on the frozen loop of eq. 8.
    Checked independently: python-control closes the controller on that loop (no code shared
    with the design) and finds it decaying at 15 speeds of the interval, which reaches 34 %
    above the wing's flutter speed; the run certifies the interval on it and on the wing
    itself (to 1 %, the ROM's flutter-speed error with room; measured 1.457 and 1.450).
    The run warns for each model exactly where the verification's robust flutter speed lies
    inside the interval held (measured 0.70 on both: the phase margin at the flap)."""
    cfg = load_config(config_path("seed_wing", "run_paper"), updates={
        "stages": ["controller"], "controller.method": "multispeed", "controller.order": 3,
        "controller.interval": [0.05, 1.45], "controller.hinf_speeds": 0,
        "controller.random_starts": 0})
    with caplog.at_level("WARNING", logger="casflutter.pipeline"):
        res = run(cfg, quiet=True, write=False)
    loop = res.model.speed_following.system.with_servo(cfg.controller.servo_omega)
    assert np.allclose(res.controlled_rom.state_matrix(1.3), loop.state_matrix(1.3))
    assert res.design.held and res.controller.nstates == 3
    for V in np.linspace(0.05, 1.45, 15):
        assert closed_loop_abscissa(loop, res.controller, V) < 0, V
    c = res.summary()["controller"]
    assert c["method"] == "multispeed" and c["held"] is True
    assert c["stable_interval"][0] == 0.0 and c["stable_interval"][1] >= 1.45
    assert c["truth_stable_interval"][0] == 0.0
    assert c["truth_stable_interval"][1] >= 0.99 * 1.45
    warned = [r.getMessage() for r in caplog.records if "not robustly so" in r.getMessage()]
    for model, key, held in (("design", "robust_flutter_speed", "stable_interval"),
                             ("truth", "truth_robust_flutter_speed", "truth_stable_interval")):
        robust = c[key]
        inside = robust is not None and robust < min(1.45, c[held][1])
        said = robust is not None and any(
            f"on {model} " in w and f"hold only to {robust:.5g}" in w for w in warned)
        assert said == inside, (model, robust)
    # where the design model's certificate carries over: its response from the flap to the
    # accelerometers follows the wing's near the flutter mode (30-100 rad/s; measured at most
    # 0.19, at the mode's own frequency) and departs from it below 6 rad/s at the top speed
    # (measured 2.05 at V = 2.5, docs/theory.rst's table); the summary reports the band's worst
    mismatch = res.control.mismatch["truth"]
    np.testing.assert_allclose(mismatch.speeds, [0.5, 1.0, 1.5, 2.0, 2.5])
    assert np.all(mismatch.worst(30.0, 100.0) < 0.25)
    assert mismatch.worst(0.0, 6.0)[-1] > 1.0
    assert c["model_error"]["truth"]["worst_relative_error"] == mismatch.worst().tolist()


def test_the_multispeed_design_needs_the_records_delay_in_the_rom():
    """The speed-following ROM removes the records' coupling delay from the HWL ROM's input
    delay: a ROM with less delay than the records is refused before any work."""
    with pytest.raises(ConfigError, match=r"input delay r = 0: identify with r >= 1"):
        load_config(updates={"controller.method": "multispeed",
                             "rom.orders": [3, 1, 1, 0, 2, 2]})
