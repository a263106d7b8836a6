"""The flap-rate term of the H∞ plants (casflutter.design.with_flap_rate)."""

import control
import numpy as np
import pytest

from casflutter.design import with_flap_rate
from casflutter.errors import ConfigError
from casflutter.pipeline import load_config


def _plant():
    # 2 states, inputs [w, v], outputs [z, zm1, zm2]
    A = np.array([[0.0, 1.0], [-4.0, -0.2]])
    B = np.array([[0.0, 0.0], [1.0, 0.5]])
    C = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    D = np.array([[0.0, 0.0], [0.0, 0.3], [0.0, 0.0]])
    return control.ss(A, B, C, D)


def test_the_new_output_is_the_weighted_filtered_flap_rate():
    """From the flap v to z_r: w a s / (s + a), computed independently; nothing else moves."""
    P = _plant()
    w, a = 0.02, 50.0
    Pa = with_flap_rate(P, nmeas=2, weight=w, bandwidth=a)
    assert (Pa.nstates, Pa.ninputs, Pa.noutputs) == (3, 2, 4)
    for om in (0.3, 7.0, 120.0):
        s = 1j * om
        G = Pa(s)                     # outputs [z, z_r, zm1, zm2]
        assert G[1, 1] == pytest.approx(w * a * s / (s + a), rel=1e-12)
        assert G[1, 0] == pytest.approx(0.0, abs=1e-14)          # no path from w
        H = P(s)
        assert np.allclose(G[[0, 2, 3], :], H, rtol=1e-12, atol=1e-14)


def test_bad_weights_are_named():
    with pytest.raises(ConfigError, match="flap-rate weight"):
        with_flap_rate(_plant(), 2, weight=0.0, bandwidth=10.0)
    with pytest.raises(ConfigError, match="controller.flap_rate_weight"):
        load_config(updates={"controller.flap_rate_weight": -1.0})
    with pytest.raises(ConfigError, match="controller.flap_rate_bandwidth"):
        load_config(updates={"controller.flap_rate_bandwidth": 0.0})
