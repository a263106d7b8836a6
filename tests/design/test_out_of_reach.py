"""Modes no controller moves (:func:`casflutter.design._out_of_reach.modes_out_of_reach`).

Truth used: the closed loops themselves.  Every plant is closed here with python-control's
``feedback`` by seeded random controllers (static and of order 2): a mode out of reach is an
eigenvalue of every one of them, to rounding, and a slow mode called in reach moves.  The
plants are COMPleib's (``problems/compleib_large``): the HE6 helicopter, whose slowest modes
its measurements do not see, AC4 (a mode at -0.05 out of reach), and the Boeing 767 at a
flutter condition (AC10), whose flutter mode and slow pair a stiff plant's pencil puts close
to, but not at, rank loss: in reach.
"""

from __future__ import annotations

import re

import control
import numpy as np
import pytest

from casflutter._resources import problems_dir
from casflutter.design import load_compleib
from casflutter.design._out_of_reach import OutOfReach, modes_out_of_reach


def _control_part(name: str):
    folder = "compleib" if name == "AC4" else "compleib_large"
    P, nu, ny, _ = load_compleib(problems_dir() / folder / f"{name}.json")
    A, B, C = (np.asarray(M, dtype=float) for M in (P.A, P.B, P.C))
    return A, B[:, -nu:], C[-ny:, :]


def _random_loops(A, B, C, rng, count: int = 3):
    """Closed-loop eigenvalues with seeded random controllers, static and of order 2."""
    G = control.ss(A, B, C, np.zeros((C.shape[0], B.shape[1])))
    scale = np.linalg.norm(A, 2) / (np.linalg.norm(B, 2) * np.linalg.norm(C, 2))
    for k in range(count):
        if k % 2 == 0:
            K = control.ss([], [], [], scale * rng.standard_normal((B.shape[1], C.shape[0])))
        else:
            K = control.ss(-np.eye(2) + 0.3 * rng.standard_normal((2, 2)),
                           rng.standard_normal((2, C.shape[0])),
                           scale * rng.standard_normal((B.shape[1], 2)),
                           np.zeros((B.shape[1], C.shape[0])))
        yield np.linalg.eigvals(control.feedback(G, K, sign=1).A)


@pytest.mark.parametrize("name, slowest", [("HE6", -0.005), ("AC4", -0.05), ("AC10", None)])
def test_the_modes_out_of_reach_stay_in_every_closed_loop(name, slowest):
    """HE6: the modes at -0.005 (and -0.01, -0.012) are unseen; AC4: the mode at -0.05;
    AC10: none slower than 0.05, though its flutter mode (+0.10 +- 19.77j) and a slow pair
    (-0.023 +- 0.093j) give pencil values of 1e-9 and 2e-10 of ‖A‖.  Each reported mode is
    an eigenvalue of the loop closed by each random controller (within 1e-9 of its size);
    each mode of the plant slower than 0.05 that is not reported moves by more than 1e-3
    with at least one of them."""
    A, B, C = _control_part(name)
    out = modes_out_of_reach(A, B, C, 0.05)
    assert out[0].eigenvalue.real >= out[-1].eigenvalue.real if out else slowest is None
    if slowest is not None:
        assert any(abs(m.eigenvalue - slowest) < 1e-6 for m in out)
    assert all(not (m.reached and m.seen) for m in out)
    lam = np.linalg.eigvals(A)
    slow = lam[(lam.real >= -0.05) & (lam.imag >= 0)]
    reported = np.array([m.eigenvalue for m in out])
    in_reach = [mu for mu in slow
                if not reported.size or np.min(np.abs(reported - mu)) > 1e-9 * max(1, abs(mu))]
    assert in_reach or name != "AC10"
    loops = list(_random_loops(A, B, C, np.random.default_rng(3)))
    for cl in loops:
        for mu in reported:
            assert np.min(np.abs(cl - mu)) < 1e-9 * max(1.0, abs(mu)), (name, mu)
    for mu in in_reach:
        assert max(np.min(np.abs(cl - mu)) for cl in loops) > 1e-3, (name, mu)


def test_only_modes_slower_than_the_rate_are_tested():
    """HE6's unseen modes decay at 0.005-0.012: asked for modes slower than 0.001 there are
    none (its other slow modes are in reach or faster)."""
    A, B, C = _control_part("HE6")
    assert all(m.eigenvalue.real >= -0.05 for m in modes_out_of_reach(A, B, C, 0.05))
    assert modes_out_of_reach(A, B, C, 0.001) == []


def test_a_fully_reachable_and_seen_plant_has_none():
    """A damped oscillator driven and read through its velocity: nothing out of reach."""
    A = np.array([[0.0, 1.0], [-4.0, -0.01]])
    assert modes_out_of_reach(A, [[0.0], [1.0]], [[0.0, 1.0]], 1.0) == []
    # read through nothing that sees it: both modes of the pair are unseen
    out = modes_out_of_reach(A, [[0.0], [1.0]], [[0.0, 0.0]], 1.0)
    assert len(out) == 1 and not out[0].seen and out[0].reached
    assert "unseen by the measurements" in out[0].describe()
    # an integrator (A = 0) that no control drives keeps its pole at 0; one that is driven
    # and read does not
    assert modes_out_of_reach([[0.0]], [[0.0]], [[1.0]], 0.05) == [
        OutOfReach(0j, reached=False, seen=True)]
    assert modes_out_of_reach([[0.0]], [[1.0]], [[1.0]], 0.05) == []


@pytest.mark.parametrize("B2, C2, why", [
    ([[0.0], [1.0]], [[1.0, 1.0]], "unreached by the controls"),
    ([[1.0], [1.0]], [[0.0, 1.0]], "unseen by the measurements")])
def test_synthesis_names_a_growing_mode_no_controller_moves(B2, C2, why):
    """Refused before any start, with the mode named (PBH at λ = 1 by hand: the row or
    column of the unstable state is zero in B2 or C2)."""
    from casflutter.design import synthesize
    from casflutter.errors import SynthesisError

    A = np.diag([1.0, -1.0])
    P = control.ss(A, np.hstack([[[1.0], [1.0]], B2]), np.vstack([[[1.0, 1.0]], C2]),
                   [[0.0, 1.0], [0.0, 0.0]])
    with pytest.raises(SynthesisError,
                       match=re.escape(f"the mode at λ = 1 ({why}) does not decay")):
        synthesize(P, 1, 1, 0)
