"""The multi-speed fixed-order design (:func:`casflutter.design.design_over_speeds`).

Truth used: the verification layer's certificate (:func:`casflutter.verify.verify_family`,
which shares no code with the design) and closed-loop eigenvalues computed here with
python-control's ``feedback`` on the family's own interpolated plant, on the shipped
``goland_4flaps`` family (50 states, 4 flaps, 8 sensors, 41 airspeeds; open-loop flutter
at 139.7 m/s).
"""

from __future__ import annotations

from dataclasses import replace

import control
import numpy as np
import pytest

from casflutter._settings import build_settings
from casflutter.aeroelastic import FamilySignals, GriddedFamily, PlantFamily, load_family
from casflutter.design import MultiSpeedSettings, design_over_speeds
from casflutter.errors import ConfigError, SynthesisError
from casflutter.verify import verify_family

INTERVAL = (60.0, 150.0)
FAST = MultiSpeedSettings(hinf_speeds=0, random_starts=1, full_order=False)


@pytest.fixture(scope="module")
def family():
    return load_family("goland_4flaps")


@pytest.fixture(scope="module")
def design(family):
    return design_over_speeds(family, INTERVAL, 2, settings=FAST, seed=0)


def _worst_abscissa(family, K, V: float) -> float:
    sig = family.signals
    G = family.plant(V)
    meas, ctrl = sig.output_index(), sig.input_index()
    G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                   np.asarray(G.D)[np.ix_(meas, ctrl)])
    return float(np.max(control.feedback(G, K, sign=family.feedback_sign).poles().real))


def test_one_order_2_controller_holds_the_interval_across_the_flutter_speed(family, design):
    assert design.held and design.order == 2 and design.controller.nstates == 2
    assert design.reached == INTERVAL
    # the open family flutters inside the interval, the closed one decays at every speed
    assert _worst_abscissa(family, control.ss([], [], [], np.zeros((4, 8))), 145.0) > 0
    for V in np.linspace(*INTERVAL, 10):
        assert _worst_abscissa(family, design.controller, V) < -0.9 * design.decay, V
    assert design.worst_abscissa <= -design.decay * (1 - 1e-6)


def test_the_verification_layer_certifies_what_the_design_holds(family, design):
    check = verify_family(family, design.controller, speed_range=family.speed_range)
    assert check.covers(*INTERVAL)
    assert list(design.controller.input_labels) == list(family.signals.measurements)
    assert list(design.controller.output_labels) == list(family.signals.controls)


def test_same_seed_same_controller(family, design):
    again = design_over_speeds(family, INTERVAL, 2, settings=FAST, seed=0)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(again.controller, name),
                                      getattr(design.controller, name))


def test_a_decay_a_mode_out_of_reach_forbids_is_refused_before_any_work(family, caplog):
    """Order 1 holds the whole range at a decay rate of 2.8 rad/s (measured), but at 60 m/s
    the aerodynamic lag pole at -2.986 rad/s (one per mode, more than the flaps and sensors
    can tell apart) is in every closed loop: 5 rad/s is refused, naming the mode and the
    bound, before any start is tried (none is logged)."""
    with caplog.at_level("DEBUG", logger="casflutter.design"), \
            pytest.raises(ConfigError,
                          match=r"the mode at λ = -2\.986 .* ask for a decay rate below 2\.986"):
        design_over_speeds(family, (60.0, 200.0), 1, seed=0, settings=MultiSpeedSettings(
            decay=5.0, hinf_speeds=0, random_starts=0, full_order=False, max_rounds=20))
    assert not [r for r in caplog.records if "continuation" in r.getMessage()
                or "start" in r.getMessage()]


class _Constant(PlantFamily):
    """One plant at every speed of (0, 1)."""

    speed_range = (0.0, 1.0)
    signals = FamilySignals(inputs=("u",), outputs=("y",))

    def __init__(self, A, B, C, name):
        self.matrices, self.name = (np.asarray(A, float), B, C), name

    def plant(self, V: float) -> control.StateSpace:
        A, B, C = self.matrices
        return control.ss(A, B, C, [[0.0]], inputs=["u"], outputs=["y"])


def test_no_start_that_decays_even_at_the_low_end_is_a_synthesis_error():
    """A double integrator read through its position: closed by a strictly proper order-1
    controller ``b c / (s - a)`` its characteristic polynomial is ``s^3 - a s^2 - b c``,
    whose missing ``s`` term leaves it unstable for every controller (Routh); both modes
    are in reach, so this is the design's own failure, reported as such."""
    fam = _Constant([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], "double integrator")
    with pytest.raises(SynthesisError, match="no start of order 1 decays at the rate 0.05"):
        design_over_speeds(fam, (0.0, 1.0), 1, seed=0, settings=MultiSpeedSettings(
            strictly_proper=True, hinf_speeds=0, random_starts=0, full_order=False,
            max_rounds=20))


def _with_hidden_mode(rate: float) -> _Constant:
    """A lightly damped oscillator (3 rad/s) the controller drives and reads, and a mode at
    ``-rate`` it can neither move nor see."""
    A = [[0.0, 1.0, 0.0], [-9.0, 0.3, 0.0], [0.0, 0.0, -rate]]
    return _Constant(A, [[0.0], [1.0], [0.0]], [[1.0, 0.0, 0.0]], f"hidden mode {-rate:g}")


def test_a_slow_mode_out_of_reach_sets_the_decay_rate_left_open(caplog):
    """The hidden mode decays at 0.01, below the 0.05 asked by default: the design asks for
    half of it, says so, and holds (0, 1) at that rate.  Independent check: the loop closed
    here with python-control keeps the hidden mode at -0.01 and decays at the rate held.  A rate
    given explicitly that the mode forbids is refused, and a hidden mode that grows makes
    every design impossible: both named before any work."""
    fam = _with_hidden_mode(0.01)
    settings = MultiSpeedSettings(hinf_speeds=0, random_starts=0, full_order=False)
    with caplog.at_level("WARNING", logger="casflutter.design"):
        d = design_over_speeds(fam, (0.0, 1.0), 1, settings=settings, seed=0)
    assert "decays at only 0.01" in caplog.text and "asks for 0.005" in caplog.text
    assert d.decay == pytest.approx(0.005) and d.held
    poles = control.feedback(fam.plant(0.5), d.controller, sign=fam.feedback_sign).poles()
    assert np.min(np.abs(poles + 0.01)) < 1e-9           # the hidden mode stays, unmoved
    assert np.max(poles.real) <= -d.decay * (1 - 1e-6)   # and the loop decays at the rate
    with pytest.raises(ConfigError, match="decays at only 0.01 .* rate 0.05 asked"):
        design_over_speeds(fam, (0.0, 1.0), 1, seed=0,
                           settings=replace(settings, decay=0.05))
    with pytest.raises(ConfigError, match="does not decay, and no controller moves it"):
        design_over_speeds(_with_hidden_mode(-0.01), (0.0, 1.0), 1, settings=settings)
    # an unmeasured position: named as the pole at the origin it is, not as "the mode 0"
    with pytest.raises(ConfigError, match=r"the mode at λ = 0 \(a pole at the origin: a "
                       r"position or an integrator; unreached by the controls and unseen"):
        design_over_speeds(_with_hidden_mode(0.0), (0.0, 1.0), 1, settings=settings)


def test_a_slow_open_loop_mode_sets_the_decay_rate_left_open(family, design, caplog):
    """An aircraft's phugoid decays at 0.001-0.004 /s; a default rate of 0.05 would make the
    controller move it from far (and cost the margins).  Here a slow oscillator (0.1 rad/s,
    decaying at 0.002 /s) beside an unstable one (3 rad/s) the controller must stabilise,
    both reached and seen: left open, the rate asked is half the open loop's slowest decay at
    the interval's low end (numpy's eigenvalues of the plant are the check), and the loop
    closed here with python-control decays at it.  A rate given is kept, and on
    goland_4flaps, whose slowest mode at 60 m/s decays at 2.95 /s, the default stays 0.05."""
    A = [[0.0, 1.0, 0.0, 0.0], [-0.01, -0.004, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0],
         [0.0, 0.0, -9.0, 0.3]]
    fam = _Constant(A, [[0.0], [1.0], [0.0], [1.0]], [[1.0, 0.0, 1.0, 0.0]], "slow mode")
    lam = np.linalg.eigvals(np.asarray(fam.plant(0.0).A))
    expected = -0.5 * np.max(lam.real[lam.real < 0])
    settings = MultiSpeedSettings(hinf_speeds=0, random_starts=0, full_order=False)
    with caplog.at_level("INFO", logger="casflutter.design"):
        d = design_over_speeds(fam, (0.0, 1.0), 1, settings=settings, seed=0)
    assert expected == pytest.approx(0.001, rel=1e-6)
    assert d.decay == pytest.approx(expected, rel=1e-12) and d.held
    assert "slowest mode decays at only 0.002" in caplog.text
    for V in (0.0, 1.0):
        loop = control.feedback(fam.plant(V), d.controller, sign=fam.feedback_sign)
        assert np.max(loop.poles().real) <= -d.decay * (1 - 1e-6)
    given = design_over_speeds(fam, (0.0, 1.0), 1, seed=0,
                               settings=replace(settings, decay=0.05))
    assert given.decay == 0.05 and given.held
    lam = np.linalg.eigvals(family.state_matrix(INTERVAL[0]))
    assert -np.max(lam.real) > 2 * 0.05
    assert design.decay == 0.05


@pytest.mark.parametrize("interval, order, match", [
    ((150.0, 60.0), 2, "interval"),
    ((10.0, 150.0), 2, "range"),
    ((60.0, float("nan")), 2, "interval"),
    ((60.0, 150.0), -1, "order"),
])
def test_bad_requests_are_refused_before_any_work(family, interval, order, match):
    with pytest.raises(ConfigError, match=match):
        design_over_speeds(family, interval, order, settings=FAST)


@pytest.mark.parametrize("settings, match", [
    ({"max_outer": 1}, r"unknown key 'max_outer' in \[settings\] \(it belongs in \[settings.synthesis\]\); "
     "allowed: decay, "),
    ({"synthesis": {"max_outr": 1}}, r"unknown key 'max_outr' in \[settings.synthesis\] \(did you mean 'max_outer'\?\)"),
    ({"n_speeds": 2.5}, r"settings.n_speeds: expected an integer"),
    # only the values that are wrong, each with what to give
    ({"decay": -1.0, "n_speeds": 1},
     r"settings.decay = -1.0: give a number >= 0, or None to have it chosen; n_speeds = 1: "
     r"give an integer >= 2 \(MultiSpeedSettings\)$"),
])
def test_settings_given_as_a_table_name_the_bad_key(family, settings, match):
    with pytest.raises(ConfigError, match=match):
        design_over_speeds(family, (60.0, 150.0), 2, settings=settings)


def test_settings_from_a_numpy_sweep_are_accepted():
    """A study script's numbers are numpy scalars; the table takes them as Python's."""
    s = build_settings(
        MultiSpeedSettings, {"n_speeds": np.int64(8), "decay": np.float64(0.1),
                             "full_order": np.bool_(False), "synthesis": {"max_outer": 3}})
    assert (s.n_speeds, s.decay, s.full_order, s.synthesis.max_outer) == (8, 0.1, False, 3)
    assert type(s.n_speeds) is int and type(s.full_order) is bool


@pytest.mark.parametrize("side", ["output", "input"])
def test_the_sensitivity_channels_are_the_loops_sensitivities(family, design, side):
    """The H∞ plants of ``sensitivity = True``, closed by the design's controller, against
    the loop's output sensitivity ``(I − s G K)⁻¹`` and input sensitivity ``(I − s K G)⁻¹``
    formed here with python-control's ``feedback`` on the family's own plant, at frequencies
    around the flutter mode's, to 1e-7 of the largest entry (rounding in the 50-state
    frequency responses)."""
    from casflutter.design._multispeed import _as_ss
    from casflutter.design._speeds import DesignChannels, design_partition

    V, K, s = 120.0, design.controller, family.feedback_sign
    sig = family.signals
    G = family.plant(V)
    meas, ctrl = sig.output_index(), sig.input_index()
    G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                   np.asarray(G.D)[np.ix_(meas, ctrl)])
    loop = G * K if side == "output" else K * G
    I = control.ss([], [], [], np.eye(loop.noutputs))
    S = control.feedback(I, loop, sign=s)
    part = design_partition(family, V, DesignChannels(sensitivity=side))
    P = _as_ss(part, part.B1.shape[1] + 2, part.C1.shape[0] + 1)    # padded with zeros
    T = P.lft(K, nu=K.noutputs, ny=K.ninputs)             # F_l(P, K): u = +K y
    n = S.ninputs
    for w in (1.0, 30.0, 68.7, 300.0):
        Tj, Sj = T(1j * w), S(1j * w)
        np.testing.assert_allclose(Tj[:n, :n], Sj, rtol=1e-6, atol=1e-7 * np.abs(Sj).max())
        assert np.all(Tj[n:, :] == 0) and np.all(Tj[:, n:] == 0)      # the zero padding


@pytest.mark.slow
def test_the_sensitivity_objective_bounds_every_loops_margins(family):
    """``sensitivity = True``: the H∞ phase minimises the worst output and input sensitivity
    over its speeds, so at each of them every loop broken alone (the others closed) has
    ``|S_ii| <= γ``, hence a phase margin of at least ``2 asin(1 / (2 γ))``.  Checked with
    the verification layer's own loop-at-a-time margins
    (:func:`casflutter.verify.loop_margins`), which share no code with the design."""
    from casflutter.verify import loop_margins

    settings = MultiSpeedSettings(hinf_speeds=3, random_starts=1, full_order=False,
                                  sensitivity=True)
    d = design_over_speeds(family, INTERVAL, 2, settings=settings, seed=0)
    assert d.held and d.synthesis is not None and len(d.hinf_speeds) == 3
    # the QP solver left open: qpOASES, whose statuses are its own
    assert "Successful return." in d.synthesis.statuses
    assert not any(st.startswith("Solve_Succeeded") for st in d.synthesis.statuses)
    bound = np.degrees(2 * np.arcsin(1 / (2 * d.gamma)))
    sig = family.signals
    meas, ctrl = sig.output_index(), sig.input_index()
    for V in d.hinf_speeds:
        G = family.plant(V)
        G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                       np.asarray(G.D)[np.ix_(meas, ctrl)])
        for side in ("input", "output"):
            for lm in loop_margins(G, d.controller, family.feedback_sign, side):
                assert lm.phase >= bound * (1 - 1e-6), (V, side, lm.phase, bound)


def test_the_callers_hinf_plants_are_held_from_the_start(family):
    """``hinf_plants`` outside the interval: the input-disturbance-to-sensor plant at
    145 m/s, above the open family's flutter, on a design over (60, 120), where the family
    alone needs no control.  The design's controller stabilises that plant too, so its H∞
    objective is finite and bounds the exact norm of the closed loop formed here with
    python-control's ``feedback`` and computed by the verification layer's ``hinf_norm``."""
    from casflutter.verify import hinf_norm

    s, sig = family.feedback_sign, family.signals
    G = family.plant(145.0)
    meas, ctrl = sig.output_index(), sig.input_index()
    G = control.ss(G.A, np.asarray(G.B)[:, ctrl], np.asarray(G.C)[meas, :],
                   np.asarray(G.D)[np.ix_(meas, ctrl)])
    assert np.max(G.poles().real) > 0                      # flutters open loop
    B, C, D = np.asarray(G.B), np.asarray(G.C), np.asarray(G.D)
    # inputs [w, u] (the flaps see w + s u), outputs [z = y, y]; u = +K y
    P = control.ss(G.A, np.hstack([B, s * B]), np.vstack([C, C]),
                   np.block([[D, s * D], [D, s * D]]))
    settings = replace(FAST, synthesis=replace(FAST.synthesis, max_outer=10))
    d = design_over_speeds(family, (60.0, 120.0), 2, settings=settings, seed=0,
                           hinf_plants=[P])
    assert d.held and d.synthesis is not None and np.isfinite(d.gamma)
    T = control.feedback(G, d.controller, sign=s)          # w -> y, the flaps see w + s K y
    assert np.max(T.poles().real) < 0
    assert hinf_norm(T).gamma <= d.gamma * (1 + 1e-6)


class _HiddenSpike(PlantFamily):
    """A damped oscillator (3 rad/s) the controller sees, and beside it the slowest mode,
    which it can neither move nor see, decaying at 1 rad/s except in a spike to +2 rad/s
    centred between two speeds of the design's 128-speed grid on (0, 1) (the gap from 64/127
    to 65/127)."""

    speed_range = (0.0, 1.0)
    name = "hidden spike"
    centre, width = 64.5 / 127, 0.0015
    signals = FamilySignals(inputs=("u",), outputs=("y",))

    def plant(self, V: float) -> control.StateSpace:
        a = -1.0 + 3.0 * np.exp(-((V - self.centre) / self.width) ** 2)
        A = np.array([[-3.0, 5.0, 0.0], [-5.0, -3.0, 0.0], [0.0, 0.0, a]])
        return control.ss(A, [[0.0], [1.0], [0.0]], [[1.0, 0.0, 0.0]], [[0.0]],
                          inputs=["u"], outputs=["y"])


def test_a_mode_that_crosses_between_two_scan_speeds_is_not_called_held():
    """The spike is 0.0039 from the nearest speeds of the 128-speed grid, where the mode
    decays at 0.997 rad/s: a plain grid would call (0, 1) held.  The design must stop before
    the spike, and its controller leaves that mode unstable there (it cannot touch it)."""
    fam = _HiddenSpike()
    settings = MultiSpeedSettings(n_speeds=16, hinf_speeds=0, random_starts=0,
                                  full_order=False)
    d = design_over_speeds(fam, (0.0, 1.0), 1, settings=settings, seed=0)
    assert not d.held
    assert d.reached[1] < fam.centre - fam.width
    loop = control.feedback(fam.plant(fam.centre), d.controller, sign=fam.feedback_sign)
    assert np.max(loop.poles().real) > 1.9


def test_a_gain_that_helps_without_limit_is_raised_only_as_far_as_needed():
    """A first-order divergence ``x' = 0.01 (V - 100) x + u``, ``y = x``: every added unit of
    gain lowers the abscissa by one, without end.  The design asks for the decay rate and
    gets it with a modest controller (once its line search doubled the step to 2**40:
    gains of 1e11, poles at 1e12 rad/s, all certified).  Independent check: the loop closed
    by python-control decays at the rate over the interval, with controller poles within a
    hundred times the plant's."""
    speeds = np.linspace(40.0, 200.0, 17)
    fam = GriddedFamily(speeds, (0.01 * (speeds - 100.0))[:, None, None],
                        np.ones((17, 1, 1)), np.ones((17, 1, 1)), np.zeros((17, 1, 1)))
    settings = MultiSpeedSettings(hinf_speeds=0, random_starts=0, full_order=False)
    d = design_over_speeds(fam, (60.0, 150.0), 2, settings=settings, seed=0)
    assert d.held
    assert np.max(np.abs(d.controller.poles())) < 100 * 0.5 + 0.05   # the plant's: 0.5 /s
    for V in np.linspace(60.0, 150.0, 31):
        loop = control.feedback(fam.plant(V), d.controller, sign=fam.feedback_sign)
        assert np.max(loop.poles().real) <= -d.decay * (1 - 1e-6), V
