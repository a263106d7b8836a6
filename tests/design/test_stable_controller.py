"""A controller required to be stable itself (``stable_controller``, systune's controller-pole
requirement), checked against the parity interlacing property (Youla, Bongiorno & Lu 1974): a
plant is stabilised by some stable controller exactly when between any two of its real zeros
in the closed right half-plane (infinity counted) lies an even number of its real poles.

* ``(s - 1) / ((s - 2)(s + 3))``: the pole 2 lies alone between the zeros 1 and infinity, so
  every controller that stabilises it is unstable.
* ``(s - 3) / ((s - 1)(s - 2))``: no pole lies between the zeros 3 and infinity, so a stable
  controller exists.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from casflutter._settings import settings_as
from casflutter.aeroelastic import GriddedFamily
from casflutter.design import MultiSpeedSettings, SynthesisOptions, design_over_speeds, synthesize
from casflutter.errors import SynthesisError
from casflutter.pipeline import load_config, multispeed_settings

NOT_STRONGLY = ([1.0, -1.0], np.polymul([1.0, -2.0], [1.0, 3.0]))
STRONGLY = ([1.0, -3.0], np.polymul([1.0, -1.0], [1.0, -2.0]))


def _family(num, den) -> GriddedFamily:
    """The plant ``num / den`` at every speed of (0, 1)."""
    G = control.ss(control.tf(num, den))
    n = G.nstates
    speeds = np.array([0.0, 1.0])
    return GriddedFamily(speeds, np.repeat(np.asarray(G.A)[None], 2, 0),
                         np.repeat(np.asarray(G.B)[None], 2, 0),
                         np.repeat(np.asarray(G.C)[None], 2, 0), np.zeros((2, 1, 1)),
                         name=f"{n}-state plant")


def _settings(stable: bool) -> MultiSpeedSettings:
    return MultiSpeedSettings(hinf_speeds=0, random_starts=2, full_order=False,
                              stable_controller=stable)


def _loop_abscissa(fam, K, V: float) -> float:
    """Independent check: the loop closed by python-control in the family's convention."""
    return float(np.max(control.feedback(fam.plant(V), K, sign=fam.feedback_sign)
                        .poles().real))


@pytest.mark.parametrize("order", [1, 2])
def test_a_plant_no_stable_controller_stabilises_is_refused_with_the_reason(order):
    fam = _family(*NOT_STRONGLY)
    free = design_over_speeds(fam, (0.0, 1.0), order, seed=0, settings=_settings(False))
    # the design without the requirement holds it, necessarily with an unstable controller
    assert free.held
    assert np.max(free.controller.poles().real) > 0
    assert _loop_abscissa(fam, free.controller, 0.5) <= -free.decay * (1 - 1e-6)
    with pytest.raises(SynthesisError, match="parity interlacing"):
        design_over_speeds(fam, (0.0, 1.0), order, seed=0, settings=_settings(True))


@pytest.mark.parametrize("order", [1, 2])
def test_a_strongly_stabilisable_plant_gets_a_stable_controller(order):
    fam = _family(*STRONGLY)
    d = design_over_speeds(fam, (0.0, 1.0), order, seed=0, settings=_settings(True))
    assert d.held
    # the controller decays at the loop's rate, and the loop it closes too
    assert np.max(d.controller.poles().real) <= -d.decay * (1 - 1e-6)
    for V in (0.0, 0.5, 1.0):
        assert _loop_abscissa(fam, d.controller, V) <= -d.decay * (1 - 1e-6)


def test_the_h_infinity_synthesis_keeps_the_requirement():
    """The single-plant synthesis (the paper's route): its disturbance enters at the plant's
    input and its error is the measurement.  Without the requirement it stabilises the plant
    (with an unstable controller, as it must); with it, it finds none and says why."""
    G = control.ss(control.tf(*NOT_STRONGLY))
    B, C = np.asarray(G.B), np.asarray(G.C)
    P = control.ss(G.A, np.hstack([B, B]), np.vstack([C, C]), np.zeros((2, 2)))
    opts = SynthesisOptions(max_outer=20)
    free = synthesize(P, 1, 1, 2, starts=3, seed=0, options=opts)
    assert np.max(free.controller.poles().real) > 0
    loop = control.feedback(G, free.controller, sign=1)
    assert np.max(loop.poles().real) < 0
    with pytest.raises(SynthesisError, match="parity interlacing"):
        synthesize(P, 1, 1, 2, starts=3, seed=0,
                   options=SynthesisOptions(max_outer=20, stable_controller=True))


def test_a_run_configuration_asks_both_design_routes_for_it():
    """``[controller] stable_controller`` reaches the multi-speed design's continuation and
    its H∞ phase, and the paper's synthesis (the run's settings of each)."""
    cfg = load_config(updates={"controller.stable_controller": True})
    settings = multispeed_settings(cfg, "sensitivity")
    assert settings.stable_controller and settings.synthesis.stable_controller
    assert settings_as(cfg.controller, SynthesisOptions).stable_controller
    assert not multispeed_settings(load_config(), "sensitivity").stable_controller
