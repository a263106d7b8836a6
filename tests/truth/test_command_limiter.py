"""The software limiter of the flap command in the tunnel runs (``suppression.command_limiter``),
against what a rate limiter must do, computed here from the command: the identity below the
limit; above it never faster than the limit; the plain limiter a triangle that lags the command
by the angle at which the command meets it again; the phase-compensated one a triangle in phase
with the command, around zero; both with the fundamental ``4 rate / (pi omega)``, the largest
any signal of that rate can have."""

import control
import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.truth import SuppressionSettings, closed_loop_truth, limit_command, load_problem

DT = 0.002                      # s, the seed wing's sample time
RATE = np.radians(300.0)        # rad/s, the tunnel servo's rate limit
W = 2 * np.pi * 9.26            # rad/s, the truth's LCO at 1.2 Vf
PERIOD = 2 * np.pi / W


def _limited(kind: str, u: np.ndarray) -> np.ndarray:
    return limit_command(u, RATE, DT, kind)


def _fundamental(t: np.ndarray, y: np.ndarray) -> complex:
    """The complex amplitude of ``y`` at ``W`` (``a`` in ``Re(a e^{i W t})``) over the whole
    periods of ``t``'s last second."""
    n = int(round(int(1.0 / PERIOD) * PERIOD / DT))
    t, y = t[-n:], y[-n:]
    return 2 * np.mean(y * np.exp(-1j * W * t))


@pytest.mark.parametrize("kind", ["rate", "phase_compensated"])
def test_below_the_limit_the_command_passes_as_it_is(kind):
    t = np.arange(0.0, 2.0, DT)
    u = 0.5 * RATE / W * np.sin(W * t)          # its rate at most half the limit
    np.testing.assert_array_equal(_limited(kind, u), u)


def test_deep_in_saturation_the_plain_limiter_lags_and_the_compensated_one_does_not():
    t = np.arange(0.0, 4.0, DT)
    A = 5 * RATE / W                             # the command's rate 5x the limit
    u = A * np.cos(W * t)                        # saturation begins off-centre, at the peak
    command = _fundamental(t, u)
    # the triangle's amplitude at the limit, and where the falling command meets it
    tri = RATE * PERIOD / 4
    lag_plain = np.pi / 2 - np.arcsin(tri / A)
    for kind, lag in (("rate", lag_plain), ("phase_compensated", 0.0)):
        y = _limited(kind, u)
        assert np.max(np.abs(np.diff(y))) <= RATE * DT * (1 + 1e-12)
        f = _fundamental(t, y)
        # the largest fundamental a signal of this rate can have, to the sampling
        assert abs(f) == pytest.approx(4 * RATE / (np.pi * W), rel=0.02), kind
        # its phase behind the command's: one sample is W DT = 6.7 deg
        behind = np.angle(command / f)
        assert behind == pytest.approx(lag, abs=W * DT), kind
        if kind == "phase_compensated":          # around zero, not where it began
            last = y[-int(round(PERIOD / DT)) * 8:].reshape(8, -1)
            assert np.all(last.max(axis=1) > 0) and np.all(last.min(axis=1) < 0)
    assert np.degrees(lag_plain) > 70


@pytest.mark.parametrize("kind", ["rate", "phase_compensated"])
def test_the_output_stays_inside_the_travel_and_does_not_wind_up(kind):
    """A command held beyond the flap's travel, then dropped to zero: the output stops at the
    travel and is back at zero after travel / rate (one sample more), not after the time it
    would take from where the command was."""
    travel, held = np.radians(15.0), np.radians(40.0)
    t = np.arange(0.0, 1.0, DT)
    u = np.where(t < 0.5, held, 0.0)
    y = limit_command(u, RATE, DT, kind, travel=travel)
    assert np.max(np.abs(y)) <= travel
    back = t[(t >= 0.5) & (np.abs(y) <= 1e-12)][0] - 0.5
    assert back <= travel / RATE + 2 * DT
    assert back < held / RATE


def test_a_limiter_needs_the_servos_rate_and_a_known_name():
    with pytest.raises(ConfigError, match="command_limiter = 'pcrl'"):
        SuppressionSettings(command_limiter="pcrl", flap_rate_limit=RATE)
    with pytest.raises(ConfigError, match="give flap_rate_limit too"):
        SuppressionSettings(command_limiter="phase_compensated")
    truth = load_problem("typical_section")
    with pytest.raises(ConfigError, match="give flap_rate_limit too"):
        closed_loop_truth(truth, control.ss([], [], [], [[0.0, 0.0]]), 1.0,
                          np.arange(0.0, 1.0, 0.1), truth.displaced_state(0, 0.01),
                          lambda t: 1.0, command_limiter="rate")
