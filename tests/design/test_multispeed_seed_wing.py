"""The multi-speed design's H∞ phase on the seed wing's ROM that follows the wing over speed
(``problems/seed_wing/multispeed.toml``: one common-denominator ROM identified at V0 = 0.69,
its aerodynamic lags scaled by V / V0, flap behind the 40 Hz servo; 39 states).

Truth used: the verification layer's certificate of the stable interval on the family
(:func:`casflutter.verify.verify_family`, which shares no code with the design) and the exact
H∞ norms of the loop's sensitivities computed by the verification layer
(:func:`casflutter.verify.hinf_norm`) on plants formed here with python-control's
``feedback``.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from casflutter.design import MultiSpeedSettings, design_over_speeds
from casflutter.pipeline import config_path, design_family, load_config
from casflutter.verify import hinf_norm, verify_family

pytestmark = pytest.mark.slow

INTERVAL = (0.05, 1.45)


@pytest.fixture(scope="module")
def family():
    return design_family(load_config(config_path("seed_wing", "multispeed")))


def test_the_sensitivity_phase_delivers_a_certified_controller(family):
    """The sensitivity objective on the seed wing's speed-following ROM, order 4 over
    (0.05, 1.45): the interval is held and certified by the verification layer, the H∞
    phase delivers (it does not fall back to the held controller), and the γ it reports
    bounds the exact output and input sensitivities at its speeds."""
    s = MultiSpeedSettings(full_order=False, random_starts=1, sensitivity=True,
                           rate_weight=0.003, rate_bandwidth=251.3)
    d = design_over_speeds(family, INTERVAL, 4, settings=s, seed=0)
    assert d.held and d.synthesis is not None
    check = verify_family(family, d.controller, speed_range=(0.0, 2.4))
    assert check.covers(*INTERVAL)
    # the reported gamma bounds the worst sensitivity over the H∞ speeds (1e-4: the
    # norm's tolerance), and is well below the ~600 of a held controller on this family
    sig, sign = family.signals, family.feedback_sign
    worst = 0.0
    for V in d.hinf_speeds:
        G = family.plant(V)
        meas, ctrl = sig.output_index(), sig.input_index()
        G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                       np.asarray(G.D)[np.ix_(meas, ctrl)])
        for loop in (G * d.controller, d.controller * G):
            eye = control.ss([], [], [], np.eye(loop.noutputs))
            worst = max(worst, hinf_norm(control.feedback(eye, loop, sign=sign)).gamma)
    assert worst <= d.gamma * (1 + 1e-4)
    assert d.gamma < 300.0
