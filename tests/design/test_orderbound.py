"""The rank relaxation of order-k synthesis (casflutter.design._orderbound).

Truth used: a brute-force grid over the one free gain of a SISO static problem, closed
by the verification layer (independent of the relaxation's own LFT and gradients); on HE6 the
LMI full-order optimum γ* of ``problems/compleib_large/reference.json`` and the synthesis'
order-3 design checked by the independent verification layer.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.cli.bench.synthesis import run_plant
from casflutter.design import load_compleib, synthesize
from casflutter.design._orderbound import order_relaxation
from casflutter.errors import ConfigError
from casflutter.verify import hinf_norm as verify_norm
from casflutter.verify import lft_closed_loop

ROOT = Path(__file__).resolve().parents[2]
LARGE = ROOT / "problems" / "compleib_large"


def _siso_plant() -> control.StateSpace:
    """x' = -x + w + u, z = [x; 0.5 u], y = x + 0.1 w: a static gain trades the DC
    error against the control weight seen through the measurement noise at ω = ∞."""
    A = [[-1.0]]
    B = [[1.0, 1.0]]
    C = [[1.0], [0.0], [1.0]]
    D = [[0.0, 0.0], [0.0, 0.5], [0.1, 0.0]]
    return control.ss(A, B, C, D)


def test_static_siso_relaxation_matches_a_brute_force_gain_grid():
    """Order 0 with the frequency 0: K(0) = K(∞) = K, so the relaxation is
    min over K of max(σ̄ T(0; K), σ̄ T(∞; K)); a 1-D grid over K closed by python-control
    gives the same minimum to 0.2 %."""
    P = _siso_plant()
    res = order_relaxation(P, 1, 1, 0, (0.0,), starts=3, seed=0)
    def worst(K):
        cl = lft_closed_loop(P, control.ss([], [], [], [[K]]), 1, 1)
        return max(np.linalg.norm(np.atleast_2d(cl.dcgain()), 2),
                   np.linalg.norm(np.asarray(cl.D, float), 2))

    grid = np.concatenate([-np.geomspace(1e-3, 1e3, 300), np.linspace(-1, 0.99, 100)])
    vals = [worst(K) for K in grid]
    i = int(np.argmin(vals))
    fine = np.linspace(grid[max(i - 2, 0)], grid[min(i + 2, grid.size - 1)], 400)
    best = min(min(vals), min(worst(K) for K in fine))
    assert not res.trivial
    np.testing.assert_allclose(res.value, best, rtol=2e-3)
    np.testing.assert_allclose(max(res.sigma_at_infinity, *res.sigma_at_frequencies),
                               res.value, rtol=1e-12)


def test_relaxation_is_deterministic_and_checks_its_inputs():
    P = _siso_plant()
    a = order_relaxation(P, 1, 1, 0, (0.0, 1.0), starts=2, seed=3)
    b = order_relaxation(P, 1, 1, 0, (0.0, 1.0), starts=2, seed=3)
    assert a == b
    with pytest.raises(ConfigError, match="frequencies"):
        order_relaxation(P, 1, 1, 0, (-1.0,))
    with pytest.raises(ConfigError, match="pole"):
        order_relaxation(control.ss([[0.0]], [[1.0, 1.0]], [[1.0], [0.0], [1.0]],
                                    [[0, 0], [0, 1], [0.1, 0]]), 1, 1, 0, (0.0,))
    with pytest.raises(ConfigError, match="starts"):
        order_relaxation(P, 1, 1, 0, starts=0)


@pytest.mark.slow
def test_he6_order3_is_held_above_1p5_gamma_star_by_its_static_control_direction():
    """HE6 (4 controls, 6 measurements, four near-integrating tracking weights): an order-3
    controller leaves one control direction static (qᵀCk = 0), and the static-direction
    relaxation (ω = 0 and ∞) stays above 4 γ*, so the issue's 1.5 γ* cannot be reached at
    order 3.  The synthesis' order-3 design (verified independently) reaches that value to
    1 % and is not below it by more than 0.1 % (it would be, were the relaxation's local
    minimum not its global one)."""
    P, nmeas, ncon, meta = load_compleib(LARGE / "HE6.json")
    gstar = meta["gamma_full_order_lmi"]
    rel = order_relaxation(P, nmeas, ncon, 3, (0.0,), starts=6, seed=0)
    assert not rel.trivial
    assert rel.value > 4.0 * gstar
    # several starts agree on the best local minimum
    assert sum(v <= rel.value * (1 + 1e-4) for v in rel.start_values) >= 2
    res = synthesize(P, nmeas, ncon, 3, starts=3, seed=0)
    ref = verify_norm(lft_closed_loop(P, res.controller, nmeas, ncon))
    assert ref.stable
    np.testing.assert_allclose(res.gamma, ref.gamma, rtol=1e-6)
    assert rel.value * (1 - 1e-3) <= ref.gamma <= 1.01 * rel.value


def test_bench_synthesis_records_the_relaxation_below_the_order_it_bounds():
    """``bench synthesis --relaxation-starts``: the order-0 record of AC15 (2 controls,
    3 measurements) carries the static-direction relaxation, whose value is the larger of its
    two σ̄ and (a lower bound at its global minimum) does not exceed the static γ the
    synthesis reached."""
    path = ROOT / "problems" / "compleib" / "AC15.json"
    (rec,) = run_plant(path, [0], starts=1, seed=0, time_limit=None, hinfsyn_timeout=0,
                       relaxation_starts=3)
    rel = rec["static_direction_relaxation"]
    assert rel["value"] == pytest.approx(max(rel["sigma_at_zero"], rel["sigma_at_infinity"]),
                                         rel=1e-9)
    assert len(rel["start_values"]) == 3
    assert rec["stable"] and rec["gamma"] is not None
    assert rel["value"] <= rec["gamma"] * (1 + 1e-6)
