"""GolandWing.generalized_aero_forces: the frequency-domain Q(ik) against the independent
strip-by-strip model of test_goland.py, against the truth's own time-domain forces, and the
exact Theodorsen function against its published table."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError
from casflutter.truth import GolandWing
from casflutter.truth._goland import theodorsen_C

from .test_goland import C_jones, C_theodorsen, Strips


@pytest.fixture(scope="module")
def wing():
    return GolandWing()


def test_theodorsen_function_table():
    """Theodorsen (NACA 496) / Bisplinghoff, Ashley & Halfman table: F + iG at k = 0.1, 0.5,
    1.0 (4 digits), C(0) = 1 and C -> 1/2 as k -> infinity."""
    C = theodorsen_C([0.0, 0.1, 0.5, 1.0, 1e4])
    assert C[0] == 1.0
    assert_allclose(C[1:4].real, [0.8319, 0.5979, 0.5394], atol=1e-4)
    assert_allclose(C[1:4].imag, [-0.1723, -0.1507, -0.1003], atol=1e-4)
    assert_allclose(C[4], 0.5, atol=1e-4)
    assert_allclose(C[1:4], C_theodorsen(np.array([0.1, 0.5, 1.0])), rtol=1e-14)


@pytest.mark.parametrize("theodorsen, Cfun", [("exact", C_theodorsen), ("jones", C_jones)])
def test_q_equals_independent_strips(wing, theodorsen, Cfun):
    """Q(ik) [u; v] = Phi^T f / (rho U^2 L), f from the independent strips, at two airspeeds
    with the same k (Q depends on k only), every mode and the flap."""
    p = wing.params
    ms = wing.modal_structure()
    N = ms.n_modes
    ks = np.array([0.05, 0.47, 1.3])
    Q = wing.generalized_aero_forces(ks, theodorsen=theodorsen)
    strips = Strips(p)
    for U in (80.0, 150.0):
        for n, k in enumerate(ks):
            om = k * U / p.b
            cols = []
            for j in range(N + 1):
                x = ms.shapes[:, j] if j < N else np.zeros(N)
                f = strips.forces(U, om, x[:p.n_bending], x[p.n_bending:], float(j == N), Cfun)
                cols.append(ms.shapes.T @ f / (p.rho * U * U * p.semispan))
            ref = np.array(cols).T
            assert_allclose(Q[n], ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_jones_q_is_the_truth_state_space_response(wing):
    """With Jones' C(k), Q(ik) is the frequency response of the truth's own state space: the
    modal equation [-w^2 + Omega^2 - alpha V^2 Q(ik)] u = alpha w from (sI - A)^-1 B."""
    ms = wing.modal_structure()
    N = ms.n_modes
    U = 120.0
    V = wing.speed_index(U)
    sys = wing.statespace(V)
    for om in (30.0, 70.0):
        k = om * wing.params.b / U
        Q = wing.generalized_aero_forces([k], theodorsen="jones")[0][:, :N]
        A, B = np.asarray(sys.A), np.asarray(sys.B)
        G = np.linalg.solve(1j * om * np.eye(A.shape[0]) - A, B[:, 1:])[:N]  # w -> u
        Z = -om ** 2 * np.eye(N) + np.diag(ms.omega ** 2) - ms.alpha * V * V * Q
        assert_allclose(Z @ G, ms.alpha * np.eye(N), atol=1e-8 * ms.alpha)


def test_bad_arguments(wing):
    with pytest.raises(ConfigError, match="'exact' or 'jones'"):
        wing.generalized_aero_forces([0.1], theodorsen="wagner")
    with pytest.raises(ConfigError, match=">= 0"):
        wing.generalized_aero_forces([-0.1, 0.2])
