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


_H = np.array([0.0, 1.0, 0.0])


class _Hidden(_Linear):
    """f(K) = 1 + g·vec(K) where a decay-rate constraint h·vec(K) <= 0 holds, infeasible
    elsewhere; the constraint is invisible at the start (no constraint cuts there), as an
    eigenvalue is that a step moves farther than its linear model said."""

    def value(self, K):
        if float(_H @ K.ravel(order="F")) > 0.0:
            return np.inf, None
        return 1.0 + float(_G @ K.ravel(order="F")), None


def _violated(K, margin, threshold, delta, which="all"):
    """The hidden constraint as the plant's eigenvalue cut at ``K`` (``_Hidden``)."""
    c = float(_H @ K.ravel(order="F"))
    return [Cut(c, _H.copy(), ("eig", "s", 0, 0j))] if c > 0.0 else []


class _Creeping(_Linear):
    """f(K) = 1 + 1e-4 g·vec(K): every step lowers f, by well under 1 % in ten steps."""

    def value(self, K):
        return 1.0 + 1e-4 * float(_G @ K.ravel(order="F")), None

    def cuts(self, K, f, info, delta, memory):
        return [Cut(f, 1e-4 * _G, ("sigma", 0, 1.0, 0))], []


def _phase(cls, wall=False, **options):
    prob = SimpleNamespace(n=_N, shape=(1, _N), nu=1, ny=_N, aug=[None],
                           vec=lambda M: M.ravel(order="F"),
                           mat=lambda v: np.asarray(v).reshape((1, _N), order="F"),
                           reevaluate=lambda K, c, margin: c,
                           eig_cuts=(_violated if cls is _Hidden
                                     else lambda *args, **kwargs: []))
    ph = cls(prob, CutQP(_N), SynthesisOptions(**options), "hinf", 0.0, np.inf, [])
    ph.wall = wall
    return ph


def test_a_collapsed_trust_region_is_not_called_converged():
    # every trial point leaves the feasible set: the radius halves until the predicted
    # decrease (proportional to it) is below the tolerance, while the model still sees a
    # first-order decrease of |g|_1 per unit step
    res = _phase(_Linear, wall=True).run(np.zeros((1, _N)), "test", 200)
    assert not res.converged and res.collapsed
    assert res.f == 1.0 and len(res.history) == 1     # nothing accepted, the start kept


def test_a_rejected_trial_points_violated_decay_cut_keeps_the_next_steps_out():
    # the first trial point breaks a constraint that no cut at the start saw (K2 <= 0, while
    # the objective falls as K2 grows); its cut there joins the next QPs, which then descend
    # in K1 and K3 alone, instead of halving the radius along the same direction until the
    # region collapses as in the wall test above
    res = _phase(_Hidden).run(np.zeros((1, _N)), "test", 12)
    assert not res.collapsed
    assert res.f < 0.5 and len(res.history) > 5
    assert float(_H @ res.K.ravel(order="F")) <= 1e-9      # every accepted step feasible


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


def test_the_budget_extends_only_while_the_objective_falls_fast():
    # falling fast (the linear objective, steps doubling): the extra iterations are spent
    res = _phase(_Linear, extra_outer=8, stall_window=5).run(np.zeros((1, _N)), "test", 12)
    assert res.iterations == 20 and len(res.history) == 21
    # creeping (well under extra_rate = 1 % in stall_window iterations, yet far above tol):
    # stops at the budget as without the extension
    res = _phase(_Creeping, extra_outer=8, stall_window=5, trust_region=0.3,
                 max_trust_region=0.3).run(np.zeros((1, _N)), "test", 12)
    assert res.iterations == 12 and len(res.history) == 13
    assert 0.0 < 1.0 - res.f < 0.01
