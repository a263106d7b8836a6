"""Same inputs and seed, bit-identical results in two fresh processes launched with different
BLAS/OpenMP thread settings (issue 14): ``casflutter flutter`` (parametric ROM included),
``casflutter identify`` and a short ``casflutter run``.

Each command runs in its own interpreter, once with one thread and once with two; the JSON
they print (and, for ``run``, the files it writes) must agree exactly.  JSON floats are
written with ``repr``, which round-trips every bit, so equal text is equal numbers.  Only the
wall-clock timings, and the record of the thread settings themselves, are left out.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from casflutter.ident import random_hwl_model, synthetic_data

THREADS = ({"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"},
           {"OPENBLAS_NUM_THREADS": "2", "OMP_NUM_THREADS": "2", "MKL_NUM_THREADS": "2"})


def _strip(doc):
    """The document without wall-clock times and thread settings (they differ by design)."""
    if isinstance(doc, dict):
        return {k: _strip(v) for k, v in doc.items()
                if not (k.startswith("timings") or k.endswith("time_s") or "thread" in k)}
    if isinstance(doc, list):
        return [_strip(v) for v in doc]
    return doc


def _cli(args, env_threads, cwd):
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env.update(env_threads, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-m", "casflutter", *args], capture_output=True,
                          text=True, env=env, cwd=cwd, timeout=1800)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


def _twice(args, cwd):
    """The command's JSON in two fresh processes, one and two BLAS threads."""
    first, second = (_strip(_cli(args, t, cwd)) for t in THREADS)
    return first, second


def test_flutter_typical_section_is_bit_identical(tmp_path):
    first, second = _twice(["flutter", "typical_section", "--json", "-q"], tmp_path)
    assert first["parametric_rom"]["status"] == "flutter"
    assert first == second


@pytest.mark.slow
def test_flutter_seed_wing_is_bit_identical(tmp_path):
    first, second = _twice(["flutter", "seed_wing", "--json", "-q"], tmp_path)
    assert first["parametric_rom"]["status"] == "flutter"
    assert first == second


@pytest.mark.parametrize("criterion", ["prediction", "simulation"])
def test_identify_is_bit_identical(tmp_path, criterion):
    truth = random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1)
    synthetic_data(truth, 1500, seed=2, noise=0.02).to_npz(tmp_path / "rec.npz")
    first, second = _twice(["identify", "rec.npz", "--orders", "2,1,1,1,2,2", "--criterion",
                            criterion, "--json"], tmp_path)
    assert first["success"] is True
    assert first == second


SHORT_RUN = """\
seed = 3
stages = ["lco", "controller", "suppression"]
[data]
duration = 4.0
[flutter]
n_grid = 61
[lco]
duration = 3.0
[controller]
starts = 2
max_outer = 3
[suppression]
settle = 2.0
ramp = 1.0
hold = 2.0
release = 4.0
"""


@pytest.mark.slow
def test_short_run_is_bit_identical(tmp_path):
    (tmp_path / "short.toml").write_text(SHORT_RUN)
    docs = []
    for i, threads in enumerate(THREADS):
        doc = _strip(_cli(["run", "short.toml", "--out", f"out{i}", "--json", "-q"], threads,
                          tmp_path))
        docs.append(doc)
    assert docs[0]["controller"]["stable"] is not None
    assert docs[0] == docs[1]
    # the files that carry numbers: the controller and the ROM
    c0, c1 = (json.loads((tmp_path / f"out{i}" / "controller.json").read_text())
              for i in range(2))
    assert c0 == c1
    with np.load(tmp_path / "out0" / "rom.npz") as r0, np.load(tmp_path / "out1" / "rom.npz") as r1:
        assert sorted(r0.files) == sorted(r1.files)
        for name in r0.files:
            assert np.array_equal(r0[name], r1[name]), name


def test_single_threaded_limits_pools_loaded_after_the_cli_starts():
    """The CLI enters ``single_threaded()`` before a command imports numpy/scipy: every BLAS
    pool must still run one thread inside the block, whatever the environment says."""
    code = ("import casflutter.cli\n"
            "from casflutter._threads import single_threaded\n"
            "import threadpoolctl, json\n"
            "with single_threaded():\n"
            "    import scipy.linalg, control\n"
            "    print(json.dumps([p['num_threads'] for p in threadpoolctl.threadpool_info()"
            " if p['user_api'] == 'blas']))\n")
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "2", "OMP_NUM_THREADS": "2"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    threads = json.loads(proc.stdout)
    assert threads and all(n == 1 for n in threads), threads
