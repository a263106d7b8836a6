"""Aircraft-size and hard COMPleib plants (problems/compleib_large/, 20-82 states).

Truth used: the LMI full-order optimum γ* of reference.json (a lower bound for every order)
and the independent verification layer's norm.  All slow: ``make test-all`` runs them;
``casflutter bench synthesis --plants problems/compleib_large`` measures them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casflutter.design import load_compleib, synthesize
from casflutter.verify import lft_closed_loop
from casflutter.verify import hinf_norm as verify_norm

ROOT = Path(__file__).resolve().parents[2]
LARGE = ROOT / "problems" / "compleib_large"

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("name", ["CM1", "EB4"])
def test_lightly_damped_plants_get_a_real_decay_margin(name):
    """Poles on/near the axis (CM1) and modes damped 1e-7 (EB4): no start ends in an
    invalid number, every start reaches a decay margin, γ is finite and checked."""
    P, nmeas, ncon, meta = load_compleib(LARGE / f"{name}.json")
    res = synthesize(P, nmeas, ncon, 0, starts=3, seed=0)
    statuses = [s for r in res.starts for s in r.statuses]
    assert not any("Invalid_Number" in s or "Infeasible" in s for s in statuses)
    assert all(r.stabilized and r.spectral_abscissa < 0 for r in res.starts)
    assert res.spectral_abscissa < 0
    ref = verify_norm(lft_closed_loop(P, res.controller, nmeas, ncon))
    np.testing.assert_allclose(res.gamma, ref.gamma, rtol=1e-6)
    assert res.gamma >= meta["gamma_full_order_lmi"] * (1 - 1e-3)


@pytest.mark.parametrize("name", ["AC10", "BDT2"])
def test_large_plants_stabilised_and_monotone_in_order(name):
    """AC10 (Boeing 767 at a flutter condition, 55 states) and BDT2 (82 states): orders 0 and
    1 stabilised, the order-1 design warm-started from the static one is no worse."""
    P, nmeas, ncon, _ = load_compleib(LARGE / f"{name}.json")
    r0 = synthesize(P, nmeas, ncon, 0, starts=1, seed=0)
    r1 = synthesize(P, nmeas, ncon, 1, starts=1, seed=0, initial=r0.controller)
    for r in (r0, r1):
        assert r.success and r.spectral_abscissa < 0
    assert r1.gamma <= r0.gamma * (1 + 1e-9)
