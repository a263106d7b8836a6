"""verify_controller end to end on a toy wing whose LFT (eq. 14) is built in the test:
the exact V interval must match a direct eigenvalue sweep over V of ΣAE(V) closed with K
(python-control feedback, no LFT), and the small-gain intervals must lie inside it."""

from __future__ import annotations

import json
import math

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError, DimensionError
from casflutter.verify import (feedback_stability_interval, stability_interval,
                               verify_controller)
from verify_helpers import dense_peak, lqg_controller, wing, wing_lft, wing_plant_at

VF = 1.0   # just above the open-loop flutter speed index (≈ 0.996)


def _closed_abscissa(w, K, V):
    return np.max(np.linalg.eigvals(control.feedback(wing_plant_at(w, V), K, sign=1).A).real)


@pytest.mark.parametrize("sensor,Dk", [("state", np.zeros((1, 2))),
                                       ("accel", np.array([[0.05, -0.03]]))])
def test_exact_interval_matches_direct_sweep_over_V(sensor, Dk):
    w = wing(sensor)
    assert _closed_abscissa(w, np.zeros((1, 2)), VF) > 0        # open loop flutters at VF
    K = lqg_controller(wing_plant_at(w, VF), Dk)
    r = verify_controller(wing_lft(w, VF), K, nmeas=2, ncon=1, Vf=VF, n_delta=2)
    assert r.stable and r.exact is not None
    lo, hi = r.exact_V
    # independent sweep: stable set around VF on a grid of step h
    h = 2e-3
    V = VF
    while V < 10 and _closed_abscissa(w, K, V + h) < 0:
        V += h
    assert abs(V - hi) <= h + 1e-9
    V = VF
    while V - h > 0 and _closed_abscissa(w, K, V - h) < 0:
        V -= h
    if lo == 0.0:
        assert V - h <= 0                 # stable down to V = 0, as the paper reports
    else:
        assert abs(V - lo) <= h + 1e-9
    # sharp: stable just inside the upper end, unstable just outside
    assert _closed_abscissa(w, K, hi * (1 - 1e-7)) < 0 < _closed_abscissa(w, K, hi * (1 + 1e-7))
    # ΔV ↔ V (eq. 10)
    assert_allclose(hi, math.sqrt(VF**2 + r.exact.upper), rtol=1e-12)
    # small gain is a certificate: inside the exact interval; wf->zf only is wider
    assert r.hinf_delta.gamma <= r.hinf.gamma * (1 + 1e-9)
    for sg in (r.small_gain_V, r.small_gain_V_delta):
        assert lo <= sg[0] and sg[1] <= hi
    assert r.small_gain_V_delta[0] <= r.small_gain_V[0]
    assert r.small_gain_V_delta[1] >= r.small_gain_V[1]
    assert_allclose(r.small_gain_dV[1], 1 / r.hinf.gamma, rtol=1e-12)
    # the norm itself against an independent sweep of the closed loop
    assert_allclose(r.hinf.gamma, dense_peak(r.closed_loop)[0], rtol=1e-6)


def test_rational_case_is_reported_and_differs_from_affine_guess():
    w = wing("accel")
    K = lqg_controller(wing_plant_at(w, VF), np.array([[0.05, -0.03]]))
    r = verify_controller(wing_lft(w, VF), K, 2, 1, Vf=VF, n_delta=2)
    D = np.asarray(r.closed_loop.D)[:2, :2]
    assert np.any(D != 0)
    assert any("rational" in n for n in r.notes)
    # ignoring D (affine guess) would give a different, wrong interval
    A, B, C = (np.asarray(M) for M in (r.closed_loop.A, r.closed_loop.B, r.closed_loop.C))
    guess = stability_interval(A, -B[:, :2] @ C[:2])
    assert abs(guess.upper - r.exact.upper) > 1e-3


def test_feedback_interval_equals_affine_interval_when_D_is_zero():
    w = wing("state")
    K = lqg_controller(wing_plant_at(w, VF), np.zeros((1, 2)))
    r = verify_controller(wing_lft(w, VF), K, 2, 1, Vf=VF, n_delta=2)
    A, B, C = (np.asarray(M) for M in (r.closed_loop.A, r.closed_loop.B, r.closed_loop.C))
    aff = stability_interval(A, -B[:, :2] @ C[:2])
    fb = feedback_stability_interval(A, B[:, :2], C[:2])
    assert_allclose([aff.lower, aff.upper], [fb.lower, fb.upper], rtol=1e-9)
    assert_allclose([r.exact.lower, r.exact.upper], [fb.lower, fb.upper], rtol=1e-12)


def test_random_rational_feedback_family_matches_sweep():
    rng = np.random.default_rng(31)
    n, k = 6, 2
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, k)), rng.standard_normal((k, n))
    D = 0.5 * rng.standard_normal((k, k))
    si = feedback_stability_interval(A, B, C, D)

    def ok(d):
        M = np.eye(k) + d * D
        if np.linalg.cond(M) > 1e8:
            return False
        return np.max(np.linalg.eigvals(A - B @ np.linalg.solve(M, d * C)).real) < 0

    h = 1e-3
    for sign, end in ((1, si.upper), (-1, si.lower)):
        d = 0.0
        while abs(d) < 30 and ok(d + sign * h):
            d += sign * h
        if math.isinf(end):
            assert abs(d) >= 30
        else:
            assert abs(d - end) <= h + 1e-9


def test_unstable_closed_loop_is_reported_not_hidden():
    w = wing("state")
    r = verify_controller(wing_lft(w, 1.1), np.zeros((1, 2)), 2, 1, Vf=1.1, n_delta=2)
    assert not r.stable and r.gamma == math.inf and r.spectral_abscissa > 0
    assert r.exact is None and r.small_gain_V is None
    assert any("unstable" in n for n in r.notes)
    assert "UNSTABLE" in r.format()


def test_report_text_and_json():
    w = wing("state")
    K = lqg_controller(wing_plant_at(w, VF), np.zeros((1, 2)))
    r = verify_controller(wing_lft(w, VF), K, 2, 1, Vf=VF, delta_channel=2, method="scipy")
    text = str(r)
    for key in ("gamma =", "small gain (paper", "wf->zf only", "exact stability", "V in ("):
        assert key in text
    d = json.loads(json.dumps(r.to_dict()))
    assert d["hinf"]["method"] == "scipy" and d["n_delta"] == 2
    assert_allclose(d["exact_V"][1], r.exact_V[1])
    # without Vf: poles and norm only
    r2 = verify_controller(wing_lft(w, VF), K, 2, 1)
    assert r2.exact is None and r2.Vf is None and r2.stable


def test_argument_errors():
    w = wing("state")
    P = wing_lft(w, VF)
    with pytest.raises(ConfigError, match="both Vf and n_delta"):
        verify_controller(P, np.zeros((1, 2)), 2, 1, Vf=1.0)
    with pytest.raises(DimensionError, match="n_delta=9"):
        verify_controller(P, lqg_controller(wing_plant_at(w, VF), np.zeros((1, 2))), 2, 1,
                          Vf=1.0, n_delta=9)
    with pytest.raises(DimensionError, match="controller K has 2 outputs x 2 inputs"):
        verify_controller(P, np.zeros((2, 2)), 2, 1)


def test_report_without_slycot_matches_report_with_it(monkeypatch):
    """"auto" falls back to the scipy branch when slycot is absent; same numbers."""
    import sys

    w = wing("accel")
    K = lqg_controller(wing_plant_at(w, VF), np.array([[0.05, -0.03]]))
    with_default = verify_controller(wing_lft(w, VF), K, 2, 1, Vf=VF, n_delta=2)
    monkeypatch.setitem(sys.modules, "slycot", None)
    without = verify_controller(wing_lft(w, VF), K, 2, 1, Vf=VF, n_delta=2)
    assert without.hinf.method == "scipy" and without.hinf_delta.method == "scipy"
    assert_allclose(without.gamma, with_default.gamma, rtol=1e-8)
    assert_allclose(without.small_gain_V_delta, with_default.small_gain_V_delta, rtol=1e-8)
    assert without.exact_V == with_default.exact_V


@pytest.mark.parametrize("sensor,Dk", [("state", np.zeros((1, 2))),
                                       ("accel", np.array([[0.05, -0.03]]))])
def test_speed_sweep_poles_equal_direct_assembly_and_bracket_exact_interval(sensor, Dk):
    from types import SimpleNamespace

    from casflutter.verify import speed_sweep, verify_lft

    w = wing(sensor)
    K = lqg_controller(wing_plant_at(w, VF), Dk)
    P = wing_lft(w, VF)
    Vgrid = np.linspace(0.0, 3.0, 301)
    sw = speed_sweep(P, K, 2, 1, Vf=VF, n_delta=2, V=Vgrid)
    for i in (0, 57, 150, 299):
        direct = np.linalg.eigvals(control.feedback(wing_plant_at(w, Vgrid[i]), K, sign=1).A)
        assert_allclose(np.sort_complex(sw.poles[i]), np.sort_complex(direct), rtol=1e-8,
                        atol=1e-9)
    r = verify_lft(SimpleNamespace(P=P, nmeas=2, ncon=1, Vf=VF, n_delta=2), K)
    lo, hi = r.exact_V
    inside = (Vgrid > lo) & (Vgrid < hi)
    assert np.all(sw.stable[inside])
    # the first grid point above the upper end is unstable
    assert not sw.stable[np.argmax(Vgrid >= hi)]
    with pytest.raises(ConfigError, match="lacks"):
        verify_lft(SimpleNamespace(P=P), K)
