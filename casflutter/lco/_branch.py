"""Pseudo-arclength continuation of a branch of periodic orbits (or invariant circles).

The discretisation (collocation of a period, or Fourier series of an invariant circle)
provides a square system ``G(X) = 0`` in the unknowns ``X = [orbit, period-like, V]`` closed
by one linear condition ``<c, X> = s``.  From a converged point ``X_k`` with unit tangent
``t_k`` (in the diagonal metric ``M``), the predictor is ``X_k + ds t_k`` and the corrector
solves ``G(X) = 0`` on the hyperplane ``<t_k, X - X_k>_M = ds``; the new tangent solves
``[dG/dX; (M t_k)^T] t = [0; 1]``.  The step grows after easy corrections, shrinks after
hard or failed ones and is capped so that the speed changes by at most ``max_dV`` (relative)
per step.  A sign change of the tangent's speed component between two points is a fold of
cycles; it is located by a secant (Illinois) iteration on the arclength until that component
vanishes.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from .._format import result_repr
from ..errors import ConvergenceError
from ._results import SUBCRITICAL, SUPERCRITICAL, Fold, HopfClassification, LCOSettings

__all__ = ["BranchRun", "BranchStart", "continue_branch", "run_from_hopf", "run_from_orbit",
           "tangent"]

log = logging.getLogger("casflutter.lco")


@dataclass
class BranchRun:
    """Raw output of :func:`continue_branch`."""

    X: list
    points: list
    tangents: list
    folds: list
    completed: bool
    stop_reason: str


def tangent(disc, X: np.ndarray, ref: np.ndarray, c: np.ndarray, M: np.ndarray,
            factor=None) -> np.ndarray:
    """Unit tangent (metric ``M``) at ``X`` with ``<c, t> = 1`` before normalisation.

    With ``factor`` (the LU factors of the corrector's last Newton Jacobian, whose rows are
    the same system bordered by ``c``) no new factorisation is made; the tangent is then
    that of the last iterate but one, a predictor direction good to the Newton step.
    """
    rhs = np.zeros(disc.iV + 1)
    rhs[-1] = 1.0
    if factor is not None:
        t = factor.solve(rhs)
    else:
        J = disc.jacobian(X, ref)
        A = sp.vstack([J, sp.csr_matrix(c[None, :])]).tocsc()
        t = spsolve(A, rhs)
    if not np.all(np.isfinite(t)):
        raise np.linalg.LinAlgError("singular continuation Jacobian")
    return t / math.sqrt(float(np.sum(M * t * t)))


def _locate_fold(disc, Xk, tk, ds, tv0, tv1, M, settings):
    """Secant (Illinois) on the arclength ``s`` in ``(0, ds)`` for ``t_V(s) = 0``."""
    iV = disc.iV
    ref = disc.reference(Xk)
    c = M * tk
    lo, flo, hi, fhi = 0.0, tv0, ds, tv1
    best = None
    side = 0
    for _ in range(settings.fold_iterations):
        s = hi - fhi * (hi - lo) / (fhi - flo) if fhi != flo else 0.5 * (lo + hi)
        if not lo < s < hi:
            s = 0.5 * (lo + hi)
        res = disc.solve(Xk + s * tk, ref, c, float(c @ Xk) + s)
        if not res.success:
            break
        try:
            t = tangent(disc, res.x, disc.reference(res.x), c, M)
        except np.linalg.LinAlgError:
            break
        fv = float(t[iV])
        if best is None or abs(fv) < abs(best[1]):
            best = (res.x, fv)
        if abs(fv) < 1e-6 or (hi - lo) < 1e-10 * max(1.0, ds):
            break
        if fv * flo > 0:
            lo, flo = s, fv
            if side == -1:
                fhi *= 0.5
            side = -1
        else:
            hi, fhi = s, fv
            if side == 1:
                flo *= 0.5
            side = 1
    return best


def continue_branch(disc, X1: np.ndarray, t1: np.ndarray, M: np.ndarray, settings: LCOSettings,
                    vrange: tuple, V_ref: float, start_amplitude: float) -> BranchRun:
    """Continue from ``X1`` along ``t1`` (see the module docstring).

    Parameters
    ----------
    disc
        The discretisation: ``iV``, ``solve``, ``jacobian``, ``reference``, ``evaluate``
        and ``size(X)`` (a scalar amplitude of the orbit).
    X1, t1 : numpy.ndarray
        First converged point and its unit tangent (oriented away from the Hopf point).
    M : numpy.ndarray
        Diagonal metric.
    settings : LCOSettings
    vrange : tuple
        Speed-index range; the branch stops when it leaves it.
    V_ref : float
        Reference speed for the relative step cap (the Hopf speed).
    start_amplitude : float
        ``size`` of the first point (the branch stops if it shrinks back below half).
    """
    iV = disc.iV
    lo, hi = vrange
    X, T = [X1], [t1]
    pts = [disc.evaluate(X1)]
    folds: list[Fold] = []
    ds = settings.ds
    reason, completed = f"reached the point budget ({settings.max_points} points)", True
    while len(X) < settings.max_points:
        Xk, tk = X[-1], T[-1]
        ref = disc.reference(Xk)
        c = M * tk
        step = min(ds, settings.ds_max)
        if abs(tk[iV]) > 0:
            step = min(step, settings.max_dV * V_ref / abs(tk[iV]))
        ok = False
        while step >= settings.ds_min:
            res = disc.solve(Xk + step * tk, ref, c, float(c @ Xk) + step)
            if res.success:
                try:
                    tn = tangent(disc, res.x, ref, c, M, res.factor)
                except np.linalg.LinAlgError:
                    tn = None
                # reject a corrector that jumped to another branch (tangent turned too far)
                if tn is not None and float(np.sum(M * tn * tk)) > 0.8:
                    ok = True
                    break
            step *= 0.5
        if not ok:
            completed = False
            reason = (f"continuation failed at V = {Xk[iV]:.6g}: no corrector converged down to "
                      f"the smallest step ds_min = {settings.ds_min:g} (last status "
                      f"{res.return_status!r}); the last converged point is kept")
            log.warning(reason)
            break
        Xn = res.x
        if not lo <= Xn[iV] <= hi:
            reason = f"left the speed range [{lo:.6g}, {hi:.6g}] at V = {Xn[iV]:.6g}"
            break
        pn = disc.evaluate(Xn)
        if tk[iV] * tn[iV] < 0:
            found = _locate_fold(disc, Xk, tk, step, float(tk[iV]), float(tn[iV]), M, settings)
            if found is not None:
                pf = disc.evaluate(found[0])
                folds.append(Fold(V=float(found[0][iV]), amplitude=dict(pf.amplitude),
                                  index=len(X) - 1, located=abs(found[1]) < 1e-6,
                                  tangent_V=float(found[1]), max_multiplier=pf.max_multiplier))
            else:
                folds.append(Fold(V=float(Xk[iV]), amplitude=dict(pts[-1].amplitude),
                                  index=len(X) - 1, located=False, tangent_V=float(tk[iV]),
                                  max_multiplier=pts[-1].max_multiplier))
            log.info("fold of cycles near V = %.6g", folds[-1].V)
        X.append(Xn)
        T.append(tn)
        pts.append(pn)
        if res.iterations <= 3:
            ds = min(step * 1.6, settings.ds_max)
        elif res.iterations >= 8:
            ds = step * 0.6
        else:
            ds = step
        size = disc.size(Xn)
        if settings.max_amplitude is not None and max(pn.amplitude.values()) > settings.max_amplitude:
            reason = (f"an output amplitude exceeded max_amplitude = {settings.max_amplitude:g} "
                      f"at V = {Xn[iV]:.6g}")
            break
        if size < 0.5 * start_amplitude:
            reason = (f"the branch shrank back to the equilibrium near V = {Xn[iV]:.6g} "
                      "(another Hopf point)")
            break
        if pn.period > 20.0 * pts[0].period:
            reason = (f"the period grew past 20 times its Hopf value at V = {Xn[iV]:.6g} "
                      "(approach to a homoclinic orbit or a static instability)")
            break
    return BranchRun(X=X, points=pts, tangents=T, folds=folds, completed=completed,
                     stop_reason=reason)


@dataclass(frozen=True)
class BranchStart:
    """What a discretisation provides to start a branch at a Hopf/Neimark--Sacker point.

    Attributes
    ----------
    cp : CriticalPair
        The critical pair (:mod:`._normal_form`).
    lyapunov : float
        ``l1`` (flow) or ``d`` (map).
    radial : float
        The cubic coefficient of the radial normal form, ``r' = mu r + radial r^3``
        (``omega l1``) or ``r -> r (1 + beta + radial r^2)`` (``d``).
    omega, freq_hz : float
        Frequency of the critical pair.
    discrete : bool
    qhat : numpy.ndarray
        The critical eigenvector scaled to 1 on its dominant displacement.
    dominant : int
        That displacement's index.
    guess : callable
        ``(amplitude, V) -> X0``: the mode with that amplitude, period at the Hopf value.
    phi : numpy.ndarray
        The mode of unit amplitude as an unknown vector (period and speed entries zero).
    ref : numpy.ndarray
        Its phase reference.
    n_points : int
        Orbit points per state in the unknowns.
    period0 : float
        Scale of the period-like unknown (period or rotation number at the Hopf point).
    hint : str
        What to try when the first orbit fails.
    """

    __repr__ = result_repr

    cp: object
    lyapunov: float
    radial: float
    omega: float
    freq_hz: float
    discrete: bool
    qhat: np.ndarray
    dominant: int
    guess: object
    phi: np.ndarray
    ref: np.ndarray
    n_points: int
    period0: float
    hint: str


def run_from_hopf(disc, start: BranchStart, settings: LCOSettings, vrange: tuple, *,
                  speed_scale: float, speed_unit: str):
    """Solve the first orbit next to the Hopf point, classify the point, continue.

    The first orbit's amplitude along the critical mode is the one for which the normal
    form predicts a speed offset of ``start_offset`` times the Hopf speed; the orbit is
    solved with that amplitude fixed (its speed free), and the direction and size of the
    offset found check the Lyapunov coefficient.

    Returns
    -------
    (HopfClassification, BranchRun)

    Raises
    ------
    ConvergenceError
        The first orbit did not converge.
    """
    cp = start.cp
    dV_target = settings.start_offset * cp.V
    r = math.sqrt(dV_target * abs(cp.crossing_rate) / abs(start.radial))
    eps = 2.0 * r * abs(cp.q[start.dominant])
    dV_pred = -start.radial * r * r / cp.crossing_rate
    phi = start.phi
    c_amp = phi / start.n_points
    s_amp = eps * float(c_amp @ phi)
    first = None
    for guess_dV in (dV_pred, -dV_pred, 0.0):
        res = disc.solve(start.guess(eps, cp.V + guess_dV), start.ref, c_amp, s_amp)
        if res.success:
            first = res
            break
    if first is None:
        what = "invariant circle" if start.discrete else "periodic orbit"
        point = "Neimark-Sacker" if start.discrete else "Hopf"
        raise ConvergenceError(f"the first {what} next to the {point} point at "
                               f"{cp.V * speed_scale:.6g} {speed_unit} did not converge "
                               f"({res.return_status}, residual {res.residual:.3g}); "
                               f"{start.hint}", res)
    X1 = first.x
    dV1 = float(X1[disc.iV] - cp.V)
    direction = 1 if dV1 > 0 else -1
    kind = SUPERCRITICAL if start.lyapunov < 0 else SUBCRITICAL
    kind_branch = SUPERCRITICAL if direction * cp.crossing_rate > 0 else SUBCRITICAL
    # metric: the orbit in units of a reference amplitude (the amplitude at a 5 % speed
    # change on the parabola through the first orbit), the period and the speed relative
    Aref = eps * math.sqrt(0.05 * cp.V / max(abs(dV1), 1e-12 * cp.V))
    Aref = min(max(Aref, eps), 1e4 * eps)
    d = np.abs(start.qhat)
    d = np.maximum(d, 1e-3 * d.max())
    M = np.concatenate([np.tile(1.0 / (start.n_points * (Aref * d) ** 2), start.n_points),
                        [1.0 / start.period0 ** 2, 1.0 / (0.05 * cp.V) ** 2]])
    disc.w2 = (1.0 / d ** 2)[:, None]
    t1 = tangent(disc, X1, disc.reference(X1), c_amp, M)
    hopf = HopfClassification(V=cp.V, omega=float(start.omega), freq_hz=float(start.freq_hz),
                              lyapunov=float(start.lyapunov), crossing_rate=cp.crossing_rate,
                              kind=kind, branch_direction=direction, kind_from_branch=kind_branch,
                              consistent=kind == kind_branch, predicted_dV=dV_pred,
                              computed_dV=dV1, eigenvector=cp.q, discrete=start.discrete)
    if not hopf.consistent:
        log.warning("the Lyapunov coefficient (%s) and the branch direction (%s) disagree at "
                    "V = %.6g", kind, kind_branch, cp.V)
    run = continue_branch(disc, X1, t1, M, settings, vrange, cp.V, disc.size(X1))
    return hopf, run


def run_from_orbit(disc, X0: np.ndarray, M: np.ndarray, settings: LCOSettings,
                   vrange: tuple) -> BranchRun | None:
    """Solve the orbit ``X0`` (a guess, e.g. a simulated cycle) at its speed and continue
    its branch both ways.

    Parameters
    ----------
    disc
        The discretisation (as :func:`continue_branch`).
    X0 : numpy.ndarray
        The guess; its speed entry is kept fixed while it is solved.
    M : numpy.ndarray
        Diagonal metric of the continuation.
    settings : LCOSettings
    vrange : tuple
        Speed-index range.

    Returns
    -------
    BranchRun or None
        The branch ordered from its low-speed end (as continued downwards) through ``X0``
        to its other end, with both stop reasons; None when the orbit does not converge.
    """
    iV = disc.iV
    V0 = float(X0[iV])
    c = np.zeros(X0.size)
    c[iV] = 1.0
    res = disc.solve(X0, disc.reference(X0), c, V0)
    if not res.success:
        return None
    X1 = res.x
    try:
        t1 = tangent(disc, X1, disc.reference(X1), c, M)
    except np.linalg.LinAlgError:
        return None
    size = disc.size(X1)
    up = continue_branch(disc, X1, t1, M, settings, vrange, V0, size)
    down = continue_branch(disc, X1, -t1, M, settings, vrange, V0, size)
    n_down = len(down.points)
    folds = [Fold(V=f.V, amplitude=f.amplitude, index=n_down - 2 - f.index, located=f.located,
                  tangent_V=f.tangent_V, max_multiplier=f.max_multiplier)
             for f in reversed(down.folds)]
    folds += [Fold(V=f.V, amplitude=f.amplitude, index=n_down - 1 + f.index,
                   located=f.located, tangent_V=f.tangent_V, max_multiplier=f.max_multiplier)
              for f in up.folds]
    return BranchRun(X=down.X[:0:-1] + up.X, points=down.points[:0:-1] + up.points,
                     tangents=[-t for t in down.tangents[:0:-1]] + up.tangents, folds=folds,
                     completed=up.completed and down.completed,
                     stop_reason=f"one way: {down.stop_reason}; the other: {up.stop_reason}")
