"""What ``casflutter run`` shows a person: one line per stage on stderr (the optimiser's
iterations only with ``--verbose``), numbers with at most 6 significant digits on screen,
γ said for what it is, a skipped stage once."""

import contextlib
import io
import re

import pytest

from casflutter.cli import main
from casflutter.pipeline import config_path

#: a number written with more than 6 significant digits (e.g. 9.153151391264155)
LONG_NUMBER = re.compile(r"\d\.\d{6,}|\d{2}\.\d{5,}|\d{3}\.\d{4,}")


@pytest.fixture(scope="module")
def typical_section_check(tmp_path_factory):
    """The typical section's flutter check (V0 iterated 4 times, order-2 synthesis,
    verification, closed loop): stdout and stderr of a default and a --verbose run (captured
    here: capsys is per test)."""
    out = {}
    cfg = str(config_path("typical_section", "flutter_check"))
    for flags in ((), ("--verbose",)):
        folder = tmp_path_factory.mktemp("run")
        err, std = io.StringIO(), io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(std):
            assert main([*flags, "run", cfg, "--out", str(folder / "o")]) == 0
        out[flags] = (std.getvalue(), err.getvalue())
    return out


def test_the_default_progress_is_one_line_per_stage(typical_section_check):
    _, err = typical_section_check[()]
    lines = err.strip().splitlines()
    stages = [ln for ln in lines if re.match(r"\[\d+/\d+\] ", ln)]
    assert len(stages) == int(stages[0].split("/")[1].split("]")[0])   # each stage once
    assert len(lines) <= len(stages) + 4, err                          # and a few notes
    assert not any(" it " in ln for ln in lines)


def test_the_iterations_show_with_verbose(typical_section_check):
    _, err = typical_section_check[("--verbose",)]
    assert re.search(r"start 0 \(\w+\) hinf it \d+: ", err)
    assert re.search(r"stage controller: \d+\.\d\d s", err)


def test_numbers_on_screen_have_a_few_digits_and_gamma_says_what_it_is(typical_section_check):
    std, err = typical_section_check[()]
    assert not LONG_NUMBER.search(std + err), LONG_NUMBER.findall(std + err)
    assert "verified γ = " in std and "of the LFT at Vf, eq. 16" in std
    assert "H-inf norm over the 4 design plant(s)" in err      # the synthesis's own γ
