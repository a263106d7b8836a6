"""``run`` from Python gives the same numbers whatever the BLAS thread count of the process
(the command line's promise, tests/cli/test_determinism.py, for the Python API).

The case is the seed wing's speed-following ROM (``problems/seed_wing/convective.toml``, model
stages only): without the pin its ROM loop's flutter speed measured 1.0804571066486937 with
one OpenBLAS thread and 1.0804571066489486 with two, and a design started there ends in
another local optimum.  JSON floats are written with ``repr``: equal text is equal bits.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import json
from casflutter.pipeline import config_path, load_config, run
cfg = load_config(config_path("seed_wing", "convective"), updates={"stages": []})
r = run(cfg, quiet=True, write=False)
print(json.dumps({"Vf": r.flutter.Vf, "freq": r.flutter.frequency_hz,
                  "A": r.system.state_matrix(1.0).ravel().tolist()}))
"""


def _run(threads: int) -> dict:
    env = dict(os.environ, MPLBACKEND="Agg")
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(threads)
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, cwd=ROOT, capture_output=True,
                         text=True, timeout=600, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_run_is_bit_identical_with_one_and_two_blas_threads():
    one, two = _run(1), _run(2)
    assert abs(one["Vf"] - 1.0805) < 1e-3          # the speed-following ROM's flutter
    assert one == two
