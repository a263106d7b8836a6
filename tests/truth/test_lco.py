"""The truth's own LCO (the ``lco`` stage of a run): continued until it stops growing."""

import numpy as np
import pytest

from casflutter.data import analyze_response
from casflutter.truth import load_problem, truth_lco


def test_slowly_growing_lco_is_followed_to_its_amplitude():
    # 5 % above the seed wing's own flutter speed (1.085) the LCO needs ~30 s to saturate:
    # the last 10-s window of one 40-s simulation is the independent reference
    wing = load_problem("seed_wing", [])
    V, dt = 1.139, 0.002
    res = truth_lco(wing, V, 10.0, 1, 0.01, dt=dt)
    assert res.kind == "lco"
    assert res.t_start > 0.0
    t_all = np.arange(0.0, res.t_start + 10.0, dt)
    sim = wing.simulate(t_all, wing.displaced_state(1, 0.01), V)
    zm = sim.uddot @ wing.modal_structure().Hs.T
    last = t_all >= t_all[-1] - res.timepts[-1] - 0.5 * dt
    ref = analyze_response(t_all[last] - t_all[last][0], zm[last])
    assert ref.kind == "lco"
    assert res.amplitude == pytest.approx(ref.amplitude, rel=1e-3)
    assert res.freq_hz == pytest.approx(ref.frequency_hz, rel=1e-3)
