"""Continuation in the controller order over a fixed speed interval (:func:`reduce_order`),
and the design that puts stability over the interval first (:func:`design_interval_controller`).

Start: the order-8 controller that holds the seed wing over (0, 2.4)
(``tests/witnesses/truth_interval_controller_order8.json``, certified in
``tests/verify/test_truth_witness.py``).  Truth used: the verification layer's exact stable
interval of the wing's own linearisation (:func:`casflutter.verify.speed_family_interval`,
python-control closing the loop), which shares no code with the optimiser.

What is asserted is what :func:`reduce_order` promises: the requested orders are reached and
each holds the interval, certified independently.  Not the way there: whether a step is
split at a half-way order (8 -> 6 -> 5 -> 4 rather than 8 -> 6 -> 4) depends on a local
optimiser whose path changes with the last bits of the arithmetic, e.g. with the machine's
BLAS kernels.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.aeroelastic import TruthLoop
from casflutter.design import design_interval_controller, reduce_order
from casflutter.errors import ConfigError, DimensionError
from casflutter.truth import SeedWing
from casflutter.verify import load_controller, speed_family_interval

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"

INTERVAL = (0.05, 1.6)


@pytest.fixture(scope="module")
def wing():
    return TruthLoop(SeedWing(), 251.3)


@pytest.fixture(scope="module")
def witness():
    return load_controller(WITNESS_DIR / "truth_interval_controller_order8.json")


def _reached_in_order(steps, requested, start_order):
    """The steps' orders fall strictly from below ``start_order`` and include every
    requested order (half-way orders of split steps may lie between them)."""
    orders = [s.order for s in steps]
    assert all(a > b for a, b in zip([start_order] + orders, orders)), orders
    assert set(requested) <= set(orders), orders


def test_lower_orders_hold_the_interval_and_the_verification_certifies_them(wing, witness):
    red = reduce_order(wing, witness, INTERVAL, [6, 4])
    _reached_in_order(red.steps, [6, 4], witness.nstates)
    assert red.lowest is red.steps[-1] and red.lowest.met and red.lowest.order == 4
    for step in red.steps:
        assert step.controller.nstates == step.order
        assert step.worst_abscissa <= -red.decay
        cert = speed_family_interval(lambda V: wing.loop(V).flap_to_sensors(),
                                     step.controller, 1.0)
        assert cert.lower <= INTERVAL[0] and cert.upper >= INTERVAL[1], step.order
    # the reduction's own dense scan agrees with eigenvalues computed here
    K = red.lowest.controller
    for V in np.linspace(*INTERVAL, 25):
        assert np.max(np.linalg.eigvals(wing.closed_loop_state_matrix(V, K)).real) < 0


def test_stability_first_then_the_order_holds_the_wing_past_flutter(wing):
    """LQG at 1.45 (34 % above the wing's flutter speed 1.085), continued down to 0.05, then
    reduced 32 -> 14 -> 8 -> 4; the wing's exact interval is certified independently."""
    design = design_interval_controller(wing, (0.05, 1.45), 4, orders=(14, 8))
    assert design.full_order.controller.nstates == 32 and design.full_order.met
    _reached_in_order(design.reduction.steps, [14, 8, 4], 32)
    assert all(s.met for s in design.reduction.steps)
    assert design.met and design.controller.nstates == 4
    cert = speed_family_interval(lambda V: wing.loop(V).flap_to_sensors(), design.controller,
                                 1.0)
    assert cert.lower == 0.0 and cert.upper >= 1.45          # measured 1.4797
    # the open wing flutters inside the interval: the controller does the work
    assert np.max(np.linalg.eigvals(wing.state_matrix(1.45)).real) > 0


@pytest.mark.parametrize("interval, orders, match", [
    ((2.0, 1.0), [6], "interval"),
    ((0.05, 1.6), [6, 6], "strictly decreasing"),
    ((0.05, 1.6), [8], "below the start's order 8"),
    ((0.05, 1.6), [0], "orders"),
    ((0.05, 1.6), [], "orders"),
])
def test_bad_requests_are_refused_before_any_work(wing, witness, interval, orders, match):
    with pytest.raises(ConfigError, match=match):
        reduce_order(wing, witness, interval, orders)


def test_a_controller_on_other_signals_is_refused(wing):
    three_sensors = control.ss(np.diag([-1.0, -2.0, -3.0]), np.ones((3, 3)), np.ones((1, 3)),
                               np.zeros((1, 3)))
    with pytest.raises(DimensionError, match="2 inputs"):
        reduce_order(wing, three_sensors, INTERVAL, [2])
