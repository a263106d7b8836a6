"""casflutter's own warnings on the command line: one ``casflutter: warning:`` line each,
also when a command meets the same warning twice (while it checks its input and again
inside the run), and never Python's ``file:line: DataWarning:`` form."""

import subprocess
import sys
import pytest
from truth.test_wing_file_sampling import _wing

from casflutter.cli import main


def _lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if "contradicts the time channel" in line]


@pytest.fixture()
def wing(tmp_path):
    """A two-mode wing file whose records.dt (2 ms) contradicts its time channel (4 ms)."""
    return _wing(tmp_path, records="dt = 0.002")


def test_problems_says_a_load_warning_once_in_the_cli_form(wing, capsys):
    assert main(["problems", str(wing)]) == 0
    lines = _lines(capsys.readouterr().err)
    assert len(lines) == 1 and lines[0].startswith("casflutter: warning: wing file")


def test_run_says_it_once_though_the_file_is_read_twice(wing, tmp_path):
    """In a process of its own: pytest records the warnings of an in-process call, and the
    doubled line came from Python's own warning display."""
    cfg = tmp_path / "run.toml"
    cfg.write_text(f'stages = []\n[problem]\nname = "{wing.name}"\n[rom]\nnf = "auto"\n')
    err = subprocess.run([sys.executable, "-m", "casflutter", "run", str(cfg), "--out",
                          str(tmp_path / "out")], capture_output=True, text=True,
                         timeout=600).stderr
    lines = _lines(err)
    assert len(lines) == 1 and lines[0].startswith("casflutter: warning: wing file")
    assert "DataWarning" not in err
