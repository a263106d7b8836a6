"""``casflutter bench interval``: bad requests are refused before any design work.

The benchmark itself takes minutes (two continuations and the exact intervals); what it
computes is tested in ``tests/design/test_interval_reach.py``.  One short run carries a saved
controller over part of the interval (``--start``), another continues random order-3 starts
from the top (``--random-orders``); both check their record against the verification layer.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest

from casflutter.cli import main
from casflutter.verify import controller_from_json

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"


@pytest.mark.parametrize("args, words", [
    (["--interval", "2.4,0.05"], "LO < HI"),
    (["--interval", "a,b"], "numbers"),
    (["--orders", "0"], "orders >= 1"),
    (["--random-orders", "0"], "orders >= 1"),
    (["--random-orders", "x"], "--random-orders K,K"),
    (["--random-orders", "3", "--random-starts", "0"], "--random-starts >= 1"),
    (["--random-orders", "3", "--seed", "-2"], "--seed >= 0"),
])
def test_bad_arguments_exit_2_at_once(tmp_path, capsys, args, words):
    t0 = time.perf_counter()
    assert main(["bench", "interval", "--out", str(tmp_path / "b.json"), *args]) == 2
    assert time.perf_counter() - t0 < 5
    assert words in capsys.readouterr().err


def test_a_rom_file_without_the_loop_is_named(tmp_path, capsys):
    bad = tmp_path / "rom.npz"
    np.savez(bad, Af=np.eye(2))
    assert main(["bench", "interval", "--rom", str(bad), "--out",
                 str(tmp_path / "b.json")]) == 2
    err = capsys.readouterr().err
    assert "rom.npz" in err and "missing" in err and "Vf" in err
    assert not (tmp_path / "b.json").exists()          # nothing written


def test_an_output_that_is_not_json_is_refused(tmp_path, capsys):
    assert main(["bench", "interval", "--out", str(tmp_path / "b.txt")]) == 2
    assert "--out" in capsys.readouterr().err


def test_truth_model_refuses_a_bad_servo_before_any_work(tmp_path, capsys):
    t0 = time.perf_counter()
    assert main(["bench", "interval", "--model", "truth", "--servo", "0", "--out",
                 str(tmp_path / "b.json")]) == 2
    assert time.perf_counter() - t0 < 10
    assert "servo_omega" in capsys.readouterr().err
    assert not (tmp_path / "b.json").exists()


def test_a_start_controller_of_the_wrong_shape_is_refused_before_any_work(tmp_path, capsys):
    bad = tmp_path / "k.json"
    bad.write_text('{"A": [[-1.0]], "B": [[1.0, 1.0, 1.0]], "C": [[1.0]], '
                   '"D": [[0.0, 0.0, 0.0]]}')          # three sensors; the loop has two
    t0 = time.perf_counter()
    assert main(["bench", "interval", "--start", str(bad), "--out",
                 str(tmp_path / "b.json")]) == 2
    assert time.perf_counter() - t0 < 10
    err = capsys.readouterr().err
    assert "k.json" in err and "3 inputs" in err and "2 sensors" in err
    assert not (tmp_path / "b.json").exists()


def test_a_static_start_is_refused_before_any_work(tmp_path, capsys):
    gain = tmp_path / "k.json"
    gain.write_text('{"D": [[1.0, 2.0]]}')
    assert main(["bench", "interval", "--start", str(gain), "--out",
                 str(tmp_path / "b.json")]) == 2
    assert "static gain" in capsys.readouterr().err
    assert not (tmp_path / "b.json").exists()


def test_a_start_that_does_not_hold_the_low_end_is_recorded_with_the_reason(tmp_path):
    bad = tmp_path / "unstable.json"          # its own pole at +1 stays in the closed loop
    bad.write_text('{"A": [[1.0]], "B": [[1e-6, 1e-6]], "C": [[1e-6]], "D": [[0.0, 0.0]]}')
    out = tmp_path / "b.json"
    assert main(["bench", "interval", "--start", str(bad), "--orders", "", "--no-full-order",
                 "--interval", "0.05,1.0", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    (run,) = doc["runs"]
    assert run["reached"] is None and not run["met"] and "anchor" in run["error"]
    assert doc["summary"]["highest_upper_end_from_low"] is None
    assert not doc["summary"]["target_certified_by_any"]


def test_a_missing_start_file_and_a_bad_rom_servo_are_named(tmp_path, capsys):
    assert main(["bench", "interval", "--start", str(tmp_path / "none.json"), "--out",
                 str(tmp_path / "b.json")]) == 2
    assert "none.json" in capsys.readouterr().err
    assert main(["bench", "interval", "--servo", "-1", "--out", str(tmp_path / "b.json")]) == 2
    assert "servo omega = -1.0 must be > 0" in capsys.readouterr().err
    assert not (tmp_path / "b.json").exists()


def test_a_saved_controller_is_continued_on_the_rom_loop_with_the_servo(tmp_path):
    """The wing's best order-3 controller carried over (0.05, 1.0) of the default ROM loop
    with the flap behind the 40 Hz servo: the continuation's claim (a dense eigenvalue scan)
    is certified by the verification layer's exact interval, computed independently."""
    out = tmp_path / "b.json"
    start = WITNESS_DIR / "truth_best_order3_controller.json"
    assert main(["bench", "interval", "--start", str(start), "--orders", "",
                 "--no-full-order", "--servo", "251.3", "--interval", "0.05,1.0",
                 "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["model"] == "rom" and doc["servo_omega"] == 251.3
    (run,) = doc["runs"]
    assert run["start"].startswith("file ") and run["order"] == 3
    assert run["met"] and run["reached"] == [0.05, 1.0]
    lo, hi = run["verified_exact_interval"]
    assert lo <= 0.05 and hi >= 1.0                    # the certificate covers the claim
    assert doc["summary"]["target_certified_by_any"]
    # below the ROM loop's flutter speed (1.2) the flutter mode is stable: no dip to report
    grip = doc["flutter_mode_grip"]
    assert "weakest_unstable_V" not in grip and grip["worst_overlap"] >= 0.9
    assert 55 < grip["eigenvalue_at_hi"][1] < 65


def test_random_order3_starts_from_the_high_end_are_recorded_and_certified(tmp_path,
                                                                          default_rom_loop):
    """Four seeded order-3 starts at the top of the frozen ROM loop with the servo, kept
    stable themselves: the one that held (2.2, 2.4) is recorded with the count of starts that
    held the top, and the verification layer's exact interval covers its claim."""
    out = tmp_path / "b.json"
    assert main(["bench", "interval", "--random-orders", "3", "--random-ends", "high",
                 "--random-starts", "4", "--random-stable",
                 "--orders", "", "--no-full-order", "--servo", "251.3",
                 "--interval", "2.2,2.4", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    (run,) = doc["runs"]
    assert run["anchor"] == "high" and run["order"] == 3 and run["random_starts"] == 4
    assert run["stable_controller"] and run["controller_spectral_abscissa"] <= -0.05 + 1e-9
    assert 1 <= run["held_the_anchor"] <= 4 and len(run["far_ends"]) == run["held_the_anchor"]
    assert run["met"] and run["reached"] == [2.2, 2.4]
    lo, hi = run["verified_exact_interval"]
    assert lo <= 2.2 and hi >= 2.4
    # the recorded controller is the one certified: its closed loop decays on (2.2, 2.4)
    K = controller_from_json(run["controller"])
    family = default_rom_loop[0]
    family = family.with_servo(251.3)
    assert run["controller_spectral_abscissa"] == pytest.approx(
        np.max(np.linalg.eigvals(K.A).real), abs=1e-9)
    assert K.nstates == 3 and all(
        np.max(np.linalg.eigvals(family.closed_loop_state_matrix(V, K)).real) < 0
        for V in np.linspace(2.2, 2.4, 11))
    assert doc["summary"]["lowest_lower_end_from_high"] == 2.2
    assert doc["summary"]["by_order"] == {"3": {"highest_upper_end_from_low": None,
                                                "lowest_lower_end_from_high": 2.2}}


def test_the_flutter_mode_grip_record_finds_the_frozen_rom_loops_dip(default_rom_loop):
    from casflutter.cli.bench.interval import _flutter_mode_grip
    rom, Vf = default_rom_loop
    rec = _flutter_mode_grip(rom.with_servo(251.3), 0.05, 2.4)
    assert 1.85 < rec["weakest_unstable_V"] < 2.05 and rec["growth_rate_there"] > 6
    assert rec["grip_there"] < rec["grip_at_onset"] / 3       # almost four times weaker
    assert min(rec["phase_swing_deg"]) > 180


def test_a_truncation_that_does_not_hold_the_low_end_is_recorded_not_dropped(
        closed_loop_abscissa, default_rom_loop):
    """The truth runs (full order from the top, then its balanced truncations from the low end)
    on a short top band of the frozen ROM loop with the servo, a family of the same kind that
    runs in seconds: every truncation leaves a record, continued when its loop decays at the
    low end and refused with the reason when it does not, as the loop closed by
    python-control on the recorded full-order controller says."""
    import control

    from casflutter.cli.bench.interval import _truth_runs
    family = default_rom_loop[0]
    family = family.with_servo(251.3)
    doc = {"runs": []}
    _truth_runs(family, 2.3, 2.4, [1, 4], doc, lambda: None)
    full, *truncations = doc["runs"]
    assert full["anchor"] == "high" and full["reached"] == [2.3, 2.4]
    lo, hi = full["verified_exact_interval"]
    assert lo <= 2.3 and hi >= 2.4
    assert [r["order"] for r in truncations] == [1, 4]
    K = controller_from_json(full["controller"])
    outcomes = []
    for run in truncations:
        Kr = control.balred(K, run["order"], method="truncate")
        Kr = control.ss(Kr.A, Kr.B, Kr.C, np.zeros_like(np.asarray(Kr.D)))
        holds = closed_loop_abscissa(family, Kr, 2.3) < 0
        outcomes.append(holds)
        assert (run["reached"] is not None) == holds
        if not holds:
            assert not run["met"] and "anchor V = 2.3" in run["error"]
    assert outcomes == [False, True]        # both kinds of record are exercised
