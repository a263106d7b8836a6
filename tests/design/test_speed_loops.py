"""The closed loops of the multi-speed design and the gradient of their decay
(:class:`casflutter.design._speeds.SpeedLoops`).

Truth used: the eigenvectors of LAPACK's full eigendecomposition (``scipy.linalg.eig``) and
central finite differences of the eigenvalues numpy computes, on the shipped
``goland_4flaps`` family (50 states, 4 flaps, 8 sensors) closed by seeded random controllers.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from casflutter.aeroelastic import load_family
from casflutter.design._multispeed import MultiSpeedSettings, _Engine, _Models
from casflutter.design._speeds import _eigenvectors


@pytest.fixture(scope="module")
def loops():
    models = _Models((load_family("goland_4flaps"),), 60.0, 150.0)
    eng = _Engine(models, MultiSpeedSettings(), True)
    K = eng.random_start(2, np.random.default_rng(3), 0.3)
    free = eng.free(2)
    return models.loops(np.linspace(60.0, 150.0, 6), 2, free, K), K[free]


def _abscissa(loops, q, j):
    return float(np.max(loops.abscissae(q)[j]))


@pytest.mark.parametrize("j", range(6))
def test_the_gradient_of_the_rightmost_eigenvalue_is_its_finite_difference(loops, j):
    L, q = loops
    value, grad = L.rightmost(q, j)
    assert value == pytest.approx(_abscissa(L, q, j), abs=1e-12)
    h, rng = 1e-6, np.random.default_rng(j)
    for d in rng.standard_normal((3, q.size)):
        fd = (_abscissa(L, q + h * d, j) - _abscissa(L, q - h * d, j)) / (2 * h)
        assert grad @ d == pytest.approx(fd, rel=1e-5, abs=1e-8)


@pytest.mark.parametrize("tau", [0.3, 0.01, None])
def test_the_smoothed_worst_abscissa_and_its_gradient(loops, tau):
    L, q = loops
    a = L.abscissae(q)
    value, grad = L.smoothed(q, tau)
    expected = (np.max(a) if tau is None
                else np.max(a) + tau * np.log(np.sum(np.exp((a - np.max(a)) / tau))))
    assert value == pytest.approx(expected, abs=1e-12)
    d = np.random.default_rng(7).standard_normal(q.size)
    h = 1e-6
    fd = (L.smoothed(q + h * d, tau)[0] - L.smoothed(q - h * d, tau)[0]) / (2 * h)
    assert grad @ d == pytest.approx(fd, rel=1e-5, abs=1e-8)
    # the lazy form: the same value, and the same gradient once asked for
    lazy_value, lazy_grad = L.smoothed(q, tau, lazy=True)
    assert lazy_value == value and np.array_equal(lazy_grad(), grad)


def _check_pair(M, lam, x, y):
    scale = np.max(np.abs(M))
    assert np.linalg.norm(M @ x - lam * x) <= 1e-8 * scale * np.linalg.norm(x)
    assert np.linalg.norm(y.conj() @ M - lam * y.conj()) <= 1e-8 * scale * np.linalg.norm(y)


def test_inverse_iteration_gives_lapacks_eigenvectors():
    rng = np.random.default_rng(0)
    for n in (3, 20, 60):
        M = rng.standard_normal((n, n)) * np.logspace(0, 3, n)
        w, VL, VR = sla.eig(M, left=True, right=True)
        i = int(np.argmax(w.real))
        x, y = _eigenvectors(M, w[i])
        _check_pair(M, w[i], x, y)
        # the same directions as LAPACK's, up to a complex factor
        assert abs(abs(VR[:, i].conj() @ x) / np.linalg.norm(x) / np.linalg.norm(VR[:, i])
                   - 1) < 1e-8
        assert abs(abs(VL[:, i].conj() @ y) / np.linalg.norm(y) / np.linalg.norm(VL[:, i])
                   - 1) < 1e-8


def test_a_defective_eigenvalue_still_gets_eigenvectors():
    # a Jordan block: inverse iteration meets an exactly singular shifted matrix
    M = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    x, y = _eigenvectors(M, 1.0 + 0j)
    _check_pair(M, 1.0, x, y)
