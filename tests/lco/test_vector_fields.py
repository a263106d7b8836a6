"""The truths' CasADi vector fields against the numpy right-hand sides the simulators
integrate (every truth, linear and nonlinear terms, across speeds and amplitudes)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.truth import GolandWing, SeedWing, TypicalSection, TypicalSectionParams

CASES = [
    (TypicalSection(TypicalSectionParams(kappa1=0.7, kappa2=3.0, kappa3=-1.0, kappa4=5.0)),
     (0.6, 2.17, 3.4)),
    (GolandWing(), (0.8, 1.73, 2.4)),
    (SeedWing(), (0.4, 1.085, 1.9)),
]


@pytest.mark.parametrize("truth, speeds", CASES, ids=["typical_section", "goland", "seed_wing"])
def test_vector_field_matches_numpy_rhs(truth, speeds):
    f = truth.vector_field()
    rhs_at = truth.flap_dynamics
    rng = np.random.default_rng(7)
    for V in speeds:
        rhs = rhs_at(V)
        for scale in (1e-3, 0.3, 3.0):
            x = rng.normal(size=f.size1_in(0)) * scale
            a = np.asarray(f(x, V)).ravel()
            b = rhs(x, 0.0, 0.0, 0.0)[0]
            assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))


def test_linearisation_is_the_state_matrix():
    for truth, speeds in CASES:
        f = truth.vector_field()
        x = ca.SX.sym("x", f.size1_in(0))
        J = ca.Function("J", [x], [ca.jacobian(f(x, speeds[1]), x)])
        A = np.asarray(J(np.zeros(f.size1_in(0))))
        ref = truth.state_matrix(speeds[1])
        assert np.max(np.abs(A - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_non_quadratic_speed_dependence_is_refused():
    class Odd(TypicalSection):
        def aero_matrices(self, V):
            am = super().aero_matrices(V)
            return type(am)(**{**am.__dict__, "Cx": am.Cx * V ** 2})

    with pytest.raises(ConfigError, match="not quadratic in the speed"):
        Odd().vector_field()
