"""Controller poles against the data's Nyquist frequency and the actuator, and the speed
units of the exports (speed index, airspeed, dynamic pressure)."""

from __future__ import annotations

import logging
from types import SimpleNamespace

import control
import numpy as np
import pytest

from casflutter.pipeline._exports import controller_pole_check, log_flags
from casflutter.pipeline._units import interval_values, speed_scale, speed_values


def _controller(*hz):
    """A first-order-per-pole controller with real poles at the given frequencies [Hz]."""
    p = [-2 * np.pi * f for f in hz]
    n = len(p)
    return control.ss(np.diag(p), np.ones((n, 2)), np.ones((1, n)), np.zeros((1, 2)))


def test_poles_above_the_nyquist_frequency_of_2ms_data_are_flagged():
    # the controller: poles at 3978 Hz and 507 Hz, records sampled every 2 ms
    check = controller_pole_check(_controller(3978.0, 507.0, 3.0), dt=0.002)
    assert check["nyquist_hz"] == pytest.approx(250.0, rel=1e-12)
    assert check["faster_than_nyquist"] is True and check["faster_than_actuator"] is None
    assert check["natural_frequencies_hz"] == pytest.approx([3978.0, 507.0, 3.0], rel=1e-12)
    (text,) = check["warnings"]
    assert text.startswith("controller poles at 3978, 507 Hz are faster than the 250 Hz "
                           "Nyquist frequency")


def test_slow_poles_pass_and_the_actuator_bandwidth_is_checked():
    check = controller_pole_check(_controller(20.0, 3.0), dt=0.002)
    assert check["faster_than_nyquist"] is False and check["warnings"] == []
    act = 2 * np.pi * 10.0                                    # a 10 Hz flap actuator
    check = controller_pole_check(_controller(20.0, 3.0), dt=0.002, actuator_omega=act)
    assert check["faster_than_actuator"] is True
    assert check["actuator_bandwidth_hz"] == pytest.approx(10.0, rel=1e-12)
    assert check["warnings"] == ["controller poles at 20 Hz are faster than the flap actuator "
                                 "(10 Hz, closed_loop.actuator_omega)"]
    assert controller_pole_check(control.ss([], [], [], [[1.0, 2.0]]), dt=0.002) is None
    # a problem in its own time unit: no Hz
    text = controller_pole_check(_controller(1.0), dt=0.1, time_unit="1/omega_theta",
                                 actuator_omega=1.0)["warnings"][0]
    assert "cycles per 1/omega_theta" in text and "Hz" not in text


def test_poles_far_faster_than_the_plant_are_flagged():
    """A controller pole more than 100 times faster than every pole of the plant it was
    designed on is flagged; the plant's speed is that of its fastest pole over the speeds."""
    from casflutter.aeroelastic import GriddedFamily
    from casflutter.pipeline._exports import plant_speed

    speeds = np.array([1.0, 2.0, 3.0])
    fam = GriddedFamily(speeds, [[[-2 * np.pi * 0.5 * v]] for v in speeds],
                        np.ones((3, 1, 1)), np.ones((3, 1, 1)), np.zeros((3, 1, 1)))
    omega = plant_speed(fam, 1.0, 2.5)
    assert omega == pytest.approx(2 * np.pi * 1.25, rel=1e-12)   # the pole at V = 2.5
    check = controller_pole_check(_controller(200.0, 100.0), dt=None, plant_omega=omega)
    assert check["plant_fastest_hz"] == pytest.approx(1.25, rel=1e-12)
    assert check["faster_than_plant"] is True
    (text,) = check["warnings"]
    assert text.startswith("controller poles at 200 Hz are more than 100 times faster than "
                           "the plant's fastest pole (1.25 Hz")
    slow = controller_pole_check(_controller(100.0), dt=None, plant_omega=omega)
    assert slow["faster_than_plant"] is False and slow["warnings"] == []


def test_the_run_logs_a_warning_for_fast_controller_poles(caplog):
    result = SimpleNamespace(
        controller=_controller(3978.0, 507.0),
        config=SimpleNamespace(stages=("controller",),
                               closed_loop=SimpleNamespace(actuator_omega=10.0)),
        identification=SimpleNamespace(model=SimpleNamespace(dt=0.002)), data=None,
        system=SimpleNamespace(structure=SimpleNamespace(time_unit="s")))
    with caplog.at_level(logging.WARNING, logger="casflutter.pipeline"):
        log_flags(result)
    (rec,) = caplog.records
    assert rec.levelno == logging.WARNING and "Nyquist" in rec.getMessage()


def test_goland_speeds_in_index_metres_per_second_and_pascal():
    from casflutter.truth import load_problem

    g = load_problem("goland")
    p = g.params
    scale = speed_scale(g)
    V = 1.7
    U = V * p.b * p.omega_ref                       # V = U / (b omega_ref)
    got = speed_values(V, scale)
    assert got["speed_index"] == V
    assert got["airspeed_m_s"] == pytest.approx(U, rel=1e-14)
    assert got["dynamic_pressure_Pa"] == pytest.approx(0.5 * 1.225 * U ** 2, rel=1e-14)
    iv = interval_values((0.5, float("inf")), scale)
    assert iv["speed_index"] == [0.5, None] and iv["airspeed_m_s"][1] is None


def test_a_problem_without_a_speed_scale_has_only_the_speed_index():
    from casflutter.truth import load_problem

    scale = speed_scale(load_problem("typical_section"))
    assert speed_values(2.0, scale) == {"speed_index": 2.0}
    assert scale.speed_index_label.startswith("speed index (V = U / (b omega_theta)")


def test_a_discrete_controller_file_is_refused_not_misread(tmp_path, capsys):
    from casflutter.cli import main
    from casflutter.verify import controller_to_json, plant_to_json, save_json

    P = control.ss([[-1.0]], [[1.0, 1.0]], [[1.0], [1.0]], np.zeros((2, 2)))
    save_json(plant_to_json(P, 1, 1), tmp_path / "plant.json")
    doc = controller_to_json(control.ss([[-0.5]], [[1.0]], [[0.1]], [[0.0]]))
    for time_base, code in (({"domain": "continuous", "dt": None}, 0),
                            ({"domain": "discrete", "dt": 0.002}, 1),
                            ({"domain": "sampled"}, 1)):
        save_json({**doc, "time_base": time_base}, tmp_path / "controller.json")
        assert main(["verify", str(tmp_path / "plant.json"),
                     str(tmp_path / "controller.json")]) == code
        out, err = capsys.readouterr()
        if time_base["domain"] == "discrete":
            assert "discrete time (dt=0.002)" in err
        elif code:
            assert "time_base" in err and "continuous" in err
        else:
            assert "PASSED" in out


def test_an_unstable_controller_is_flagged():
    """A controller pole at +0.975 rad/s (an aircraft family's order-2 design): stable only
    inside the loop, which an engineer must be told."""
    K = control.ss([[0.975, 0.0], [0.0, -3.0]], np.ones((2, 1)), np.ones((1, 2)), [[0.0]])
    check = controller_pole_check(K, dt=None)
    assert check["unstable"] is True
    (text,) = check["warnings"]
    assert text.startswith("the controller itself is unstable (poles at 0.975 rad per s)")
    assert controller_pole_check(_controller(3.0), dt=None)["unstable"] is False
