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


def _resonant(rng, modes: int) -> tuple[np.ndarray, ...]:
    """A structure-like system: ``modes`` oscillators (1-100 rad/s, ζ from 1e-4 to 1e-2, some
    of them 0.5 % apart) mixed by a random similarity, 2 inputs, 3 outputs."""
    w = np.sort(rng.uniform(1.0, 100.0, modes))
    w[1::4] = w[0::4][:w[1::4].size] * 1.005
    z = 10.0 ** rng.uniform(-4, -2, modes)
    A = np.zeros((2 * modes, 2 * modes))
    for i, (wi, zi) in enumerate(zip(w, z)):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0.0, 1.0], [-wi ** 2, -2 * zi * wi]]
    T = np.eye(2 * modes) + 0.1 * rng.standard_normal((2 * modes, 2 * modes))
    A = np.linalg.solve(T, A @ T)
    B = rng.standard_normal((2 * modes, 2))
    C = rng.standard_normal((3, 2 * modes))
    D = 0.1 * rng.standard_normal((3, 2))
    return A, B, C, D


@pytest.mark.parametrize("modes", [15, 24, 40])
def test_design_norm_on_large_resonant_systems(modes):
    """From 30 states on, the level iteration refines its lower bound to the local maximum
    of σ_max in the band where it is largest (a 1-D search on the modal form): on many
    sharp, nearly coalescing peaks the norm it confirms is still the verification layer's."""
    rng = np.random.default_rng(modes)
    for _ in range(4):
        A, B, C, D = _resonant(rng, modes)
        ref = verify_norm(control.ss(A, B, C, D))
        g, w = design_norm(A, B, C, D)
        np.testing.assert_allclose(g, ref.gamma, rtol=1e-6)
        # the peak frequency it reports is where σ_max is the norm
        s = np.linalg.svd(C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B) + D,
                          compute_uv=False)[0]
        np.testing.assert_allclose(s, g, rtol=1e-6)
