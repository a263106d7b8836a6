"""A subcritical Hopf point whose branch never gains stability: the motion just above
flutter is simulated and said.  Two ends of it, each checked by the truth's own simulator
(not the collocation):

- the NATA rig without its dampers (c_h = c_alpha = 0): the branch from the Hopf point is
  unstable all the way down, yet the rig settles on a stable 5-degree limit cycle above
  flutter, on a branch of its own (shown by an independent time integration and shooting
  before this was built); its amplitude and frequency at 13 m/s are checked against a
  release from 0.01 rad at 2 %;
- the typical section with a softening cubic pitch spring: the motion grows without bound,
  which the simulator shows too.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from casflutter.cli import main
from casflutter.data import analyze_response
from casflutter.lco import LCOSettings, lco_branch
from casflutter.truth import load_problem

from ._helpers import measure
from .test_nata_lco import _release


@pytest.fixture(scope="module")
def undamped_nata():
    truth = load_problem("nata", ["c_h=0", "c_alpha=0"])
    return truth, lco_branch(truth, (8.0, 14.0))


def test_the_settled_cycle_and_its_branch(undamped_nata):
    truth, br = undamped_nata
    assert br.kind == "subcritical" and not any(br.stable)
    s = br.settled
    assert s is not None and s.kind == "lco" and br.hopf.V < s.V < 14.0
    assert "settles on a stable limit cycle" in s.note and "does not reach" in s.note
    V = np.array([p.V for p in s.points])
    assert V.min() == pytest.approx(8.0, abs=0.6) and V.max() == pytest.approx(14.0, abs=0.6)
    assert all(p.stable for p in s.points)
    order = np.argsort(V)
    pitch = np.interp(13.0, V[order], [s.points[i].amplitude["pitch"] for i in order])
    freq = np.interp(13.0, V[order], [s.points[i].freq_hz for i in order])
    t = np.arange(0.0, 120.0, 0.002)
    sim = truth.simulate(t, _release(truth, 0.01), 13.0)
    a, f = measure(t, sim.u @ truth.modal_structure().Hs[1])
    assert a == pytest.approx(pitch, rel=0.02) and f == pytest.approx(freq, rel=0.02)
    doc = br.to_dict()["settled"]
    assert doc["kind"] == "lco" and len(doc["branch"]) == len(s.points)


def test_a_softening_spring_grows_without_bound():
    truth = load_problem("typical_section", ["kappa2=-3"])
    br = lco_branch(truth, (1.5, 2.6), LCOSettings(max_points=40))
    assert br.kind == "subcritical" and not any(br.stable)
    s = br.settled
    assert s is not None and s.kind == "divergence" and not s.points
    assert "grows without bound" in s.note
    t = np.arange(0.0, 300.0, 0.05)
    sim = truth.simulate(t, br.points[0].state, s.V)
    assert analyze_response(t, sim.u).kind == "divergence" or not np.all(np.isfinite(sim.u))


def test_the_command_line_says_it(capsys):
    args = ["lco", "typical_section", "--set", "kappa2=-3", "--vrange", "1.5", "2.6",
            "--max-points", "40"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "no stable cycle on this branch" in out and "grows without bound" in out
    assert main(args + ["--json"]) == 0
    assert json.loads(capsys.readouterr().out)["settled"]["kind"] == "divergence"
