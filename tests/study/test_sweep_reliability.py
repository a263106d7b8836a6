"""Sweeps that fail, are stopped, share a store or meet a damaged store: exit codes, the
retry of failed points, the store lock, no orphaned workers, undecodable lines, and the
checks made before any point runs."""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import time

import pytest

from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.study import Parameter, PointStore, Study, load_study, run_sweep

from . import _evals

EVALS = _evals.__name__
CLI = "import sys; from casflutter.cli import main; sys.exit(main(sys.argv[1:]))"


def _study_file(tmp_path, n=4, *, settings="", name="sq", workers=0, extra=""):
    f = tmp_path / f"{name}.toml"
    f.write_text(f'[study]\nname = "{name}"\nevaluator = "{EVALS}:square"\nworkers = {workers}\n'
                 f'{extra}[settings]\n{settings}\n[parameters]\n'
                 f'x = {{low = 0, high = {n - 1}, integer = true}}\n')
    return f


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("casflutter: error: "), err
    assert "Traceback" not in err
    return lines[0]


def _env():
    return {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}


# --------------------------------------------------------------- failures and exit codes

def test_failed_points_give_exit_1_and_are_retried_on_resume(tmp_path, capsys):
    f = _study_file(tmp_path, 4, settings="fail = [0, 1, 2, 3]")
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--out", str(out), "--no-plot"]) == 1
    text = capsys.readouterr().out
    assert "0 computed" not in text and "4 failed, 0 left" in text
    assert "4 point(s) failed" in text
    again = main(["sweep", str(f), "--out", str(out), "--no-plot", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert again == 1 and (summary["computed"], summary["resumed"], summary["failed"]) == (4, 0, 4)
    kept = main(["sweep", str(f), "--out", str(out), "--no-plot", "--json", "--keep-failed"])
    summary = json.loads(capsys.readouterr().out)
    assert kept == 1 and (summary["computed"], summary["resumed"], summary["failed"]) == (0, 4, 4)
    # the point that failed and then succeeds: the newest record wins, the exit code is 0
    f.write_text(f.read_text().replace("fail = [0, 1, 2, 3]", "fail = [0, 1, 2, 3]\nsleep = 0"))
    st = load_study(f)
    store = out / "sq.jsonl"
    for p in st.points():
        rec = {"key": st.key(p), "params": p, "status": "ok", "outputs": {"y": p["x"] ** 2}}
        PointStore(store).append(rec)  # as if recomputed successfully
    assert main(["sweep", str(f), "--out", str(out), "--no-plot"]) == 0


def test_max_points_zero_computes_nothing_and_workers_are_checked(tmp_path, capsys):
    f = _study_file(tmp_path, 3)
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--out", str(out), "--no-plot", "--max-points", "0",
                 "--json"]) == 1
    summary = json.loads(capsys.readouterr().out)
    assert (summary["computed"], summary["left"]) == (0, 3)
    assert list(PointStore(out / "sq.jsonl")) == []
    for flag, value, words in (("--workers", "-3", "workers = -3: give 0"),
                               ("--max-points", "-1", "max_points = -1")):
        assert main(["sweep", str(f), "--out", str(out), flag, value]) == 1
        assert words in _one_error_line(capsys.readouterr().err)
    with pytest.raises(ConfigError, match="workers"):
        run_sweep(load_study(f), store=out / "x.jsonl", workers=True)


# --------------------------------------------------------------------- the store lock

def test_a_second_sweep_on_the_same_store_refuses_to_start(tmp_path, capsys):
    from casflutter.errors import StoreLockedError

    f = _study_file(tmp_path, 3)
    out = tmp_path / "out"
    store = PointStore(out / "sq.jsonl")
    with store.lock():
        with pytest.raises(StoreLockedError, match=f"pid {os.getpid()}"):
            run_sweep(load_study(f), store=store.path, workers=0, progress=False)
        assert main(["sweep", str(f), "--out", str(out)]) == 1
        line = _one_error_line(capsys.readouterr().err)
        assert "is in use by another sweep" in line and "--out" in line
    assert list(store) == []  # nothing was computed twice (nor at all)
    assert main(["sweep", str(f), "--out", str(out), "--no-plot"]) == 0  # lock released
    capsys.readouterr()


def test_the_lock_is_held_across_processes_and_freed_when_its_holder_is_killed(tmp_path):
    from casflutter.errors import StoreLockedError

    f = _study_file(tmp_path, 3)
    path = tmp_path / "out" / "sq.jsonl"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from casflutter.study import PointStore\n"
         f"with PointStore({str(path)!r}).lock():\n    print('locked', flush=True)\n"
         "    time.sleep(120)"], env=_env(), stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(StoreLockedError, match=f"pid {holder.pid}"):
            run_sweep(load_study(f), store=path, workers=0, progress=False)
    finally:
        holder.kill()  # SIGKILL: no clean-up runs, the system frees the lock
        holder.wait(30)
    res = run_sweep(load_study(f), store=path, workers=0, progress=False)
    assert (res.n_computed, res.n_failed, res.n_left) == (3, 0, 0)


# ------------------------------------------------------------- stopping: no orphans

def _children(pid):
    psutil = pytest.importorskip("psutil")
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


N_STOP = 8


def _stop_sweep(tmp_path, sig, *, group):
    psutil = pytest.importorskip("psutil")
    f = _study_file(tmp_path, N_STOP, settings="sleep = 0.3", workers=2)
    out = tmp_path / "out"
    cmd = [sys.executable, "-c", CLI, "sweep", str(f), "--out", str(out), "--no-plot"]
    proc = subprocess.Popen(cmd, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    store = out / "sq.jsonl"
    workers = []
    try:
        t0 = time.time()
        while time.time() - t0 < 120:
            workers = [c for c in _children(proc.pid) if "python" in c.name().lower()]
            if store.exists() and len(store.read_text().splitlines()) >= 2 and len(workers) >= 2:
                break
            time.sleep(0.05)
        assert len(workers) >= 2, "the workers did not start"
        if group:  # Ctrl-C in a terminal reaches the whole process group
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(30)
    _, alive = psutil.wait_procs(workers, timeout=10)
    assert alive == [], f"orphaned workers: {alive}"
    stored = PointStore(store).records()
    assert 2 <= len(stored) < N_STOP
    return proc.returncode, err, f, out, stored


def test_sigterm_stops_the_workers_and_the_sweep_resumes(tmp_path):
    code, err, f, out, stored = _stop_sweep(tmp_path, signal.SIGTERM, group=False)
    assert code == 143, err
    assert "terminated (SIGTERM)" in err and "run the same command again to resume" in err
    assert "Traceback" not in err
    res = run_sweep(load_study(f), store=out / "sq.jsonl", workers=0, progress=False)
    assert (res.n_resumed, res.n_computed, res.n_left) == (len(stored), N_STOP - len(stored), 0)
    recs = list(PointStore(out / "sq.jsonl"))
    assert len(recs) == N_STOP
    assert sorted(r["outputs"]["y"] for r in recs) == [x * x for x in range(N_STOP)]


@pytest.mark.slow
def test_ctrl_c_to_the_process_group_stops_quietly_without_orphans(tmp_path):
    code, err, *_ = _stop_sweep(tmp_path, signal.SIGINT, group=True)
    assert code == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err  # workers ignore it


# ------------------------------------------------------------- a damaged store

def test_undecodable_and_garbage_lines_are_skipped_with_a_warning(tmp_path, caplog):
    st = Study(name="sq", evaluator=f"{EVALS}:square",
               parameters=(Parameter("x", values=(0.0, 1.0, 2.0, 3.0)),))
    store = tmp_path / "sq.jsonl"
    first = run_sweep(st, store=store, workers=0, progress=False, max_points=2)
    assert first.n_computed == 2
    with open(store, "ab") as fh:
        fh.write(b'{"key": "\xff\xfe not utf-8", "status": "ok"}\n')
        fh.write(b"\x00\x01\x02 binary garbage \x80\n")
        fh.write(b'["a list, not a record"]\n')
    assert len(PointStore(store).records()) == 2
    with caplog.at_level(logging.WARNING, logger="casflutter"):
        res = run_sweep(st, store=store, workers=0, progress=False)
    assert (res.n_resumed, res.n_computed, res.n_left) == (2, 2, 0)
    assert any("3 line(s)" in r.getMessage() for r in caplog.records)
    assert sorted(r["outputs"]["y"] for r in PointStore(store)) == [0.0, 1.0, 4.0, 9.0]


# ------------------------------------------------- checks before any point runs

@pytest.mark.parametrize("study_table, settings, words", [
    ('samples = "many"\ndesign = "lhs"\n', "", "samples = 'many': give an integer"),
    ("workers = -1\n", "", "workers = -1: give an integer >= 0"),
    ('outputs = "y"\n', "", "give a list of output names"),
    ('name = "../escape"\n', "", "without '/'"),
    ("", "when = 2024-01-01", "TOML date"),
    ("", "level = nan", "not a finite number"),
])
def test_bad_study_file_values_are_refused(tmp_path, capsys, study_table, settings, words):
    f = tmp_path / "s.toml"
    f.write_text(f'[study]\nevaluator = "{EVALS}:square"\n{study_table}[settings]\n{settings}\n'
                 "[parameters]\nx = [1.0, 2.0]\n")
    assert main(["sweep", str(f), "--out", str(tmp_path / "out")]) == 1
    assert words in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("spec, words", [
    ('{low = "a", high = 1}', "low = 'a' must be a finite number"),
    ('{low = 0, high = 1, num = "3"}', "num = '3' must be an integer"),
    ('{low = 0.2, high = 0.8, integer = true}', "no integer between"),
    ("[1.0, inf]", "not a finite number"),
])
def test_bad_parameter_tables_are_refused(tmp_path, capsys, spec, words):
    f = tmp_path / "s.toml"
    f.write_text(f'[study]\nevaluator = "{EVALS}:square"\n[parameters]\nx = {spec}\n')
    assert main(["sweep", str(f), "--out", str(tmp_path / "out")]) == 1
    assert words in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("settings, outputs, words", [
    ('V_min = "low"', "", "V_min = 'low': give a finite number"),
    ("n_grid = 0", "", "n_grid = 0: give an integer >= 3"),
    ("V_min = 3.0\nV_max = 2.0", "", "must be below V_max"),
    ("lco_speed_ratio = -1.1", "", "lco_speed_ratio = -1.1: give a finite number > 0"),
    ("", 'outputs = ["Vf", "Vff"]', "outputs ['Vff'] are not outputs of the evaluator"),
])
def test_bad_settings_and_outputs_fail_the_preflight_check(tmp_path, capsys, settings, outputs,
                                                           words):
    f = tmp_path / "ts.toml"
    f.write_text(f'[study]\nname = "ts"\nevaluator = "truth_flutter"\nworkers = 0\n{outputs}\n'
                 f'[settings]\nproblem = "typical_section"\n{settings}\n'
                 "[parameters]\nmu = [15.0, 20.0]\n")
    assert main(["sweep", str(f), "--out", str(tmp_path / "out")]) == 1
    assert words in _one_error_line(capsys.readouterr().err)
    assert list(PointStore(tmp_path / "out" / "ts.jsonl")) == []  # no point ran


def test_synthesis_settings_are_checked_before_any_point(tmp_path):
    from pathlib import Path

    plant = Path(__file__).resolve().parents[2] / "problems" / "compleib" / "AC4.json"
    st = Study(name="syn", evaluator="synthesis", parameters=(Parameter("order", values=(0,)),),
               settings={"plant": str(plant), "starts": 0})
    with pytest.raises(ConfigError, match="starts = 0: give an integer >= 1"):
        run_sweep(st, store=tmp_path / "s.jsonl", workers=0, progress=False)
    assert list(PointStore(tmp_path / "s.jsonl")) == []


# ------------------------------------------------------------------------ logging

def test_progress_is_logged_and_a_library_user_can_silence_or_route_it(tmp_path, capsys):
    st = Study(name="sq", evaluator=f"{EVALS}:square",
               parameters=(Parameter("x", values=(0.0, 1.0, 2.0)),))
    seen: list[logging.LogRecord] = []

    class Keep(logging.Handler):
        def emit(self, record):
            seen.append(record)

    logger = logging.getLogger("casflutter")
    h = Keep()
    logger.addHandler(h)
    old = logger.level
    try:
        logger.setLevel(logging.INFO)
        run_sweep(st, store=tmp_path / "a.jsonl", workers=0)
        lines = [r.getMessage() for r in seen if r.name == "casflutter.study._runner"]
        assert lines and "3/3 done (0 resumed), 0 failed, 0 left" in lines[-1]
        seen.clear()
        logger.setLevel(logging.WARNING)  # silenced
        run_sweep(st, store=tmp_path / "b.jsonl", workers=0)
        assert seen == []
    finally:
        logger.removeHandler(h)
        logger.setLevel(old)
    assert capsys.readouterr().err == ""  # nothing printed by the library itself


def test_quiet_keeps_the_result_lines_and_drops_the_progress(tmp_path, capsys):
    f = _study_file(tmp_path, 3)
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--out", str(out), "--no-plot", "--quiet"]) == 0
    cap = capsys.readouterr()
    assert "sq: 3 points (grid) on inline: 3 computed" in cap.out and cap.err == ""
    assert main(["--quiet", "sweep", str(f), "--out", str(out), "--no-plot"]) == 0
    cap = capsys.readouterr()
    assert "3 resumed" in cap.out and cap.err == ""
    assert main(["sweep", str(f), "--out", str(out), "--no-plot"]) == 0
    assert "3/3 done (3 resumed)" in capsys.readouterr().err
