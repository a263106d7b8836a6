"""The default run's ROM that follows the wing over speed, reported beside the paper's route.

Truth used: the seed wing's own flutter search and the control reversal of its flutter mode
on its own linearisation (flap behind the 40 Hz servo), both computed by the run from the
truth simulator, independently of the ROM.  Targets of issue 32: the ROM's flutter speed
within 2 % of the wing's (measured -1.4 %), its control reversal within 5 % (measured
+0.3 %); the paper's frozen loop of eq. 8 stays ``flutter`` (Table I, 10 % above the wing's).
"""

from __future__ import annotations

import pytest

from casflutter.pipeline import load_config, run


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
