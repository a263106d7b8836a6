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


def test_set_changes_keys_of_the_configuration(tmp_path):
    """``--set KEY=VALUE`` is ``load_config(updates=...)``: values read as in the file (a
    list, a number, a problem parameter), recorded in config.json, and the run the same as the
    one configured from Python with those updates."""
    import json

    from casflutter.pipeline import load_config, run

    cfg = config_path("typical_section", "flutter")
    updates = {"stages": [], "flutter.n_grid": 61, "problem.set.mu": 25.0}
    out = tmp_path / "o"
    assert main(["run", str(cfg), "--set", "stages=[]", "--set", "flutter.n_grid=61",
                 "--set", "problem.set.mu=25.0", "--out", str(out), "--quiet"]) == 0
    written = json.loads((out / "config.json").read_text())
    assert written["stages"] == [] and written["flutter"]["n_grid"] == 61
    assert written["problem"]["set"] == {"mu": 25.0}
    here = run(load_config(cfg, updates=updates), quiet=True)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["flutter"]["V"] == pytest.approx(here.flutter.Vf, rel=1e-9)
    # and the change took: the heavier section flutters faster than the file's mu = 20
    assert here.flutter.Vf > run(load_config(cfg, updates={"stages": []}), quiet=True).flutter.Vf
