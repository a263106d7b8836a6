"""The command line's one rule for failures: a casflutter error is one line on stderr that
names the input, the problem and the fix, with exit code 1 and no traceback (unless
``--debug``); a bug is one line with a hint to rerun with ``--debug``; a closed stdout is
quiet; the logging flags work before or after the sub-command."""

from __future__ import annotations

import logging
import os
import subprocess
import sys

import numpy as np
import pytest

import casflutter
from casflutter.cli import main

CLI = "import sys; from casflutter.cli import main; sys.exit(main(sys.argv[1:]))"


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("casflutter: error: ") and "Traceback" not in err, err
    return lines[0]


def _bad_inputs(tmp):
    """(argv, words that must appear: the input, the problem, the fix)."""
    (tmp / "empty.npz").write_bytes(b"")
    (tmp / "bin.toml").write_bytes(b"\x00\xff\xfe\x00 not text")
    (tmp / "adir.toml").mkdir()
    (tmp / "sens.toml").write_text('[sensitivity]\nV_min = "low"\n')
    (tmp / "gamma.toml").write_text('[gamma]\nplant = "x:y"\nnmeas = 1\nncon = 0\n')
    (tmp / "study.toml").write_text('[study]\nevaluator = "truth_flutter"\nsamples = "many"\n'
                                    "[parameters]\nmu = [15.0]\n")
    (tmp / "ok.toml").write_text('[study]\nevaluator = "truth_flutter"\n'
                                 "[parameters]\nmu = [15.0]\n")
    (tmp / "afile").write_text("")
    return [
        (["identify", str(tmp / "empty.npz")], [str(tmp / "empty.npz"), "empty file",
                                                "np.savez"]),
        (["sweep", str(tmp / "bin.toml")], [str(tmp / "bin.toml"), "not a UTF-8 text file",
                                            "give a TOML text file"]),
        (["sweep", str(tmp / "adir.toml")], [str(tmp / "adir.toml"), "is a folder",
                                             "the TOML file inside it"]),
        (["sweep", str(tmp / "study.toml"), "--out", str(tmp / "out")],
         [str(tmp / "study.toml"), "samples = 'many'", "give an integer >= 1"]),
        (["sweep", str(tmp / "ok.toml"), "--out", str(tmp / "afile" / "sub")],
         ["--out", str(tmp / "afile"), "is a file, not a folder", "choose another path"]),
        (["sensitivity", str(tmp / "sens.toml")], ["[sensitivity] V_min = 'low'",
                                                   "give a finite number"]),
        (["sensitivity", str(tmp / "gamma.toml")], ["[gamma] ncon = 0", "give an integer >= 1"]),
        (["demo", "--seed", "-1"], ["--seed -1", "give an integer >= 0"]),
        (["demo", "--noise", "nan"], ["--noise nan", "in [0, 1)"]),
        (["verify", str(tmp / "missing.json"), str(tmp / "K.json")],
         [str(tmp / "missing.json"), "file not found"]),
        (["verify", "goland_4flaps", str(tmp / "K.json"), "--range", "150", "60"],
         ["--range 150 60", "LO must be below HI", "give --range 60 150"]),
        (["problems", "no_such_problem"], ["'no_such_problem'", "available: typical_section"]),
        (["run", "--set", "controller.ordr=3", "--out", str(tmp / "run")],
         ["'ordr' in [controller]", "did you mean 'order'?"]),
        (["run", "--set", "controller.interval=[0.05, 2.0", "--out", str(tmp / "run")],
         ["--set controller.interval=[0.05, 2.0", "is not a value", "a list such as"]),
        (["run", "--set", "seed", "--out", str(tmp / "run")],
         ["--set item 'seed'", "name=value"]),
    ]


def test_every_bad_input_is_one_line_naming_input_problem_and_fix(tmp_path, capsys):
    for argv, words in _bad_inputs(tmp_path):
        code = main(argv)
        cap = capsys.readouterr()
        assert code == 1, argv
        line = _one_error_line(cap.err)
        for w in words:
            assert w in line, (argv, w, line)
        assert cap.out == "", argv


def test_debug_adds_the_traceback(tmp_path, capsys):
    assert main(["--debug", "problems", "no_such_problem"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "ConfigError" in err
    assert err.strip().splitlines()[-1].startswith("casflutter: error: unknown problem")
    assert main(["problems", "no_such_problem", "--debug"]) == 1  # after the command too
    assert "Traceback" in capsys.readouterr().err


def test_an_unexpected_exception_is_one_line_with_a_hint(monkeypatch, capsys):
    from casflutter.cli.commands import problems

    def broken(args):
        raise TypeError("unsupported operand\nsecond line")

    monkeypatch.setattr(problems, "run", broken)
    assert main(["problems"]) == 1
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "Traceback" not in line
    assert line.startswith("casflutter: internal error: TypeError: unsupported operand "
                           "second line") and "--debug" in line
    assert main(["problems", "--debug"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and 'raise TypeError' in err

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(problems, "run", interrupted)
    assert main(["problems"]) == 130
    assert capsys.readouterr().err.strip() == "casflutter: interrupted"


def test_closed_stdout_is_quiet(tmp_path):
    r, w = os.pipe()
    os.close(r)  # `casflutter problems | head` after head has exited
    try:
        proc = subprocess.run([sys.executable, "-c", CLI, "problems"], stdout=w,
                              stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(w)
    assert proc.stderr == "" and proc.returncode == 141


def test_logging_flags_set_the_package_logger_only_while_a_command_runs(monkeypatch, capsys):
    from casflutter.cli.commands import problems

    seen = []

    def record_level(args):
        logger = logging.getLogger("casflutter")
        seen.append(logger.getEffectiveLevel())
        logging.getLogger("casflutter.cli.test").debug("a debug message")
        logging.getLogger("casflutter.cli.test").info("an info message")
        print("the result")
        return 0

    monkeypatch.setattr(problems, "run", record_level)
    logger = logging.getLogger("casflutter")
    before = (logger.level, list(logger.handlers))
    outs = {}
    for argv in (["problems"], ["problems", "--quiet"], ["-q", "problems"],
                 ["problems", "--verbose"], ["-v", "problems"], ["--debug", "problems"]):
        assert main(argv) == 0
        outs[" ".join(argv)] = capsys.readouterr()
    assert seen == [logging.INFO, logging.WARNING, logging.WARNING, logging.DEBUG,
                    logging.DEBUG, logging.DEBUG]
    assert all(c.out == "the result\n" for c in outs.values())  # results stay on stdout
    assert outs["problems"].err == "an info message\n"
    assert outs["problems --quiet"].err == "" and outs["-q problems"].err == ""
    assert outs["problems --verbose"].err == "a debug message\nan info message\n"
    assert "[casflutter.cli.test] a debug message" in outs["--debug problems"].err
    assert (logger.level, list(logger.handlers)) == before  # nothing left behind


def test_package_logger_has_a_null_handler_and_no_output_by_default():
    handlers = logging.getLogger("casflutter").handlers
    assert any(isinstance(h, logging.NullHandler) for h in handlers)
    code = ("import logging, casflutter\n"
            "logging.getLogger('casflutter.study').warning('a library warning')\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0 and proc.stderr == ""  # no lastResort output to stderr


def test_version_flag_and_module_entry_point():
    proc = subprocess.run([sys.executable, "-m", "casflutter", "--version"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip() == f"casflutter {casflutter.__version__}"


def test_identify_data_errors_from_the_loaders_are_one_line(tmp_path, capsys):
    rng = np.random.default_rng(0)
    np.savez(tmp_path / "u3.npz", y=rng.standard_normal((50, 2)),
             u=rng.standard_normal((50, 2, 1)), dt=0.1)
    assert main(["identify", str(tmp_path / "u3.npz")]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert str(tmp_path / "u3.npz") in line and "(50, 2, 1)" in line and "reshape" in line


@pytest.mark.parametrize("argv", [["problems", "--json"], ["problems"]])
def test_results_go_to_stdout_and_nothing_to_stderr(argv, capsys):
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert cap.out and cap.err == ""
