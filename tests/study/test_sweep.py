"""The sweep engine: results, failures, resumption, killed workers and drivers, solver reuse."""

import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from casflutter.study import (Parameter, PointStore, Progress, Study, plot_sweep, run_sweep,
                              sweep_table, write_table)

from . import _evals

EVALS = _evals.__name__


def _square_study(n=8, **settings):
    return Study(name="sq", evaluator=f"{EVALS}:square",
                 parameters=(Parameter("x", values=tuple(float(i) for i in range(n))),),
                 settings=settings)


def _truth_study(evaluator="truth_flutter"):
    return Study(name="ts", evaluator=evaluator,
                 parameters=(Parameter("mu", values=(15.0, 20.0, 30.0)),
                             Parameter("sigma", values=(0.3, 0.4))),
                 settings={"problem": "typical_section", "V_min": 0.02, "V_max": 4.0})


def test_truth_flutter_sweep_matches_direct_analysis(tmp_path):
    from casflutter.aeroelastic import find_flutter
    from casflutter.truth import load_problem, problem_definition

    st = _truth_study()
    res = run_sweep(st, store=tmp_path / "ts.jsonl", workers=0, progress=False)
    assert (res.n_points, res.n_computed, res.n_failed, res.n_left) == (6, 6, 0, 0)
    rows = {(r["mu"], r["sigma"]): r for r in sweep_table(st, res.store)}
    for (mu, sigma), row in rows.items():
        m = load_problem("typical_section", [f"mu={mu}", f"sigma={sigma}"])
        direct = find_flutter(m.state_matrix, (0.02, 4.0), n_grid=81)
        np.testing.assert_allclose(row["Vf"], direct.Vf, rtol=1e-12)
        np.testing.assert_allclose(row["omega_f"], direct.omega_f, rtol=1e-12)
    ref = problem_definition("typical_section")["reference"]["jones"]
    np.testing.assert_allclose(rows[(20.0, 0.4)]["Vf"], ref["flutter_speed"], rtol=ref["rtol"])


def test_failures_are_recorded_and_do_not_stop_the_sweep(tmp_path):
    st = _square_study(8, fail=[3.0, 5.0])
    buf = io.StringIO()
    res = run_sweep(st, store=tmp_path / "sq.jsonl", workers=0, progress=False)
    assert (res.n_computed, res.n_failed, res.n_left) == (8, 2, 0)
    recs = {r["params"]["x"]: r for r in PointStore(res.store)}
    assert recs[3.0]["status"] == "failed"
    assert recs[3.0]["error"] == "ValueError: x = 3.0 is not allowed here"
    assert "ValueError" in recs[3.0]["traceback"]
    assert all(recs[x]["outputs"]["y"] == x * x for x in recs if x not in (3.0, 5.0))
    # resuming recomputes only the failed points (they fail again here); keeping them
    # (retry_failed=False) counts them as done
    again = run_sweep(st, store=res.store, workers=0, progress=False)
    assert (again.n_resumed, again.n_computed, again.n_failed) == (6, 2, 2)
    kept = run_sweep(st, store=res.store, workers=0, progress=False, retry_failed=False)
    assert (kept.n_resumed, kept.n_computed, kept.n_failed) == (8, 0, 2)
    st_ok = _square_study(8)
    assert st_ok.key({"x": 3.0}) != st.key({"x": 3.0})  # settings are part of the key
    prog = Progress(10, skipped=4, stream=buf, interval=0.0)
    prog.update({"status": "ok"})
    prog.update({"status": "failed"})
    prog.close()
    last = buf.getvalue().strip().splitlines()[-1]
    assert "6/10 done (4 resumed), 1 failed, 4 left" in last


def test_resume_does_not_recompute_or_lose_points(tmp_path):
    st = _square_study(10)
    store = tmp_path / "sq.jsonl"
    first = run_sweep(st, store=store, workers=0, progress=False, max_points=4)
    assert first.interrupted and (first.n_computed, first.n_left) == (4, 6)
    before = PointStore(store).records()
    second = run_sweep(st, store=store, workers=0, progress=False)
    assert (second.n_resumed, second.n_computed, second.n_left) == (4, 6, 0)
    lines = [json.loads(s) for s in store.read_text().splitlines()]
    assert len(lines) == 10 and len({r["key"] for r in lines}) == 10  # nothing twice
    after = PointStore(store).records()
    assert all(after[k] == before[k] for k in before)


def test_local_processes_reuse_one_parametric_solver_per_worker(tmp_path):
    st = Study(name="hopf", evaluator="truth_hopf",
               parameters=(Parameter("a", low=-0.4, high=0.0, num=4),
                           Parameter("mu", values=(15.0, 20.0, 30.0))),
               settings={"problem": "typical_section"})
    inline = run_sweep(st, store=tmp_path / "a.jsonl", workers=0, progress=False).records()
    res = run_sweep(st, store=tmp_path / "h.jsonl", workers=2, progress=False)
    recs = res.records()
    assert res.executor == "processes(2)" and res.n_failed == 0 and len(recs) == 12
    assert set(recs) == set(inline)
    for k in recs:  # same arithmetic in the workers, bit for bit
        assert recs[k]["outputs"]["Vf"] == inline[k]["outputs"]["Vf"]
    # the Hopf NLP is built once per worker process and reused for all its points
    assert all(r["outputs"]["solver_builds"] == 1 for r in recs.values())
    pids = [r["outputs"]["pid"] for r in recs.values()]
    assert os.getpid() not in pids
    assert len(set(pids)) <= 2 and len(pids) > len(set(pids))
    # and it gives the flutter speed of the eigenvalue tracking (Brent-refined)
    flut = run_sweep(Study(name="f", evaluator="truth_flutter", parameters=st.parameters,
                           settings=st.settings), store=tmp_path / "f.jsonl", workers=0,
                     progress=False).records()
    by_params = {json.dumps(r["params"], sort_keys=True): r["outputs"]["Vf"] for r in flut.values()}
    for r in recs.values():
        np.testing.assert_allclose(r["outputs"]["Vf"],
                                   by_params[json.dumps(r["params"], sort_keys=True)], rtol=1e-9)


def test_killed_worker_is_replaced_and_no_point_is_lost(tmp_path):
    st = Study(name="c", evaluator=f"{EVALS}:crash_once",
               parameters=(Parameter("x", values=tuple(float(i) for i in range(6))),),
               settings={"crash_x": 2.0, "marker": str(tmp_path / "marker")})
    res = run_sweep(st, store=tmp_path / "c.jsonl", workers=2, progress=False)
    assert (tmp_path / "marker").exists()  # the worker really died once
    assert res.worker_restarts == 1
    assert (res.n_failed, res.n_left) == (0, 0)
    assert sorted(r["outputs"]["y"] for r in res.records().values()) == [0, 1, 4, 9, 16, 25]


@pytest.mark.slow
def test_point_that_always_kills_its_worker_is_recorded_failed(tmp_path):
    st = Study(name="c", evaluator=f"{EVALS}:crash_always",
               parameters=(Parameter("x", values=tuple(float(i) for i in range(5))),),
               settings={"crash_x": 1.0})
    res = run_sweep(st, store=tmp_path / "c.jsonl", workers=2, progress=False)
    recs = {r["params"]["x"]: r for r in res.records().values()}
    assert (res.n_failed, res.n_left) == (1, 0)
    assert recs[1.0]["status"] == "failed" and "worker process died" in recs[1.0]["error"]
    assert all(recs[x]["outputs"]["y"] == x * x for x in (0.0, 2.0, 3.0, 4.0))


_DRIVER = """
import sys
sys.path[:0] = {paths!r}
from casflutter.study import Study, Parameter, run_sweep
if __name__ == "__main__":
    st = Study(name="k", evaluator={ev!r},
               parameters=(Parameter("x", values=tuple(float(i) for i in range(16))),),
               settings={{"sleep": 0.25}})
    run_sweep(st, store={store!r}, workers=2, progress=False)
"""


def test_killed_driver_resumes_without_recomputing(tmp_path):
    store = tmp_path / "k.jsonl"
    script = tmp_path / "driver.py"
    script.write_text(_DRIVER.format(paths=[p for p in sys.path if p], ev=f"{EVALS}:square",
                                     store=str(store)))
    proc = subprocess.Popen([sys.executable, str(script)], start_new_session=True)
    try:
        t0 = time.time()
        while time.time() - t0 < 90:
            if store.exists() and len(store.read_text().splitlines()) >= 4:
                break
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)  # the driver and its workers, mid-sweep
    finally:
        proc.wait(30)
    stored = PointStore(store).records()
    assert 4 <= len(stored) < 16
    st = Study(name="k", evaluator=f"{EVALS}:square",
               parameters=(Parameter("x", values=tuple(float(i) for i in range(16))),),
               settings={"sleep": 0.25})
    res = run_sweep(st, store=store, workers=0, progress=False)
    assert res.n_resumed == len(stored) and res.n_computed == 16 - len(stored)
    valid = list(PointStore(store))
    assert len(valid) == 16 and len({r["key"] for r in valid}) == 16
    after = PointStore(store).records()
    assert all(after[k] == stored[k] for k in stored)  # finished points kept untouched


def test_table_csv_and_plot(tmp_path):
    st = _square_study(6, fail=[4.0])
    res = run_sweep(st, store=tmp_path / "sq.jsonl", workers=0, progress=False)
    rows = sweep_table(st, res.store)
    assert [r["x"] for r in rows] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    files = write_table(rows, tmp_path / "out" / "sq")
    with open(files[0]) as fh:
        table = list(csv.DictReader(fh))
    assert list(table[0])[:3] == ["key", "status", "x"]
    assert [float(r["y"]) if r["y"] else None for r in table] == [0, 1, 4, 9, None, 25]
    assert table[4]["status"] == "failed" and "not allowed" in table[4]["error"]
    try:
        import pyarrow  # noqa: F401
        assert files[1].suffix == ".parquet"
    except ImportError:
        assert len(files) == 1
    fig = plot_sweep(rows, ["x"], ["y"])
    assert len(fig.axes) == 1
    line = fig.axes[0].lines[0]
    np.testing.assert_array_equal(line.get_ydata(), [0, 1, 4, 9, 25])


def test_dask_local_cluster_gives_the_same_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    st = _truth_study("truth_hopf")
    inline = run_sweep(st, store=tmp_path / "a.jsonl", workers=0, progress=False).records()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        res = run_sweep(st, store=tmp_path / "d.jsonl", scheduler=cluster.scheduler_address,
                        progress=False, max_points=4)
        assert res.interrupted and res.n_computed == 4
        res = run_sweep(st, store=tmp_path / "d.jsonl", scheduler=cluster.scheduler_address,
                        progress=False)
    assert res.executor.startswith("dask(tcp://127.0.0.1")
    assert (res.n_resumed, res.n_computed, res.n_failed, res.n_left) == (4, 2, 0, 0)
    recs = res.records()
    assert set(recs) == set(inline)
    for k in recs:
        np.testing.assert_allclose(recs[k]["outputs"]["Vf"], inline[k]["outputs"]["Vf"],
                                   rtol=1e-12)
    assert len({r["worker"] for r in recs.values()}) >= 1


def test_rom_flutter_evaluator_passes_the_pipeline_through(tmp_path):
    from casflutter.pipeline import config_path, load_config, run

    st = Study(name="rom", evaluator="rom_flutter",
               parameters=(Parameter("data.V0", values=(1.8,)),),
               settings={"problem": "typical_section", "flutter.n_grid": 61})
    res = run_sweep(st, store=tmp_path / "r.jsonl", workers=0, progress=False)
    rec = next(iter(res.records().values()))
    assert rec["status"] == "ok", rec.get("error")
    cfg = load_config(config_path("typical_section", "flutter"),
                      updates={"data.V0": 1.8, "flutter.n_grid": 61, "stages": ["frozen"]})
    direct = run(cfg, quiet=True, write=False)
    out = rec["outputs"]
    np.testing.assert_allclose(out["Vf_truth"], direct.flutter_truth.Vf, rtol=1e-12)
    np.testing.assert_allclose(out["Vf_rom"], direct.flutter.Vf, rtol=1e-9)
    np.testing.assert_allclose(out["rom_error"], direct.rom_error, rtol=1e-6)


def test_synthesis_evaluator_gamma_vs_order(tmp_path):
    from casflutter.design import load_compleib
    from casflutter.study import load_study

    root = Path(__file__).resolve().parents[2] / "problems"
    st = load_study(root / "studies" / "compleib_ac4_orders.toml")
    st = Study(**{**st.__dict__, "parameters": (Parameter("order", values=(0,)),),
                  "settings": {**st.settings, "starts": 1}})
    res = run_sweep(st, store=tmp_path / "s.jsonl", workers=0, progress=False)
    rec = next(iter(res.records().values()))
    assert rec["status"] == "ok", rec.get("error")
    out = rec["outputs"]
    _, _, _, meta = load_compleib(root / "compleib" / "AC4.json")
    assert out["success"] and out["spectral_abscissa"] < 0
    assert out["gamma"] >= meta["gamma_full_order_lmi"] * (1 - 1e-6)  # full order bounds it
    np.testing.assert_allclose(out["delta_bound"], 1.0 / out["gamma"], rtol=1e-12)


@pytest.mark.slow
def test_ctrl_c_stops_the_sweep_and_the_same_command_resumes(tmp_path):
    study = tmp_path / "sq.toml"
    study.write_text(f'[study]\nname = "sq"\nevaluator = "{EVALS}:square"\nworkers = 2\n'
                     '[settings]\nsleep = 0.1\n'
                     '[parameters]\nx = {low = 0, high = 15, integer = true}\n')
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    cmd = [sys.executable, "-c", "import sys; from casflutter.cli import main; "
           "sys.exit(main(sys.argv[1:]))", "sweep", str(study), "--out", str(out),
           "--no-plot"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    store = out / "sq.jsonl"
    t0 = time.time()
    while time.time() - t0 < 90:
        if store.exists() and len(store.read_text().splitlines()) >= 3:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)  # Ctrl-C to the driver only
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "run the same command again to resume" in err
    stored = PointStore(store).records()
    assert 3 <= len(stored) < 16
    done = subprocess.run(cmd + ["--workers", "0", "--json"], env=env, capture_output=True,
                          text=True, timeout=120)
    summary = json.loads(done.stdout)
    assert (summary["resumed"], summary["computed"], summary["left"]) == (
        len(stored), 16 - len(stored), 0)
    valid = list(PointStore(store))
    assert len({r["key"] for r in valid}) == 16 == len(valid)
    assert sorted(r["outputs"]["y"] for r in valid) == [x * x for x in range(16)]


def test_output_named_like_a_column_does_not_hide_the_point_status(tmp_path):
    st = Study(name="clash", evaluator=f"{EVALS}:square",
               parameters=(Parameter("x", values=(1.0, 2.0)),), settings={"fail": [2.0]})
    res = run_sweep(st, store=tmp_path / "c.jsonl", workers=0, progress=False)
    store = PointStore(res.store)
    rec = store.records()[st.key({"x": 1.0})]
    store.append({**rec, "outputs": {**rec["outputs"], "status": "flutter", "x": -1}})
    rows = {r["x"]: r for r in sweep_table(st, res.store)}
    assert rows[1.0]["status"] == "ok" and rows[1.0]["out_status"] == "flutter"
    assert rows[1.0]["out_x"] == -1 and rows[2.0]["status"] == "failed"


def test_a_sweep_point_takes_a_rig_file(tmp_path):
    """A study's problem may be a rig file (by name, or a path beside the study file):
    its parameters are swept like a built-in problem's."""
    from casflutter._resources import problems_dir
    from casflutter.errors import ConfigError
    from casflutter.study._truth_point import load_truth

    truth, options = load_truth({"c_h": 0.0}, {"problem": "nata", "V_min": 1.0})
    assert truth.params.c_h == 0.0 and options == {"V_min": 1.0}
    (tmp_path / "rig.toml").write_text((problems_dir() / "nata" / "problem.toml").read_text())
    truth, _ = load_truth({"rho": 1.0}, {"problem": "rig.toml", "_base_dir": str(tmp_path)})
    assert truth.params.rho == 1.0 and truth.params.k_alpha[0] == 2.82
    with pytest.raises(ConfigError, match="unknown problem 'nope.toml'"):
        load_truth({}, {"problem": "nope.toml", "_base_dir": str(tmp_path)})
