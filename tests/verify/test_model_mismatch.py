"""How far a model family's response lies from a reference's (casflutter.verify.model_mismatch)."""

import numpy as np
import pytest

from casflutter.aeroelastic import FamilySignals, GriddedFamily
from casflutter.errors import DimensionError
from casflutter.verify import model_mismatch

OMEGA_N, ZETA = 10.0, 0.05


def _oscillator(c_scale=1.0, phase_lag=0.0, *, measurements=("y1", "y2"),
                time_unit="s"):
    """A lightly damped mode at OMEGA_N rad/s, one control, two measurements, on a grid of
    three speeds; ``c_scale`` scales the measurements and ``phase_lag`` advances their phase
    by that angle at OMEGA_N (each reads cos(phi) x + sin(phi) x' / OMEGA_N instead of x,
    which is e^{j phi} x where x' = j OMEGA_N x)."""
    speeds = np.array([0.0, 1.0, 2.0])
    A = np.array([[0.0, 1.0], [-OMEGA_N ** 2, -2 * ZETA * OMEGA_N]])
    B = np.array([[0.0], [1.0]])
    C = c_scale * np.array([[1.0, 0.0], [0.5, 0.0]])
    if phase_lag:
        C = C @ np.array([[np.cos(phase_lag), np.sin(phase_lag) / OMEGA_N], [0.0, 0.0]])
    D = np.zeros((2, 1))
    signals = FamilySignals(inputs=("u",), outputs=tuple(measurements), controls=("u",),
                            measurements=tuple(measurements))
    stack = lambda M: np.repeat(M[None], speeds.size, axis=0)  # noqa: E731
    return GriddedFamily(speeds, stack(A), stack(B), stack(C), stack(D), signals,
                         speed_unit="m/s", time_unit=time_unit)


def test_a_gain_error_is_measured_exactly_at_every_frequency():
    # G_ref = 1.1 G: sigma_max(0.1 G) / sigma_max(G) = 0.1 whatever the frequency and speed
    model, reference = _oscillator(), _oscillator(1.1)
    m = model_mismatch(reference, model, [0.5, 1.5])
    assert m.relative_error.shape == (2, m.omega.size)
    np.testing.assert_allclose(m.relative_error, 0.1, rtol=1e-9)
    np.testing.assert_allclose(m.worst(), 0.1, rtol=1e-9)
    # a model against itself: no error
    assert np.max(model_mismatch(model, model, [1.0]).relative_error) == 0.0


def test_the_band_is_that_of_the_lightly_damped_mode():
    m = model_mismatch(_oscillator(1.1), _oscillator(), [1.0])
    wn = OMEGA_N     # |lambda| of the pair is omega_n
    assert m.band == pytest.approx((0.5 * wn, 2.0 * wn), rel=1e-9)
    # the default grid spans a decade either side of the poles (to one step of its 400),
    # and holds the mode's own frequency, where the responses peak
    assert m.omega[0] == pytest.approx(wn / 10, rel=1e-9)
    assert m.omega[-1] == pytest.approx(wn * 10, rel=0.02)
    assert np.min(np.abs(m.omega - wn * np.sqrt(1 - ZETA ** 2))) < 1e-9 * wn
    # outside the grid's band worst() refuses instead of returning nothing
    with pytest.raises(ValueError, match="no frequency"):
        m.worst(1e5, 1e6)


def test_a_phase_error_at_the_mode_shows_as_its_chord():
    # G_ref = e^{j phi} G at omega_n: the relative error is |e^{j phi} - 1| = 2 sin(phi / 2),
    # 0.174 for 10 deg (the docstring's "0.1 is about 6 deg")
    phi = np.radians(10.0)
    m = model_mismatch(_oscillator(phase_lag=phi), _oscillator(), [1.0], omega=[OMEGA_N])
    assert m.relative_error[0, 0] == pytest.approx(2 * np.sin(phi / 2), rel=1e-9)


def test_families_that_cannot_be_compared_are_refused():
    with pytest.raises(DimensionError, match="same units"):
        model_mismatch(_oscillator(time_unit="ms"), _oscillator(), [1.0])
    one = GriddedFamily([0.0, 1.0], np.zeros((2, 1, 1)) - 1.0, np.ones((2, 1, 1)),
                        np.ones((2, 1, 1)), np.zeros((2, 1, 1)), speed_unit="m/s")
    with pytest.raises(DimensionError, match="same controls and measurements"):
        model_mismatch(one, _oscillator(), [0.5])
    with pytest.raises(ValueError, match="speeds"):
        model_mismatch(_oscillator(), _oscillator(), [])


def test_the_figure_draws_each_speed_and_marks_where_the_plant_is_lost():
    from casflutter.report import plot_model_mismatch
    from casflutter.verify import ClosedLoopCrossing

    m = model_mismatch(_oscillator(1.1), _oscillator(), [0.5, 1.5])
    lost = [ClosedLoopCrossing(speed=1.2, omega=12.0, direction="destabilizing", kind="flutter"),
            ClosedLoopCrossing(speed=1.4, omega=0.0, direction="destabilizing",
                               kind="divergence"),
            ClosedLoopCrossing(speed=1.6, omega=30.0, direction="stabilizing", kind="flutter")]
    ax = plot_model_mismatch(m, crossings=lost).axes[0]
    curves = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == m.omega.size]
    assert len(curves) == 2
    np.testing.assert_allclose(curves[1].get_ydata(), m.relative_error[1])
    # one red line per destabilising crossing: at its frequency, a real one at the grid's start
    marks = sorted(float(ln.get_xdata()[0]) for ln in ax.get_lines()
                   if isinstance(ln.get_color(), str) and ln.get_color() == "tab:red")
    assert marks == pytest.approx([m.omega[0], 12.0])
