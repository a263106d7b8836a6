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


def test_role_names_with_blanks_match_as_the_data_file_names_do(tmp_path):
    # the data file's names are stripped (a MATLAB char matrix pads them): so are the roles
    rng = np.random.default_rng(1)
    np.savez(tmp_path / "g.npz", speeds=[10.0, 20.0], A=-np.ones((2, 1, 1)),
             B=rng.standard_normal((2, 1, 2)), C=rng.standard_normal((2, 2, 1)),
             D=np.zeros((2, 2, 2)), input_names=np.array(["flap ", "gust"]),
             output_names=np.array(["gyro", "acc"]))
    (tmp_path / "f.toml").write_text('kind = "plant_family"\nfile = "g.npz"\n'
                                     'speed_unit = "m/s"\nfeedback = "negative"\n'
                                     'controls = [" flap"]\nmeasurements = ["acc "]\n')
    fam = load_family(tmp_path / "f.toml")
    assert fam.signals.controls == ("flap",) and fam.signals.measurements == ("acc",)
    assert fam.signals.disturbances == ("gust",)


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


def _recoordinated(rec, transforms):
    """The record's models, each in the coordinates ``x = T x'`` of its own ``T``."""
    A, B, C, D = (np.asarray(M) for M in (rec.A, rec.B, rec.C, rec.D))
    inv = [np.linalg.inv(T) for T in transforms]
    fields = {k: getattr(rec, k) for k in ("speeds", "speed_unit", "feedback", "input_names",
                                           "output_names")}
    return type(rec)(**fields, A=np.stack([Ti @ a @ T for Ti, a, T in zip(inv, A, transforms)]),
                     B=np.stack([Ti @ b for Ti, b in zip(inv, B)]),
                     C=np.stack([c @ T for c, T in zip(C, transforms)]), D=D)


def test_models_exported_each_in_its_own_coordinates_are_named(caplog):
    """The shipped 50-state family is in one realisation: no interval is named and nothing
    is logged.  The same 41 models, each in coordinates of its own (a seeded orthogonal
    change of basis; or every other model with its states re-ordered and a fifth of them
    sign-flipped, as a modal solver re-normalising its mode shapes would give), are the same
    plants at the grid speeds (frequency responses equal to 1e-5, the rounding of the
    50-state resolvent in another basis; an independent check), but
    interpolated between them they are not: every interval is named, and the loader warns
    with the first of them."""
    rec = read_family_file(problems_dir() / "goland_4flaps" / "problem.toml")
    with caplog.at_level("WARNING", logger="casflutter"):
        assert load_family(rec).realisation_gaps() == ()
    assert not caplog.records
    n, k = np.asarray(rec.A).shape[1], len(rec.speeds)
    rng = np.random.default_rng(7)
    rotated = [np.linalg.qr(rng.standard_normal((n, n)))[0] for _ in range(k)]
    relabelled = [np.eye(n) if j % 2 == 0 else
                  np.eye(n)[rng.permutation(n)] @ np.diag(np.where(rng.random(n) < 0.2, -1, 1))
                  for j in range(k)]
    for transforms in (rotated, relabelled):
        other = _recoordinated(rec, transforms)
        ref = load_family(rec)
        caplog.clear()
        with caplog.at_level("WARNING", logger="casflutter"):
            fam = load_family(other)
        for V in (rec.speeds[0], rec.speeds[20], rec.speeds[-1]):
            for w in (1.0, 30.0, 300.0):
                g0 = np.asarray(ref.plant(V)(1j * w))
                g1 = np.asarray(fam.plant(V)(1j * w))
                assert_allclose(g1, g0, rtol=1e-5, atol=1e-5 * np.abs(g0).max())
        gaps = fam.realisation_gaps()
        assert [(g.lo, g.hi) for g in gaps] == list(zip(rec.speeds[:-1], rec.speeds[1:]))
        assert all(g.pole_distance > 0.3 for g in gaps)
        assert len(caplog.records) == 1
        assert "states seem to change meaning" in caplog.text and "40 of 40" in caplog.text
        assert f"first {rec.speeds[0]:g}-{rec.speeds[1]:g} m/s" in caplog.text


def test_a_coarse_grid_in_one_realisation_is_not_named():
    """The seed wing's own loop sampled at 4 speeds over (0.05, 2.4), one realisation: its
    poles move far between neighbours (up to the flutter mode's instability), and no
    interval is named."""
    loop = TruthLoop(SeedWing(), 251.3)
    speeds = np.linspace(0.05, 2.4, 4)
    fam = load_family(family_record(loop, speeds))
    assert fam.realisation_gaps() == ()
