"""``verify_family``: certified interval, absolute and robust flutter speeds, margins per loop
and per speed, closed-loop crossings; the same keys for a gridded family and for the seed
wing's own loop families (its truth's linearisation, a ROM loop kept in an ``.npz``)."""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stdout

import control
import numpy as np
import pytest

from casflutter._outputs import print_json
from casflutter._resources import problems_dir
from casflutter.aeroelastic import GriddedFamily, TruthLoop, load_rom_loop
from casflutter.errors import ConfigError
from casflutter.truth import SeedWing
from casflutter.verify import verify_family

from family_helpers import SERVO, WITNESSES, abscissa, random_family, small_controller

KEYS = {"stable_interval", "absolute_flutter_speed", "robust_flutter_speed",
        "robust_flutter_reason", "margins", "crossings", "speed_unit", "frequency_unit"}


@pytest.fixture(scope="module")
def case():
    fam = random_family(4)
    K = small_controller(np.random.default_rng(104), 2, 2, 2, gain=0.3, with_d=False)
    return fam, K, verify_family(fam, K)


def _pm_python_control(fam, K, V, j):
    """Phase margin of output loop j at V: python-control only (feedback, indexing and the
    polynomial stability_margins)."""
    P = fam.control_plant(V)
    L = -fam.feedback_sign * (P * K)
    E = np.eye(L.ninputs)
    E[j, j] = 0.0
    Lj = control.feedback(L, control.ss([], [], [], E))[j, j]
    pm = np.atleast_1d(control.stability_margins(Lj, returnall=True)[1])
    return float(np.min(np.abs(pm))) if pm.size else math.inf


def test_absolute_and_robust_flutter_speeds(case):
    fam, K, r = case
    lo, hi = fam.speed_range
    assert r.stable_interval[0] == lo and r.interval.stable_at_start
    assert r.absolute_flutter_speed == r.interval.loss
    assert abscissa(fam, K, r.absolute_flutter_speed * (1 + 1e-6)) > 0
    assert abscissa(fam, K, r.absolute_flutter_speed * (1 - 1e-6)) < 0
    assert lo < r.robust_flutter_speed < r.absolute_flutter_speed
    # the robust flutter speed: output y0's phase margin falls through 45 degrees there
    assert "output 'y0': phase margin" in r.robust_reason
    V = r.robust_flutter_speed
    assert _pm_python_control(fam, K, V * (1 - 1e-5), 0) > 45.0
    assert _pm_python_control(fam, K, V * (1 + 1e-5), 0) < 45.0
    assert r.covers(lo, 0.8) and not r.covers(lo, 0.9)
    assert r.robust_over(lo, 0.8) and not r.robust_over(lo, 0.85)


def test_margin_tables_and_crossings(case):
    fam, K, r = case
    for t, names in ((r.inputs, fam.signals.controls), (r.outputs, fam.signals.measurements)):
        assert t.loops == names and t.speeds.tolist() == fam.speeds.tolist()
        assert t.gain_db.shape == t.phase_deg.shape == (fam.speeds.size, len(names))
        stable = np.array([abscissa(fam, K, V) < 0 for V in fam.speeds])
        assert (t.stable == stable).all()
        assert np.isnan(t.gain_db[~stable]).all() and not np.isnan(t.gain_db[stable]).any()
    first = r.crossings[0]
    assert first.direction == "destabilizing" and first.kind == "flutter"
    assert first.speed == pytest.approx(r.absolute_flutter_speed, rel=1e-8)
    assert first.omega == pytest.approx(r.absolute_flutter_omega, rel=1e-6)
    # the closed-loop eigenvalues kept for the damping figure
    assert r.branch_eigenvalues.shape[0] == r.branch_speeds.size


def test_the_json_is_strict_and_says_what_it_holds(case):
    _, _, r = case
    out = io.StringIO()
    with redirect_stdout(out):
        print_json(r.to_dict())
    doc = json.loads(out.getvalue())
    assert KEYS <= set(doc)
    assert doc["stable_interval"]["lower_included"] is True
    assert doc["margins"]["input"]["loops"]["u0"]["gain_margin_db"]
    assert "stable_interval" in r.format() and "robust_flutter_speed" in r.format()


def test_the_feedback_convention_is_a_sign():
    neg = random_family(2, feedback="negative")
    A, B, C, D = neg.arrays
    pos = GriddedFamily(neg.speeds, A, B, C, D, neg.signals, feedback="positive")
    K = small_controller(np.random.default_rng(102), 2, 2, 2, gain=0.02, with_d=False)
    a, b = verify_family(neg, K), verify_family(pos, -K)
    assert a.absolute_flutter_speed == pytest.approx(b.absolute_flutter_speed, rel=1e-12)
    np.testing.assert_allclose(a.inputs.gain_db, b.inputs.gain_db, rtol=1e-9)
    # and the file's "feedback" key overrides the family's
    c = verify_family(pos, K, feedback="negative")
    assert c.absolute_flutter_speed == pytest.approx(a.absolute_flutter_speed, rel=1e-12)


def test_the_seed_wing_loop_families_give_the_same_keys():
    """The truth's linearisation with its servo (order-4 witness) and the default run's ROM
    loop behind the same servo (its order-4 'low' controller, certified on (0, 1.9033) by
    its design), in the speed index."""
    truth = TruthLoop(SeedWing(), SERVO)
    w = verify_family(truth, WITNESSES / "truth_interval_controller_order4.json",
                      speed_range=(0.0, 3.0),
                      margin_speeds=13)
    assert w.stable_interval[0] == 0.0 and not w.interval.stable_at_start
    assert w.absolute_flutter_speed == pytest.approx(2.41256, abs=1e-5)
    rom = load_rom_loop(problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz")[0]
    r = verify_family(rom.with_servo(SERVO), WITNESSES / "rom_order4_low_controller.json",
                      speed_range=(0.0, 2.4),
                      margin_speeds=13)
    assert r.absolute_flutter_speed == pytest.approx(1.9033, abs=1e-4)
    for res in (w, r):
        doc = res.to_dict()
        assert KEYS <= set(doc) and doc["speed_unit"] == "speed index"
        assert res.robust_flutter_speed <= res.absolute_flutter_speed


def test_bad_requests_are_refused_before_any_work():
    truth = TruthLoop(SeedWing(), SERVO)
    K = WITNESSES / "truth_interval_controller_order4.json"
    with pytest.raises(ConfigError, match="not a finite interval; pass speed_range"):
        verify_family(truth, K)
    with pytest.raises(ConfigError, match="margins"):
        verify_family(truth, K, speed_range=(0, 3), margins=(-1, 45))
    with pytest.raises(ConfigError, match="margin_speeds"):
        verify_family(truth, K, speed_range=(0, 3), margin_speeds=[1.0, 4.0])


def test_disk_margins_are_inside_the_classical_ones():
    """The multi-loop disk margin covers gain and phase changes in every channel at once,
    so its gain and phase margins are at most each loop's classical ones."""
    fam = random_family(3, with_d=True)
    K = small_controller(np.random.default_rng(103), 2, 2, 2, gain=3.0, with_d=True)
    r = verify_family(fam, K, disk=True, margin_speeds=[0.3, 0.6],
                      speed_range=(0.1, 0.7))
    for t in (r.inputs, r.outputs):
        assert t.disk_alpha is not None and np.all(t.disk_alpha > 0)
        ok = t.stable
        assert np.all(t.disk_gain_db[ok] <= np.min(t.gain_db[ok], axis=1) * (1 + 1e-6))
        assert np.all(t.disk_phase_deg[ok] <= np.min(t.phase_deg[ok], axis=1) * (1 + 1e-6))
    assert "disk margin" in r.robust_reason


def test_the_figures_name_the_loops_and_mark_the_speeds(case):
    from casflutter.report import plot_closed_loop_damping, plot_margins_vs_speed

    _, _, r = case
    fig = plot_margins_vs_speed(r)
    labels = {t.get_text() for ax in fig.axes if ax.get_legend()
              for t in ax.get_legend().get_texts()}
    for name in ("u0", "u1", "y0", "y1"):      # each loop, with or without a crossover
        assert name in labels or f"{name} (no crossover)" in labels
    assert any(lab.startswith("robust flutter speed") for lab in labels)
    assert any(lab.startswith("absolute flutter speed") for lab in labels)
    assert fig.axes[2].get_xlabel() == "speed [q]"
    fig = plot_closed_loop_damping(r)
    assert "certified stable on [0.1, " in fig.axes[0].get_title()
