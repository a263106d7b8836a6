"""The sensitivity objective of the multi-speed design does not depend on the signals' units.

Truth used: the same physical family written in other units (gyros in deg/s instead of
rad/s, accelerometers in g and mm/s², every flap command in degrees), the controller
converted between them by hand, and the exact H∞ norm of the verification layer
(:func:`casflutter.verify.hinf_norm`, which shares no code with the design).  The loops
are the same loops, so every loop-at-a-time margin is the same; the design's objective
must be the same number too, while the plain output sensitivity's norm is not (the
sensors are in different units; the flaps are all in one unit, whose change cancels).
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from casflutter.aeroelastic import FamilySignals, GriddedFamily, load_family
from casflutter.design._multispeed import _as_ss, _units
from casflutter.design._speeds import (DesignChannels, Scaling, design_partition,
                                       unit_free_sensitivity)
from casflutter.verify import hinf_norm

#: new units per old unit, per measurement (8 sensors) and per control (4 flaps)
SENSOR_UNITS = np.array([57.29578, 57.29578, 1 / 9.80665, 1 / 9.80665, 1e3, 1.0, 1.0, 1e3])
SENSOR_NAMES = ("deg/s", "deg/s", "g", "g", "mm/s^2", "m/s^2", "m/s^2", "mm/s^2")
CONTROL_UNITS = np.full(4, 57.29578)                       # every flap in degrees
SPEEDS = (60.0, 100.0, 130.0)           # below the open loop's flutter, 139.7 m/s


@pytest.fixture(scope="module")
def families():
    fam = load_family("goland_4flaps")
    A, B, C, D = fam.arrays
    sig = fam.signals
    iu, iy = sig.input_index(), sig.output_index()
    B, C, D = B.copy(), C.copy(), D.copy()
    B[:, :, iu] /= CONTROL_UNITS                 # u_new = c u_old
    C[:, iy, :] *= SENSOR_UNITS[:, None]         # y_new = s y_old
    D[:, iy, :] *= SENSOR_UNITS[:, None]
    D[:, :, iu] /= CONTROL_UNITS
    units = list(sig.output_units)
    for i, name in zip(iy, SENSOR_NAMES):
        units[i] = name
    sig2 = FamilySignals(sig.inputs, sig.outputs, sig.controls, sig.measurements,
                         input_units=("deg",) * len(sig.inputs), output_units=units)
    other = GriddedFamily(fam.speeds, A, B, C, D, sig2, speed_unit=fam.speed_unit,
                          time_unit=fam.time_unit, feedback=fam.feedback, name="other units")
    return fam, other


@pytest.fixture(scope="module")
def controller(families):
    """An order-2 design on the family (stability only: the objective is what is compared,
    not how it was minimised)."""
    from casflutter.design import MultiSpeedSettings, design_over_speeds

    fast = MultiSpeedSettings(hinf_speeds=0, random_starts=1, full_order=False)
    return design_over_speeds(families[0], (60.0, 130.0), 2, settings=fast, seed=0).controller


def _norms(fam, K, unit_free: bool) -> list[float]:
    sc = Scaling.of([design_partition(fam, V) for V in np.linspace(60.0, 150.0, 5)])
    out = []
    for V in SPEEDS:
        for side in ("output", "input"):
            ch = DesignChannels(sensitivity=side)
            P = design_partition(fam, V, ch)
            if unit_free:
                P = unit_free_sensitivity(P, ch, sc.su, sc.sy, _units(fam, side))
            T = _as_ss(P).lft(K, nu=K.noutputs, ny=K.ninputs)
            out.append(float(hinf_norm(T).gamma))
    return out


def test_the_objective_is_the_same_in_every_unit(families, controller):
    """The six norms (output and input sensitivity at three speeds) of one loop written
    in two sets of units agree to 1e-6; the plain output sensitivities' norms differ by
    more than 10 % (what the scaling removes)."""
    fam, other = families
    K = controller
    # the same controller in the other units: u_new = c K (y_new / s)
    K2 = control.ss(K.A, K.B / SENSOR_UNITS[None, :], CONTROL_UNITS[:, None] * K.C,
                    CONTROL_UNITS[:, None] * K.D / SENSOR_UNITS[None, :])
    a, b = _norms(fam, K, True), _norms(other, K2, True)
    assert all(np.isfinite(a)), a
    np.testing.assert_allclose(b, a, rtol=1e-6)
    plain_a, plain_b = _norms(fam, K, False), _norms(other, K2, False)
    assert max(abs(x / y - 1) for x, y in zip(plain_a[::2], plain_b[::2])) > 0.1
    np.testing.assert_allclose(plain_b[1::2], plain_a[1::2], rtol=1e-6)   # one flap unit


def test_signals_in_one_unit_and_the_disturbance_channels_are_left_as_they_are(families):
    """Signals all in one unit (or none declared): a change of it is ``D = c I``, which
    cancels, and the plant is returned as it is (no rounding added): the flaps' input
    sensitivity here, the seed wing's two accelerometers; the disturbance-to-sensor
    channels (no sensitivity) likewise."""
    fam, _ = families
    out, inp = DesignChannels(sensitivity="output"), DesignChannels(sensitivity="input")
    P = design_partition(fam, 100.0, inp)
    assert _units(fam, "input") == ("rad",) * 4
    assert unit_free_sensitivity(P, inp, np.arange(1.0, 5.0), np.ones(8), ("rad",) * 4) is P
    P = design_partition(fam, 100.0, out)
    assert unit_free_sensitivity(P, out, np.ones(4), np.arange(1.0, 9.0), ("",) * 8) is P
    Q = design_partition(fam, 100.0, DesignChannels())
    assert unit_free_sensitivity(Q, DesignChannels(), np.full(4, 7.0),
                                 np.full(8, 5.0), ("a", "b") * 4) is Q
