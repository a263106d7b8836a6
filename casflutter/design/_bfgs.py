"""BFGS for nonsmooth objectives: the weak Wolfe line search of Lewis and Overton.

The worst closed-loop spectral abscissa over a set of speeds is nonsmooth wherever two
eigenvalues (or two speeds) share the maximum, and the minimiser usually sits on such a kink.
A line search built for smooth functions (scipy's, which brackets a point of small slope)
spends most of its evaluations trying to find a zero of a derivative that jumps there.
Lewis and Overton (*Nonsmooth optimization via quasi-Newton methods*, Math. Program. 141,
2013) showed that BFGS with an inexact line search that asks only for the weak Wolfe
conditions,

``f(x + t d) <= f(x) + c1 t g'd``  and  ``g(x + t d)'d >= c2 g'd``,

found by doubling ``t`` until the first fails and bisecting once it has, works well on such
functions: the inverse Hessian approximation becomes ill conditioned along the directions in
which the function is nonsmooth, and the iteration converges to the kink.  It is the method
of HANSO and of HIFOO's stabilisation and H∞ phases.

The function here stops when the objective reaches a target (the caller's requirement is
met; where a line search finds no step that meets the curvature condition, along a ray on
which the function falls without bound, it takes the first step that reached the target
rather than the longest one tried), when it has decreased by less than ``stall`` over ``window`` iterations (the usual
state at a nonsmooth minimiser, where the gradient never becomes small), when no step
satisfies the conditions, or after ``max_iter`` iterations.  Every stop is deterministic: the
same start gives the same iterates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .._format import result_repr

__all__ = ["BFGSResult", "nonsmooth_bfgs"]


@dataclass(frozen=True)
class BFGSResult:
    """Outcome of :func:`nonsmooth_bfgs`.

    Attributes
    ----------
    x : ndarray
        The best point.
    fun : float
        The objective there.
    iterations : int
        BFGS iterations taken.
    evaluations : int
        Objective evaluations (each with its gradient).
    reason : str
        Why it stopped: ``"target"``, ``"stalled"``, ``"line search"`` (no step met the
        weak Wolfe conditions: at or near a nonsmooth minimiser), ``"stationary"`` (zero
        gradient), ``"iterations"`` or ``"not finite"`` (the start).
    """

    __repr__ = result_repr

    x: np.ndarray
    fun: float
    iterations: int
    evaluations: int
    reason: str


def nonsmooth_bfgs(fun: Callable, x0: np.ndarray, *, max_iter: int = 200,
                   target: float = -np.inf, stall: float = 0.0, window: int = 20,
                   c1: float = 1e-4, c2: float = 0.5, max_line_search: int = 40
                   ) -> BFGSResult:
    """Minimise a locally Lipschitz function by BFGS with the weak Wolfe line search.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> (f, g)``: the value and a gradient where it exists (``f = inf`` marks a
        point outside the domain; the line search then shortens the step).  ``g`` may be a
        callable of no arguments that returns the gradient: it is called only where the
        line search needs it (a trial step that fails the sufficient-decrease test needs
        the value alone), which saves the gradient's cost on those steps.
    x0 : ndarray
        Start (``fun(x0)`` finite).
    max_iter : int
        Iterations at most.
    target : float
        Stop once ``f <= target``.  A line search that ends without a weak Wolfe step (the
        function falling without bound along the direction) takes its first trial step that
        reached the target, if one did.
    stall : float
        Stop once ``f`` decreased by less than this over the last ``window`` iterations
        (0: never).
    window : int
        Iterations of the stall test.
    c1, c2 : float
        The weak Wolfe constants, ``0 < c1 < c2 < 1``.
    max_line_search : int
        Trial steps per line search at most.

    Returns
    -------
    BFGSResult
    """
    x = np.array(x0, dtype=float)
    f, g = fun(x)
    f = float(f)
    if not np.isfinite(f):
        return BFGSResult(x, f, 0, 1, "not finite")
    g = _gradient(g)
    n = x.size
    H = np.eye(n)
    evaluations, history, reason, it = 1, [f], "iterations", 0
    for it in range(1, max_iter + 1):
        if f <= target:
            reason, it = "target", it - 1
            break
        d = -H @ g
        slope = float(g @ d)
        if not slope < 0:           # H lost positive definiteness to rounding: restart
            H, d = np.eye(n), -g
            slope = float(g @ d)
            if not slope < 0:
                reason = "stationary"
                break
        lo, hi, t, accepted, reached = 0.0, np.inf, 1.0, False, None
        for _ in range(max_line_search):
            xt = x + t * d
            ft, gt = fun(xt)
            ft = float(ft)
            evaluations += 1
            if not np.isfinite(ft) or ft > f + c1 * t * slope:
                hi = t              # not enough decrease: shorten
            elif float((gt := _gradient(gt)) @ d) < c2 * slope:
                lo = t              # still steeply downhill: lengthen
                if reached is None and ft <= target:
                    reached = (xt, ft, gt)
            else:
                accepted = True
                break
            t = 0.5 * (lo + hi) if np.isfinite(hi) else 2.0 * t
        if not accepted:
            if reached is not None and not np.isfinite(hi):
                # f fell along the whole ray (without bound, as a gain that lowers an
                # abscissa linearly): the first step that met the target, not the longest
                x, f, g = reached
                reason = "target"
            else:
                if np.isfinite(ft) and ft < f:
                    x, f, g = xt, ft, _gradient(gt)
                reason = "line search"
            break
        s, y = xt - x, gt - g
        x, f, g = xt, ft, gt
        sy = float(s @ y)
        if sy > 0:                  # the weak Wolfe conditions make this hold; skip if not
            if it == 1:
                H = (sy / float(y @ y)) * np.eye(n)
            rho = 1.0 / sy
            Hy = H @ y
            H = (H - rho * (np.outer(s, Hy) + np.outer(Hy, s))
                 + (rho * rho * float(y @ Hy) + rho) * np.outer(s, s))
        history.append(f)
        if stall > 0 and len(history) > window and history[-window - 1] - f < stall:
            reason = "stalled"
            break
    return BFGSResult(x, f, it, evaluations, reason)


def _gradient(g) -> np.ndarray:
    """The gradient of an evaluation (``fun``'s second value, evaluated if a callable)."""
    return np.asarray(g() if callable(g) else g, dtype=float)
