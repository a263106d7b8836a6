"""The bundle iteration's stopping test: "converged" only where the local model is
stationary at a meaningful radius, not where rejected trial points shrank the radius until
any model predicts too little."""

from types import SimpleNamespace

import numpy as np

from casflutter.design._problem import Cut
from casflutter.design._qp import CutQP
from casflutter.design._synthesis import SynthesisOptions, _Phase

_N = 3
_G = np.array([1.0, -2.0, 0.5])


class _Linear(_Phase):
    """f(K) = 1 + g·vec(K), a single cut; ``wall`` makes every trial point infeasible."""

    wall = False

    def value(self, K):
        if self.wall and np.any(K != 0.0):
            return np.inf, None
        return 1.0 + float(_G @ K.ravel(order="F")), None

    def cuts(self, K, f, info, delta, memory):
        return [Cut(f, _G.copy(), ("sigma", 0, 1.0, 0))], []


class _Flat(_Linear):
    """A constant objective: every model is stationary."""

    def value(self, K):
        return 1.0, None

    def cuts(self, K, f, info, delta, memory):
        return [Cut(f, np.zeros(_N), ("sigma", 0, 1.0, 0))], []


def _phase(cls, wall=False):
    prob = SimpleNamespace(n=_N, shape=(1, _N), nu=1, ny=_N, aug=[None],
                           vec=lambda M: M.ravel(order="F"),
                           mat=lambda v: np.asarray(v).reshape((1, _N), order="F"),
                           reevaluate=lambda K, c, margin: c)
    ph = cls(prob, CutQP(_N), SynthesisOptions(), "hinf", 0.0, np.inf, [])
    ph.wall = wall
    return ph


def test_a_collapsed_trust_region_is_not_called_converged():
    # every trial point leaves the feasible set: the radius halves until the predicted
    # decrease (proportional to it) is below the tolerance, while the model still sees a
    # first-order decrease of |g|_1 per unit step
    res = _phase(_Linear, wall=True).run(np.zeros((1, _N)), "test", 200)
    assert not res.converged and res.collapsed
    assert res.f == 1.0 and len(res.history) == 1     # nothing accepted, the start kept


def test_a_stationary_model_is_converged():
    res = _phase(_Flat).run(np.zeros((1, _N)), "test", 200)
    assert res.converged and not res.collapsed
    assert res.iterations == 1


def test_a_descent_is_followed_and_not_called_converged():
    # a linear objective is unbounded below: the steps are accepted and grow; the budget
    # ends the phase
    res = _phase(_Linear).run(np.zeros((1, _N)), "test", 12)
    assert not res.converged and not res.collapsed
    assert res.f < 0.0 and len(res.history) > 5       # from f = 1 at the start
