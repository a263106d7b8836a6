"""The flutter mode's residues in the flap-to-sensor loop along the speed.

Truth used: the first-order shift of the eigenvalue is checked against eigenvalues of the
loop closed by a small static gain, computed here with numpy (central differences); the
speeds of the flap's weakest grip on the flutter mode are the measured properties of the wing
and of the default run's frozen ROM loop that the theory page explains the interval designs'
stalls with.
"""

from __future__ import annotations

import numpy as np
import pytest

from casflutter.aeroelastic import TruthLoop, mode_residues
from casflutter.errors import ConfigError
from casflutter.truth import SeedWing

SERVO = 251.3
SPEEDS = np.linspace(1.1, 2.4, 27)


@pytest.fixture(scope="module")
def wing():
    return TruthLoop(SeedWing(), SERVO)


@pytest.fixture(scope="module")
def rom(default_rom_loop):
    return default_rom_loop[0]


def _shift(lp, lam, j, eps):
    """Eigenvalue nearest ``lam`` of the loop closed by ``v = eps zm_j`` (with the sensors'
    feed-through from the flap), minus ``lam``."""
    c = eps / (1.0 - eps * lp.D22[j])
    ev = np.linalg.eigvals(lp.A + c * np.outer(lp.B2, lp.C2[j]))
    return ev[np.argmin(np.abs(ev - lam))] - lam


@pytest.mark.parametrize("model", ["wing", "rom"])
def test_the_residue_is_the_eigenvalue_shift_per_unit_gain(model, request):
    fam = request.getfixturevalue(model)
    res = mode_residues(fam, SPEEDS)
    for k in (0, 13, len(res.V) - 1):
        lp = fam.loop(res.V[k])
        for j in range(res.residues.shape[1]):
            eps = 1e-5 / np.abs(res.residues[k, j]) * max(1.0, abs(res.eigenvalue[k].real))
            fd = (_shift(lp, res.eigenvalue[k], j, eps) - _shift(lp, res.eigenvalue[k], j, -eps)) \
                / (2 * eps)
            assert fd == pytest.approx(res.residues[k, j], rel=1e-5)


def test_the_flutter_mode_is_followed_from_either_end(wing):
    down = mode_residues(wing, SPEEDS)                    # from the most unstable mode at 2.4
    up = mode_residues(wing, SPEEDS, mode=down.eigenvalue[0])
    assert np.allclose(up.eigenvalue, down.eigenvalue, rtol=1e-12)
    assert down.worst_overlap >= 0.9 and up.worst_overlap >= 0.9
    assert down.eigenvalue[-1].real > 8 and 45 < down.eigenvalue[-1].imag < 60
    # the mode's frequency moves little: 59 -> 48 rad/s
    assert np.ptp(down.eigenvalue.imag) < 12


def test_the_flaps_grip_on_the_flutter_mode_turns_round(wing, rom):
    """On the wing the residues turn by more than 150 degrees (measured 212 and 167) through a
    dip near V = 1.45, where the mode grows at 1.6 rad/s at most; the frozen ROM loop's dip
    lies near V = 1.95, where its flutter mode already grows at more than 6 rad/s."""
    w = mode_residues(wing, SPEEDS)
    assert np.all(w.phase_swing_deg > 150)
    assert 1.3 < w.weakest_V < 1.6
    assert w.eigenvalue[w.V == w.weakest_V][0].real < 1.6
    r = mode_residues(rom.with_servo(SERVO), SPEEDS)
    assert np.all(r.phase_swing_deg > 150)
    assert 1.85 < r.weakest_V < 2.05
    assert r.eigenvalue[r.V == r.weakest_V][0].real > 6


def test_the_weakest_grip_where_the_mode_is_unstable(wing, rom):
    """Over the paper's whole interval the weakest grip is at the lowest speed, where the
    flap's force vanishes with the dynamic pressure; among the unstable speeds it is the dip
    (wing near 1.46, frozen ROM loop near 1.93), and there is none below flutter."""
    speeds = np.linspace(0.05, 2.4, 48)
    w = mode_residues(wing, speeds)
    assert w.weakest_V == pytest.approx(0.05)
    k = w.weakest_index(unstable_only=True)
    assert w.eigenvalue[k].real > 0 and 1.3 < w.V[k] < 1.6
    unstable = w.eigenvalue.real > 0
    assert w.grip[k] == pytest.approx(np.min(w.grip[unstable]))     # computed here
    r = mode_residues(rom.with_servo(SERVO), speeds)
    assert 1.85 < r.V[r.weakest_index(unstable_only=True)] < 2.05
    below = mode_residues(wing, np.linspace(0.05, 1.0, 12))
    assert np.all(below.eigenvalue.real < 0)
    assert below.weakest_index(unstable_only=True) is None
    assert below.weakest_index() == int(np.argmin(below.grip))


@pytest.mark.parametrize("speeds, kwargs, words", [
    ([2.0, 1.0], {}, "increasing"),
    ([1.0], {}, "at least 2"),
    ([1.0, np.nan], {}, "finite"),
    ([1.0, 2.0], {"min_score": 1.5}, "min_score"),
])
def test_bad_requests_are_refused(wing, speeds, kwargs, words):
    with pytest.raises(ConfigError, match=words):
        mode_residues(wing, speeds, **kwargs)


def test_a_family_without_loops_is_named():
    with pytest.raises(ConfigError, match="loop"):
        mode_residues(object(), [1.0, 2.0])


def test_the_control_reversal_speed_is_the_weakest_unstable_grip(wing, rom):
    """The reversal speed of a coarse scan refined locally against a dense scan of the grip
    computed here (400 speeds): the same dip to the dense grid's spacing (0.006), where the
    mode is unstable; the wing's near 1.46, the frozen ROM loop's near 1.93 (the issue's
    measured values); none below flutter."""
    from casflutter.aeroelastic import control_reversal
    for fam, lo, hi in ((wing, 1.40, 1.52), (rom.with_servo(SERVO), 1.85, 2.0)):
        rev = control_reversal(fam, np.linspace(0.05, 2.4, 48))
        dense = mode_residues(fam, np.linspace(0.05, 2.4, 400))
        unstable = np.flatnonzero(dense.eigenvalue.real > 0)
        V_dense = dense.V[unstable[np.argmin(dense.grip[unstable])]]
        assert lo < rev.V < hi
        assert rev.V == pytest.approx(V_dense, abs=0.006)
        assert rev.eigenvalue.real > 0
        assert rev.grip <= np.min(dense.grip[unstable]) * (1 + 1e-3)
        assert rev.grip < rev.grip_at_onset
    assert control_reversal(wing, np.linspace(0.05, 1.0, 12)) is None
    with pytest.raises(ConfigError, match="n_fine"):
        control_reversal(wing, np.linspace(0.05, 1.0, 12), n_fine=2)
