"""A ROM loop family with the flap behind a servo (:class:`ServoSystem`).

Fixture: ``default_rom_loop`` (the default run's ΣAE).  Truth used: the
servo's transfer function multiplied in by hand, and python-control closing the loop.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.aeroelastic import ServoSystem
from casflutter.errors import ConfigError
from casflutter.verify import load_controller

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"

OMEGA, ZETA = 251.3, 0.7


@pytest.fixture(scope="module")
def system(default_rom_loop):
    return default_rom_loop[0]


def test_every_speed_has_the_servo_in_front_of_the_flap(system):
    family = system.with_servo(OMEGA, ZETA)
    assert isinstance(family, ServoSystem) and family.system is system
    for V in (0.4, 1.3, 2.2):
        G, Gs = system.loop(V).flap_to_sensors(), family.loop(V).flap_to_sensors()
        assert Gs.nstates == G.nstates + 2
        for w in (2.0, 60.0, 500.0):
            s = 1j * w
            servo = OMEGA ** 2 / (s * s + 2 * ZETA * OMEGA * s + OMEGA ** 2)
            np.testing.assert_allclose(Gs(s), G(s) * servo, rtol=1e-8)
        np.testing.assert_array_equal(family.state_matrix(V), family.loop(V).A)


def test_the_closed_loop_is_python_controls(system):
    family = system.with_servo(OMEGA)
    K = load_controller(WITNESS_DIR / "truth_interval_controller_order8.json")
    for V in (0.5, 1.7):
        cl = control.feedback(family.loop(V).flap_to_sensors(), K, sign=1)
        np.testing.assert_allclose(
            np.sort_complex(np.linalg.eigvals(family.closed_loop_state_matrix(V, K))),
            np.sort_complex(np.linalg.eigvals(cl.A)), rtol=1e-7, atol=1e-6)


@pytest.mark.parametrize("omega, zeta", [(0.0, 0.7), (-5.0, 0.7), (100.0, -0.1),
                                         (float("inf"), 0.7)])
def test_a_bad_servo_is_refused(system, omega, zeta):
    with pytest.raises(ConfigError, match="servo omega"):
        system.with_servo(omega, zeta)
