"""Same seed, same controller, whatever the BLAS thread count of the process.

Each case runs in fresh interpreters with ``OPENBLAS_NUM_THREADS`` = 1 and 2 (and the other
pools alike); the controllers must be bit-identical.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import hashlib, json, numpy as np
from casflutter.design import load_compleib, synthesize, SynthesisOptions
P, nm, nc, _ = load_compleib({plant!r})
r = synthesize(P, nm, nc, 2, starts=2, seed=5, options=SynthesisOptions(max_outer=60))
K = r.controller
h = hashlib.sha256(b"".join(np.ascontiguousarray(np.asarray(M, float)).tobytes()
                            for M in (K.A, K.B, K.C, K.D))).hexdigest()
print(json.dumps({{"hash": h, "gamma": r.gamma}}))
"""


def _run(code: str, threads: int, timeout: float = 600) -> dict:
    env = dict(os.environ)
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(threads)
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True,
                         text=True, timeout=timeout, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_synthesis_identical_with_one_and_two_blas_threads():
    code = SCRIPT.format(plant=str(ROOT / "problems" / "compleib" / "AC4.json"))
    one, two = _run(code, 1), _run(code, 2)
    assert one == two


RUN = """
import json, sys
from pathlib import Path
from casflutter.cli import main
out = Path(sys.argv[1])
assert main(["run", "--out", str(out), "--quiet"]) == 0
print(json.dumps({{"controller": json.loads((out / "controller.json").read_text()),
                   "gamma": json.loads((out / "summary.json").read_text())["controller"]["gamma"]}}))
"""


@pytest.mark.slow
def test_default_run_controller_identical_with_one_and_two_blas_threads(tmp_path):
    """`casflutter run` (the default configuration) as launched by `make demo` (pools pinned
    by the environment) and from a bare shell with two threads: the same controller."""
    def run(threads):
        env = dict(os.environ, MPLBACKEND="Agg")
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env[var] = str(threads)
        out = subprocess.run([sys.executable, "-c", RUN.format(), str(tmp_path / f"t{threads}")],
                             env=env, cwd=ROOT, capture_output=True, text=True, timeout=900,
                             check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert run(1) == run(2)


def test_casadis_own_openblas_is_pinned_too():
    """CasADi's bundled OpenBLAS (Ipopt's MUMPS) is invisible to threadpoolctl and takes its
    thread count from the environment; inside ``single_threaded`` it runs on one thread,
    and afterwards on as many as before."""
    from casflutter._threads import casadi_openblas, single_threaded

    lib = casadi_openblas()
    if lib is None:
        pytest.skip("this CasADi bundles no OpenBLAS of its own")
    original = lib.openblas_get_num_threads()
    try:
        lib.openblas_set_num_threads(2)
        with single_threaded():
            assert lib.openblas_get_num_threads() == 1
        assert lib.openblas_get_num_threads() == 2
    finally:
        lib.openblas_set_num_threads(original)


FAMILY = """
import json
from casflutter.aeroelastic import load_family
from casflutter.design import design_over_speeds
from casflutter.pipeline import RunConfig, multispeed_settings
s = multispeed_settings(RunConfig(), "sensitivity")
d = design_over_speeds(load_family("goland_4flaps"), (60.0, 150.0), 2, settings=s, seed=0)
print(json.dumps({"gamma": d.gamma, "A": d.controller.A.tolist(), "C": d.controller.C.tolist()}))
"""


@pytest.mark.slow
def test_family_design_identical_with_one_and_two_blas_threads():
    """The multi-speed design on goland_4flaps (50 states): its H∞ QPs are large enough for
    a two-thread OpenBLAS in CasADi's Ipopt to change γ's last bits (1.437425093679015
    against 1.437425093664116 before CasADi's pool was pinned)."""
    assert _run(FAMILY, 1, timeout=900) == _run(FAMILY, 2, timeout=900)
