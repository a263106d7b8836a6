"""Plant families to and from family files: any family sampled by write_family loads back as
a GriddedFamily with the same plants at the grid speeds, signals, roles, units and feedback;
the shipped .npz and .mat files hold the same arrays; role errors name the closest signal.

Truth used: the family's own plants at the grid speeds (exact, the file stores them).
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from casflutter._resources import problems_dir
from casflutter.aeroelastic import (GriddedFamily, TruthLoop, family_record, load_family,
                                    write_family)
from casflutter.data import read_family_file
from casflutter.errors import ConfigError
from casflutter.truth import SeedWing


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_a_loop_family_written_and_loaded_gives_its_plants(tmp_path, fmt):
    loop = TruthLoop(SeedWing(), 251.3)
    speeds = np.linspace(0.8, 1.2, 5)
    path = write_family(loop, tmp_path / "seed.toml", speeds, fmt, description="test")
    fam = load_family(path)
    assert isinstance(fam, GriddedFamily)
    assert fam.signals == loop.signals
    assert (fam.feedback, fam.speed_unit, fam.time_unit) == ("positive", "speed index", "s")
    assert fam.name == loop.name and fam.speed_degree == 1
    for V in speeds:
        want, got = loop.plant(V), fam.plant(V)
        for a, b in zip((want.A, want.B, want.C, want.D), (got.A, got.B, got.C, got.D)):
            assert_array_equal(np.asarray(b), np.asarray(a))
    # between grid speeds: the elementwise average (what "linear" means)
    assert_allclose(fam.state_matrix(0.85), 0.5 * (loop.state_matrix(0.8)
                                                   + loop.state_matrix(0.9)), rtol=1e-14,
                    atol=1e-12)


def test_write_family_refuses_speeds_outside_the_range(tmp_path):
    fam = load_family(problems_dir() / "seed_wing_family")
    with pytest.raises(ConfigError, match="outside the range"):
        family_record(fam, [0.5, 1.0])
    with pytest.raises(ConfigError, match="must be a casflutter.aeroelastic.PlantFamily"):
        family_record(object(), [1.0, 2.0])


def test_role_names_are_checked_with_the_closest_signal(tmp_path):
    rec = read_family_file(problems_dir() / "goland_4flaps" / "problem.toml")
    bad = type(rec)(**{**{k: getattr(rec, k) for k in (
        "speeds", "A", "B", "C", "D", "speed_unit", "feedback", "input_names",
        "output_names")}, "controls": ("flap_1", "flap5")})
    with pytest.raises(ConfigError, match="'flap5': did you mean 'flap_4'"):
        load_family(bad)


@pytest.mark.parametrize("name", ["goland_4flaps", "seed_wing_family"])
def test_shipped_npz_and_mat_files_hold_the_same_family(name):
    a = load_family(problems_dir() / name)
    b = load_family(problems_dir() / name / "problem_mat.toml")
    for x, y in zip(a.arrays, b.arrays):
        assert_array_equal(x, y)
    assert_array_equal(a.speeds, b.speeds)
    assert a.signals == b.signals and a.feedback == b.feedback and a.name == b.name


def test_the_50_state_family_has_the_planned_size_and_signals():
    fam = load_family(problems_dir() / "goland_4flaps")
    sig = fam.signals
    assert (fam.n_states, len(sig.inputs), len(sig.outputs), fam.speeds.size) == (50, 4, 8, 41)
    assert sig.controls == ("flap_1", "flap_2", "flap_3", "flap_4")
    assert sig.measurements[:2] == ("gyro_50", "gyro_100")
    assert set(sig.output_units) == {"rad/s", "m/s^2"} and fam.feedback == "negative"
