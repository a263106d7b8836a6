"""Lower LFT against the frequency-domain formula P11 + P12 K (I - P22 K)^-1 P21,
evaluated with python-control's own transfer-function evaluation."""

from __future__ import annotations

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.errors import ConfigError, DimensionError
from casflutter.verify import IllPosedError, lft_closed_loop
from verify_helpers import random_stable_ss


def _fresp(sys, w):
    return sys(np.array([1j * w]), squeeze=False)[:, :, 0]


def _lft_reference(P, K, nmeas, ncon, w):
    Pw, Kw = _fresp(P, w), _fresp(K, w)
    nz, nw = P.noutputs - nmeas, P.ninputs - ncon
    P11, P12, P21, P22 = Pw[:nz, :nw], Pw[:nz, nw:], Pw[nz:, :nw], Pw[nz:, nw:]
    return P11 + P12 @ Kw @ np.linalg.solve(np.eye(nmeas) - P22 @ Kw, P21)


@pytest.mark.parametrize("seed,nx,nk,nw,nz,nmeas,ncon,d22", [
    (1, 5, 2, 2, 2, 2, 1, True), (2, 7, 3, 3, 1, 1, 2, True), (3, 4, 0, 1, 2, 2, 2, True),
    (4, 6, 4, 2, 3, 3, 1, False), (5, 3, 1, 1, 1, 1, 1, True),
])
def test_lft_matches_frequency_domain_formula(seed, nx, nk, nw, nz, nmeas, ncon, d22):
    rng = np.random.default_rng(seed)
    # the plant need not be stable for the algebra; use a random one
    P = control.ss(rng.standard_normal((nx, nx)), rng.standard_normal((nx, nw + ncon)),
                   rng.standard_normal((nz + nmeas, nx)),
                   rng.standard_normal((nz + nmeas, nw + ncon)))
    if not d22:
        D = np.array(P.D)
        D[nz:, nw:] = 0
        P = control.ss(P.A, P.B, P.C, D)
    K = (random_stable_ss(rng, nk, nmeas, ncon) if nk else
         0.3 * rng.standard_normal((ncon, nmeas)))
    T = lft_closed_loop(P, K, nmeas, ncon)
    Kss = K if nk else control.ss(np.zeros((0, 0)), np.zeros((0, nmeas)),
                                  np.zeros((ncon, 0)), K)
    assert (T.ninputs, T.noutputs, T.nstates) == (nw, nz, nx + nk)
    for w in (0.0, 0.37, 2.0, 31.0):
        assert_allclose(_fresp(T, w), _lft_reference(P, Kss, nmeas, ncon, w),
                        rtol=1e-9, atol=1e-9)


def test_closed_loop_poles_match_python_control_feedback():
    """With w, z removed, the closed-loop A is that of control.feedback(P22, K, sign=+1)."""
    rng = np.random.default_rng(7)
    P = control.ss(rng.standard_normal((5, 5)), rng.standard_normal((5, 3)),
                   rng.standard_normal((3, 5)), np.zeros((3, 3)))
    K = random_stable_ss(rng, 2, 2, 1)
    T = lft_closed_loop(P, K, 2, 1)
    ref = control.feedback(P[1:, 2:], K, sign=+1)
    assert_allclose(np.sort_complex(np.linalg.eigvals(T.A)),
                    np.sort_complex(np.linalg.eigvals(ref.A)), rtol=1e-9, atol=1e-9)


def test_dimension_mismatch_names_both_shapes():
    P = control.ss(-np.eye(2), np.ones((2, 3)), np.ones((3, 2)), np.zeros((3, 3)))
    with pytest.raises(DimensionError, match=r"1 outputs x 2 inputs.*P: 3 outputs x 3 inputs"):
        lft_closed_loop(P, np.ones((1, 2)), nmeas=1, ncon=1)
    with pytest.raises(DimensionError, match="nmeas=4"):
        lft_closed_loop(P, np.ones((1, 4)), nmeas=4, ncon=1)


def test_ill_posed_loop_is_rejected():
    D = np.zeros((2, 2))
    D[1, 1] = 0.5      # D22
    P = control.ss(-np.eye(2), np.ones((2, 2)), np.ones((2, 2)), D)
    with pytest.raises(IllPosedError, match="I - Dk D22 is singular"):
        lft_closed_loop(P, np.array([[2.0]]), 1, 1)       # 1 - 2*0.5 = 0


def test_discrete_time_is_rejected():
    P = control.ss(0.5 * np.eye(2), np.ones((2, 2)), np.ones((2, 2)), np.zeros((2, 2)), 0.01)
    with pytest.raises(ConfigError, match="discrete time"):
        lft_closed_loop(P, np.array([[1.0]]), 1, 1)
