"""States that feed no output and no other state: a family's rigid-body positions.

A small family (two flexible modes whose speed-dependent coupling flutters near V = 1.23,
one control, two sensors, 9 grid speeds) with two position states appended, each
integrating one of the kept velocity states, seen by no sensor and feeding nothing.

Truths used: the transfer function ``C (sI - A)^-1 B + D`` of the full and the reduced
plants computed here with numpy at complex frequencies between the grid speeds (independent
of the package), and the arrays of the file as written.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from casflutter._resources import problems_dir
from casflutter.aeroelastic import FamilySignals, GriddedFamily, load_family
from casflutter.data import FamilyFile, read_family_file
from casflutter.design import MultiSpeedSettings, design_over_speeds
from casflutter.errors import ConfigError

SPEEDS = np.linspace(0.0, 2.4, 9)
POSITIONS = (4, 5)


def positions_arrays(speeds=SPEEDS, *, grow: float = 0.0, extra: int = 0):
    """``(A, B, C, D)``: states q1, q2, q1', q2' of two modes coupled by ``0.5 V`` (skew:
    coalescence flutter), then the positions x4 = ∫ q1' and x5 = ∫ q2' (x5 with the
    eigenvalue ``grow``), then ``extra`` states that feed nothing (zero columns)."""
    k, n = speeds.size, 6 + extra
    A, B = np.zeros((k, n, n)), np.zeros((k, n, 1))
    C, D = np.zeros((k, 2, n)), np.zeros((k, 2, 1))
    for s, V in enumerate(speeds):
        A[s, :2, 2:4] = np.eye(2)
        A[s, 2:4, :2] = -np.array([[1.0, 0.5 * V], [-0.5 * V, 2.25]])
        A[s, 2:4, 2:4] = -np.diag([0.04, 0.06])
        A[s, 4, 2] = A[s, 5, 3] = 1.0
        A[s, 5, 5] = grow
        B[s, 2:4, 0] = [0.3, 1.0]
        C[s, 0, 2] = 1.0                         # a rate gyro on mode 1
        C[s, 1, :4] = [0.2, 1.0, 0.0, 0.3]       # a sensor on mode 2
    return A, B, C, D


def family(arrays=None) -> GriddedFamily:
    return GriddedFamily(SPEEDS, *(positions_arrays() if arrays is None else arrays),
                         FamilySignals(["flap"], ["gyro", "strain"]), name="toy")


def write(tmp_path, arrays=None):
    return FamilyFile(SPEEDS, *(positions_arrays() if arrays is None else arrays),
                      speed_unit="m/s", feedback="negative", name="toy",
                      input_names=("flap",), output_names=("gyro", "strain")
                      ).write(tmp_path / "toy.toml")


def transfer(A, B, C, D, s):
    return C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B) + D


def test_the_positions_are_the_detached_states_and_leaving_them_out_keeps_the_plant():
    full = family()
    assert full.detached_states() == POSITIONS
    red = full.without_states(full.detached_states())
    assert red.n_states == 4 and red.left_out_states == POSITIONS
    assert red.left_out_eigenvalues.shape == (SPEEDS.size, 2)
    assert np.all(red.left_out_eigenvalues == 0)
    assert (red.signals, red.speed_unit, red.feedback, red.name) == \
        (full.signals, full.speed_unit, full.feedback, full.name)
    np.testing.assert_array_equal(red.speeds, full.speeds)
    for V in (0.1, 1.23, 2.05):                  # between grid speeds, flutter among them
        P, R = full.matrices(V), red.matrices(V)
        for s in (0.05j, 1.2j, 0.4 + 2.0j, -0.3 + 0.7j):
            G = transfer(*P, s)
            np.testing.assert_allclose(transfer(*R, s), G, rtol=0, atol=1e-10 * np.abs(G).max())
    assert full.without_states([]) is full


def test_a_state_that_feeds_a_kept_state_is_not_detached_and_cannot_be_left_out():
    A, B, C, D = positions_arrays()
    A[:, 0, 4] = 0.1                             # x4 now feeds q1's equation
    fam = family((A, B, C, D))
    assert fam.detached_states() == (5,)
    with pytest.raises(ConfigError, match=r"state 4 \(0-based\) feeds state 0, which is kept"):
        fam.without_states([4, 5])
    A, B, C, D = positions_arrays()
    C[:, 1, 5] = 1e-3                            # x5 seen, faintly
    fam = family((A, B, C, D))
    assert fam.detached_states() == (4,)
    with pytest.raises(ConfigError, match="state 5 .* feeds the output 'strain'"):
        fam.without_states([5])
    # the tolerance is relative to max |C|: rounding of a column is no feed
    C[:, 1, 5] = 1e-13
    assert family((A, B, C, D)).detached_states() == POSITIONS


def test_the_fixed_point_catches_chains():
    # x6 feeds only the position x5: detached as well
    A, B, C, D = positions_arrays(extra=1)
    A[:, 5, 6] = 1.0
    fam = family((A, B, C, D))
    assert fam.detached_states() == (4, 5, 6)
    red = fam.without_states(fam.detached_states())
    assert red.left_out_states == (4, 5, 6) and np.all(red.left_out_eigenvalues == 0)
    # x5 now feeds q2: x5 goes, and with it x6, found only once x5 has left the set
    A = A.copy()
    A[:, 1, 5] = 0.2
    assert family((A, B, C, D)).detached_states() == (4,)
    # left out in two steps, named by the first family's indices
    red = fam.without_states([4]).without_states([4, 5])
    assert red.left_out_states == (4, 5, 6) and red.n_states == 4


def test_a_family_file_loads_without_its_positions_and_says_so(tmp_path, caplog):
    path = write(tmp_path)
    rec = read_family_file(path)
    with caplog.at_level("INFO", logger="casflutter.aeroelastic"):
        fam = load_family(path)
    assert fam.n_states == 4 and fam.left_out_states == POSITIONS
    assert np.all(fam.left_out_eigenvalues == 0)
    assert "2 of its 6 states left out (0-based indices [4, 5])" in caplog.text
    assert "poles at the origin that feed no output and no other state" in caplog.text
    assert "4 states (2 more left out, which feed no output: states [4, 5])" in fam.describe()
    A, B, C, D = fam.arrays
    np.testing.assert_array_equal(A, rec.A[:, :4, :4])
    np.testing.assert_array_equal(B, rec.B[:, :4])
    np.testing.assert_array_equal(C, rec.C[:, :, :4])
    np.testing.assert_array_equal(D, rec.D)


def test_problems_lists_the_states_analysed_and_the_ones_left_out(tmp_path, capsys):
    from casflutter.cli import main

    path = write(tmp_path)
    assert main(["problems", str(path), "--json"]) == 0
    (info,) = json.loads(capsys.readouterr().out)
    assert (info["n_states"], info["n_states_file"], info["left_out_states"]) == (4, 6, [4, 5])
    assert main(["problems", str(path)]) == 0
    out = capsys.readouterr().out
    assert "plant family: 4 states" in out and "the file has 6 states; states [4, 5]" in out


def test_a_decaying_position_block_is_left_out_and_a_growing_one_is_kept(tmp_path, caplog):
    # one at the origin, one decaying: positions to leave out, nothing that grows
    fam = load_family(write(tmp_path, positions_arrays(grow=-0.5)))
    assert fam.left_out_states == POSITIONS
    np.testing.assert_allclose(fam.left_out_eigenvalues, [[-0.5, 0.0]] * SPEEDS.size)
    # one grows: kept, and the design says that nothing can stabilise it, and how to leave
    # positions out
    caplog.clear()
    with caplog.at_level("INFO", logger="casflutter.aeroelastic"):
        fam = load_family(write(tmp_path, positions_arrays(grow=0.1)))
    assert fam.n_states == 6 and fam.left_out_states == ()
    assert fam.left_out_eigenvalues.shape == (SPEEDS.size, 0)
    assert fam.detached_states() == POSITIONS and "left out" not in caplog.text
    with pytest.raises(ConfigError, match=r"does not decay.*left out when it loads.*"
                       r"family\.without_states\(family\.detached_states\(\)\)"):
        design_over_speeds(fam, (1.0, 1.8), 2, settings=MultiSpeedSettings(hinf_speeds=0))
    # only decaying (no pole at the origin): nothing to leave out
    A, B, C, D = positions_arrays(grow=-0.5)
    A[:, 4, 4] = -0.2
    assert load_family(write(tmp_path, (A, B, C, D))).n_states == 6


def test_goland_is_unchanged():
    fam = load_family("goland_4flaps")
    rec = read_family_file(problems_dir() / "goland_4flaps" / "problem.toml")
    assert fam.n_states == 50 and fam.detached_states() == ()
    assert fam.left_out_states == () and fam.left_out_eigenvalues.shape == (rec.speeds.size, 0)
    for mine, theirs in zip(fam.arrays, (rec.A, rec.B, rec.C, rec.D)):
        np.testing.assert_array_equal(mine, theirs)
