"""Issue 14, run-config gaps: every bad value of a run configuration is refused at load, in
well under a second and before any stage runs, by a ConfigError naming the key, the value and
what is allowed."""

import time
from dataclasses import fields

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
    ("[lco]\ndurration = 3.0\n", r"unknown key 'durration' in \[lco\] \(did you mean 'duration'\?\); allowed: duration"),
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


@pytest.mark.parametrize("text,match", [
    # the exact order of the seed wing ROM's linear part: 5 modes x largest lag 5 of the
    # paper's orders (3, 1, 1, 1, 2, 2) = 25 states
    ("[rom]\nnf = 1000\n", r"^rom\.nf = 1000: at most 25 here .*5 modes of 'seed_wing'.*"
                           r"give 1\.\.25 or \"auto\""),
    ("[rom]\nnf = 26\n", r"^rom\.nf = 26: at most 25"),
    # common denominator na = 2, nb = 6: largest lag 6, 30 states
    ("stages = []\n[rom]\nmethod = \"common_denominator\"\nnf = 31\n",
     r"^rom\.nf = 31: at most 30 .*na = 2, nb = 6"),
    ("[data]\ncoupling_delay = 100000\n",
     r"^data\.coupling_delay = 100000: must be an integer from 0 to 3999 samples .*"
     r"duration / dt = 4000 samples.*steps of dt, not seconds"),
])
def test_limits_from_the_data_are_stated(tmp_path, text, match):
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=match):
        load_config(_write(tmp_path, text))
    assert time.perf_counter() - t0 < 1.0


def test_nf_up_to_the_exact_order_is_accepted(tmp_path):
    assert load_config(_write(tmp_path, "[rom]\nnf = 25\n")).rom.nf == 25
    cd = "stages = []\n[rom]\nmethod = \"common_denominator\"\nnf = 30\n"
    assert load_config(_write(tmp_path, cd)).rom.nf == 30


def test_nf_bound_is_the_realisation_bound():
    """The bound the configuration states is the one the realisation reports for an
    identified ROM (common-denominator ROM of short seed-wing records, na = 2, nb = 6)."""
    from casflutter._settings import settings_as
    from casflutter.ident import identify_common_denominator
    from casflutter.realize import realize
    from casflutter.truth import RecordSettings, truth_records

    cfg = load_config(updates={"stages": [], "rom.method": "common_denominator",
                               "data.duration": 1.0})
    data = truth_records(cfg.problem.load(), settings_as(cfg.data, RecordSettings),
                         V0=cfg.data.V0)
    real = realize(identify_common_denominator(data, cfg.rom.na, cfg.rom.nb).model)
    assert real.exact_order_bound == 30
    with pytest.raises(ConfigError, match=r"at most 30"):
        load_config(updates={"stages": [], "rom.method": "common_denominator", "rom.nf": 31})


def test_empty_config_is_the_papers_study(tmp_path):
    """The code defaults are problems/seed_wing/run_paper.toml: an empty file runs that
    study.  The default configuration (run.toml) differs from it in the controller and the
    suppression tunnel only."""
    from casflutter.pipeline import RunConfig, config_path, default_config_path

    paper = load_config(config_path("seed_wing", "run_paper"))
    assert load_config(_write(tmp_path, "")) == paper
    assert RunConfig() == paper
    default = load_config(default_config_path())
    changed = {f.name for f in fields(RunConfig)
               if getattr(default, f.name) != getattr(paper, f.name)}
    assert changed == {"controller", "suppression"}


@pytest.mark.parametrize("text,words", [
    ("seed = -1\n", ["seed = -1", "integer >= 0"]),
    ("[flutter]\nn_grid = 0\n", ["flutter.n_grid = 0", "integer >= 3"]),
    ("[rom]\nnf = 1000\n", ["rom.nf = 1000", "at most 25"]),
    ("[rom]\nregularization = nan\n", ["rom.regularization = nan", "finite number"]),
    ("[data]\nband = [\"a\", 60]\n", ["data.band", "'a' is not a finite number"]),
    ("[data]\ncoupling_delay = 100000\n", ["data.coupling_delay = 100000", "0 to 3999"]),
    ('[solver.ipopt]\n"ipopt.fooo" = 1\n', ["solver.ipopt", "unknown Ipopt option 'ipopt.fooo'"]),
    ("[nonsense]\nx = 1\n", ["unknown key 'nonsense'", "allowed: problem"]),
])
def test_cli_run_refuses_before_any_stage(tmp_path, capsys, monkeypatch, text, words):
    """``casflutter run``: one line naming the key, exit 1, no stage run, no output folder."""
    import casflutter.pipeline as pipeline
    from casflutter.cli import main

    def no_run(*a, **k):
        raise AssertionError("a stage ran although the configuration is invalid")

    monkeypatch.setattr(pipeline, "run", no_run)
    t0 = time.perf_counter()
    rc = main(["run", str(_write(tmp_path, text)), "--out", str(tmp_path / "out")])
    assert time.perf_counter() - t0 < 1.0
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and err[0].startswith("casflutter: error: ")
    assert all(w in err[0] for w in words), err[0]
    assert not (tmp_path / "out").exists()


def test_cli_run_refuses_a_binary_config(tmp_path, capsys):
    from casflutter.cli import main

    p = tmp_path / "run.toml"
    p.write_bytes(b"\x00\xff\xfe\x89PNG\r\n")
    assert main(["run", str(p), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a UTF-8 text file" in err[0] and str(p) in err[0]


def test_cli_run_checks_the_output_folder_before_any_stage(tmp_path, capsys, monkeypatch):
    """``casflutter run --out afile/sub`` used to compute for 45 s and then fail."""
    import casflutter.pipeline as pipeline
    from casflutter.cli import main

    def no_run(*a, **k):
        raise AssertionError("a stage ran although the output folder cannot be made")

    monkeypatch.setattr(pipeline, "run", no_run)
    (tmp_path / "afile").write_text("")
    assert main(["run", "--out", str(tmp_path / "afile" / "sub")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--out" in err[0] and "is a file, not a folder" in err[0]


def test_finite_numbers_takes_numpy_vectors_and_scalars_and_names_what_is_wrong():
    """The shared check of "finite numbers" (config fields, speed intervals, speed profiles):
    a 1-D numpy array and numpy scalars are numbers; a string, a bool, a NaN or a 2-D array
    is refused with the field's name."""
    import numpy as np

    from casflutter._settings import finite_numbers
    assert finite_numbers("v", np.array([0.0, 2.4])) == (0.0, 2.4)
    assert finite_numbers("v", (np.float32(0.5), np.int64(2)), 2) == (0.5, 2.0)
    for bad, words in ((["a"], "'a' is not a finite number"), ([True], "True"),
                       ([float("nan")], "nan"), (np.zeros((2, 2)), "give"),
                       ("ab", "give")):
        with pytest.raises(ConfigError, match=f"(?s)v = .*{words}"):
            finite_numbers("v", bad)
