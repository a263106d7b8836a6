"""``casflutter bench interval``: bad requests are refused before any design work.

The benchmark itself takes minutes (two continuations and the exact intervals); what it
computes is tested in ``tests/design/test_interval_reach.py``.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from casflutter.cli import main


@pytest.mark.parametrize("args, words", [
    (["--interval", "2.4,0.05"], "LO < HI"),
    (["--interval", "a,b"], "numbers"),
    (["--orders", "0"], "orders >= 1"),
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
