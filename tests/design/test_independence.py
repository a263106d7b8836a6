"""The synthesis' own norm against the verification layer, and the layering between them.

Truth used: ``casflutter.verify.hinf_norm`` (SLICOT AB13DD when slycot is installed, else its
own numpy Hamiltonian bisection) on the closed loops of the shared COMPleib plants with the
synthesised controllers; the design layer computes its γ with a different algorithm (a
Hamiltonian-pencil level iteration) and must agree to 1e-6 relative.
"""

from __future__ import annotations

import ast
from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.design import hinf_norm as design_norm
from casflutter.design import load_compleib, synthesize, SynthesisOptions
from casflutter.verify import hinf_norm as verify_norm
from casflutter.verify import lft_closed_loop

ROOT = Path(__file__).resolve().parents[2]
COMPLEIB = ROOT / "problems" / "compleib"
DESIGN = ROOT / "casflutter" / "design"


def test_design_never_imports_verify():
    for f in DESIGN.glob("*.py"):
        tree = ast.parse(f.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                mod = (node.module or "")
                assert "verify" not in mod.split("."), f"{f.name} imports {mod}"
            elif isinstance(node, ast.Import):
                assert all("verify" not in a.name.split(".") for a in node.names), f.name


@pytest.mark.parametrize("name", ["AC2", "AC4", "AC15", "HE1", "REA1", "REA2", "DIS1", "NN4"])
def test_synthesis_gamma_agrees_with_verification_layer(name):
    P, nmeas, ncon, _ = load_compleib(COMPLEIB / f"{name}.json")
    res = synthesize(P, nmeas, ncon, 1, starts=1, seed=0,
                     options=SynthesisOptions(max_outer=40))
    cl = lft_closed_loop(P, res.controller, nmeas, ncon)
    ref = verify_norm(cl)
    assert ref.stable
    np.testing.assert_allclose(res.gamma, ref.gamma, rtol=1e-6)
    # the design norm on the verification layer's own interconnection, too
    g, _ = design_norm(*(np.asarray(M, float) for M in (cl.A, cl.B, cl.C, cl.D)))
    np.testing.assert_allclose(g, ref.gamma, rtol=1e-6)


def test_design_norm_on_hard_systems(numpy_global_seed):
    """Lightly damped (ζ = 1e-7), a peak at ω = 0 and a feed-through that nearly equals the
    peak: the cases where a Hamiltonian test on the axis is fragile."""
    rng = np.random.default_rng(3)
    cases = [(np.array([[0.0, 1.0], [-100.0, -2e-6]]), np.array([[0.0], [1.0]]),
              np.array([[1.0, 0.0]]), np.zeros((1, 1)))]
    for _ in range(30):
        s = control.rss(int(rng.integers(2, 20)), 2, 3, strictly_proper=False)
        A, B, C, D = (np.asarray(M, float) for M in (s.A, s.B, s.C, s.D))
        if np.max(np.linalg.eigvals(A).real) < -1e-6:
            cases.append((A, B, C, D))
    for A, B, C, D in cases:
        ref = float(control.linfnorm(control.ss(A, B, C, D))[0])
        g, _ = design_norm(A, B, C, D)
        np.testing.assert_allclose(g, ref, rtol=1e-6)
