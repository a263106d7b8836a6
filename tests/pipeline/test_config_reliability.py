"""Issue 14, run-config gaps: every bad value of a run configuration is refused at load, in
well under a second and before any stage runs, by a ConfigError naming the key, the value and
what is allowed."""

import time

import pytest

from casflutter.errors import ConfigError
from casflutter.pipeline import load_config


def _write(tmp_path, text, name="run.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("text,match", [
    # the cases of issue 14
    ("seed = -1\n", r"^seed = -1: must be an integer >= 0"),
    ("[flutter]\nn_grid = 0\n", r"^flutter\.n_grid = 0: must be an integer >= 3"),
    ("[rom]\nregularization = nan\n", r"^rom\.regularization = nan: expected a finite number"),
    ("[data]\nband = [\"a\", 60]\n", r"^data\.band = \['a', 60\]: 'a' is not a finite number"),
    # non-finite numbers anywhere
    ("[lco]\nduration = inf\n", r"^lco\.duration = inf: expected a finite number"),
    ("[data]\nV0 = nan\n", r"^data\.V0 = nan: expected a finite number"),
    ("[controller]\ninterval_decay = inf\n",
     r"^controller\.interval_decay = inf: expected a finite number"),
    ("[suppression]\nsettle = -inf\n", r"^suppression\.settle = -inf: expected a finite number"),
    # unknown keys and sections, wrong types
    ("[foo]\nx = 1\n", r"unknown key 'foo' in top level; allowed: problem, data, rom"),
    ("[lco]\ndurration = 3.0\n", r"unknown key 'durration' in \[lco\]; allowed: duration"),
    ("[lco]\nduration = \"long\"\n", r"^lco\.duration: expected a number, got str 'long'"),
    ("[flutter]\nn_grid = 10.5\n", r"^flutter\.n_grid: expected an integer, got float 10.5"),
    ("[controller]\nstrictly_proper = 1\n",
     r"^controller\.strictly_proper: expected true or false"),
    ("stages = \"lco\"\n", r"^stages: expected a list, got str 'lco'"),
])
def test_bad_value_is_named_before_any_work(tmp_path, text, match):
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=match):
        load_config(_write(tmp_path, text))
    assert time.perf_counter() - t0 < 1.0


def test_binary_config_file_is_refused(tmp_path):
    p = tmp_path / "run.toml"
    p.write_bytes(bytes(range(256)))
    with pytest.raises(ConfigError, match=r"is not a UTF-8 text file .*give a TOML text file"):
        load_config(p)
