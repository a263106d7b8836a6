"""Flutter of a plant family: every open-loop crossing of the imaginary axis in its range.

A family's state matrix ``A(V)`` is known at any speed (:meth:`PlantFamily.state_matrix`)
and, for the families built here, is a polynomial of low degree between breakpoints
(``speed_degree``: 1 between the grid speeds of a linearly interpolated grid, 2 for strip
theory).  :func:`family_flutter` uses that to be exact and fast:

1. **Grid.** The speeds of the search (the grid's own speeds for a gridded family, else an
   even grid) with every breakpoint added, so that each interval lies inside one polynomial
   piece.
2. **Eigenvalue derivatives.** On an interval ``[a, b]`` with midpoint ``m`` the one-sided
   derivatives ``A'(a) = (−3A(a) + 4A(m) − A(b))/h`` and ``A'(b) = (A(a) − 4A(m) + 3A(b))/h``
   are exact for a piece of degree ≤ 2, and so is ``A'(V)``, linear between them.  With
   right and left eigenvectors ``r_i``, ``w_i`` (``W = R⁻¹``) the eigenvalue derivatives are
   ``λ_i' = w_i A' r_i`` (first-order perturbation theory).
3. **Branches.** Eigenvalues at neighbouring speeds are matched by eigenvector continuity
   (the bi-orthogonality scores of :func:`track_eigenvalues`, assignment by
   :func:`scipy.optimize.linear_sum_assignment`).  An interval is bisected (up to
   ``max_depth`` times) when a branch near the imaginary axis — one whose distance to it is
   not larger than its move over the interval — is matched with a score below
   ``min_score``, or when the cubic Hermite interpolant of ``Re λ`` (values and derivatives
   at both ends) crosses zero where the ends do not say so (a hump inside the interval).
   Clusters of equal eigenvalues far from the axis (identical actuators, lag states of
   several flaps) have arbitrary eigenvectors and are left alone: their order cannot hide a
   crossing.
4. **Crossings.** Every sign change of ``Re λ`` of a branch is located by Newton's method on
   ``Re λ(V)`` with the exact derivative, kept inside its bracket (a bisection step where
   Newton would leave it), the branch followed by its left eigenvector, to ``xtol`` of the
   speed.

The result is a :class:`FlutterResult`, as from :func:`find_flutter`, with the branch data
(:class:`EigenTracking`) for the V–g / V–f figure; speeds and frequencies are in the
family's units (``speed_unit``, rad per ``time_unit``).
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..errors import ConfigError
from ._family import PlantFamily
from ._flutter import Crossing, FlutterResult
from ._tracking import EigenTracking, _eig, _scores

__all__ = ["family_flutter"]

_LOG = logging.getLogger(__name__)
#: sample points of the cubic Hermite interpolant of Re λ inside an interval
_T = np.linspace(0.0, 1.0, 17)[1:-1]
_H = np.stack([1 - 3 * _T ** 2 + 2 * _T ** 3, _T - 2 * _T ** 2 + _T ** 3,
               3 * _T ** 2 - 2 * _T ** 3, -_T ** 2 + _T ** 3])
#: eigenvalue condition number above which its derivative is not trusted
_KAPPA_MAX = 1e8


class _Node:
    """Eigen-decomposition at one speed, columns in branch order once placed."""

    __slots__ = ("V", "A", "lam", "R", "W")

    def __init__(self, V: float, A: np.ndarray):
        self.V, self.A = float(V), A
        self.lam, self.R = _eig(A)
        self.W = _inverse(self.R)

    def permuted(self, perm: np.ndarray) -> "_Node":
        self.lam, self.R, self.W = self.lam[perm], self.R[:, perm], self.W[perm]
        return self


def _inverse(R: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.inv(R)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(R)


def _derivative(W: np.ndarray, dA: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``λ_i' = w_i A' r_i`` and the condition numbers ``|w_i| |r_i|`` (``|r_i| = 1``); at
    a defective eigenvalue (a double integrator's Jordan block) ``W`` is huge and both come
    out infinite or NaN, which the callers take as a derivative not to trust."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.einsum("ij,ji->i", W, dA @ R), np.linalg.norm(W, axis=1)


def _match(a: _Node, b: _Node) -> tuple[np.ndarray, np.ndarray]:
    """Permutation (branch k at a -> eigenpair perm[k] at b) and each branch's score."""
    S = _scores(a.R, b.R)
    scale = max(float(np.max(np.abs(a.lam))), 1.0)
    rows, cols = linear_sum_assignment(-S + 1e-6 * np.abs(a.lam[:, None] - b.lam[None, :])
                                       / scale)
    perm = np.empty_like(cols)
    perm[rows] = cols
    return perm, S[np.arange(perm.size), perm]


def _suspect(fa, fb, da, db, ok) -> np.ndarray:
    """Branches whose cubic Hermite interpolant of Re λ crosses zero unlike its ends."""
    p = _H[0][None, :] * fa[:, None] + _H[1][None, :] * da[:, None] \
        + _H[2][None, :] * fb[:, None] + _H[3][None, :] * db[:, None]
    same = fa * fb > 0
    margin = 0.05 * np.minimum(np.abs(fa), np.abs(fb))
    hump = same & (np.min(p * np.sign(fa)[:, None], axis=1) <= margin)
    seq = np.sign(np.hstack([fa[:, None], p, fb[:, None]]))
    extra = ~same & (np.sum(seq[:, 1:] * seq[:, :-1] < 0, axis=1) > 1)
    return ok & (hump | extra)


def _sign_changes(re: np.ndarray) -> list[tuple[int, int]]:
    """``(interval, branch)`` of every sign change of ``Re λ`` along the branches.

    A sign change across a run of exact zeros counts once, in the interval that ends at the
    first zero (the crossing is that grid speed); zeros at the start of the range (an
    undamped structure at zero speed) are no crossing.
    """
    out = []
    s = np.sign(re)
    for k in range(s.shape[1]):
        nz = np.flatnonzero(s[:, k])
        for p, q in zip(nz[:-1], nz[1:]):
            if s[p, k] != s[q, k]:
                out.append((int(p), int(k)))
    return sorted(out)


def _grid(family: PlantFamily, speeds, n_grid: int | None, subdivide: int) -> np.ndarray:
    lo, hi = family.speed_range
    if speeds is None and not math.isfinite(hi):
        raise ConfigError(f"{family.name} has the open speed range [{lo:g}, {hi:g}]: give the "
                          "speeds of the search (e.g. speeds=family.speed_grid(101, lo, hi))")
    if speeds is None:
        if family.speed_degree == 1 and family.breakpoints and n_grid is None:
            v = np.array([lo, *family.breakpoints, hi], dtype=float)
        else:
            v = family.speed_grid(101 if n_grid is None else int(n_grid))
    else:
        v = np.asarray(speeds, dtype=float).ravel()
        if v.size < 2 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0):
            raise ConfigError("speeds must hold at least two finite, strictly increasing "
                              "speeds")
        v = np.array([family.check_speed(x, "speeds") for x in v])
        v = np.unique(np.concatenate([v, [b for b in family.breakpoints if v[0] < b < v[-1]]]))
    if int(subdivide) < 1:
        raise ConfigError(f"subdivide = {subdivide!r} must be an integer >= 1")
    if subdivide > 1:
        t = np.linspace(0.0, 1.0, int(subdivide) + 1)[:-1]
        v = np.concatenate([(v[:-1, None] + t[None, :] * np.diff(v)[:, None]).ravel(), v[-1:]])
    return v


def _locate(fn, a: _Node, b: _Node, dA_a, dA_b, k: int, xtol: float):
    """Newton on Re λ_k(V) in [a.V, b.V], kept in the bracket; (V, λ, slope, converged)."""
    h = b.V - a.V
    fa, fb = a.lam[k].real, b.lam[k].real
    if fa == 0.0 or fb == 0.0:
        n, dA = (a, dA_a) if fa == 0.0 else (b, dA_b)
        return n.V, complex(n.lam[k]), float(np.real(n.W[k] @ dA @ n.R[:, k])), True
    lo, hi, flo = a.V, b.V, fa
    # start at the root of the secant; follow the branch from the nearer end
    V = a.V - fa * h / (fb - fa)
    w_ref = a.W[k] if V - a.V < b.V - V else b.W[k]
    lam = complex(a.lam[k])
    slope, converged = 0.0, False
    for _ in range(100):
        A = fn(V)
        node_lam, R = _eig(A)
        j = int(np.argmax(np.abs(w_ref @ R)))
        W = _inverse(R)
        dA = dA_a + (V - a.V) / h * (dA_b - dA_a)
        lam = complex(node_lam[j])
        slope = float(np.real(W[j] @ dA @ R[:, j]))
        w_ref = W[j]
        f = lam.real
        if f == 0.0:
            converged = True
            break
        if np.sign(f) == np.sign(flo):
            lo, flo = V, f
        else:
            hi = V
        step = -f / slope if slope != 0.0 and math.isfinite(slope) else math.inf
        new = V + step
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        tol = xtol * max(abs(V), 1.0)
        if abs(new - V) <= tol or hi - lo <= tol:
            converged = True
            V = new if lo < new < hi else V
            break
        V = new
    return float(V), lam, slope, converged


def family_flutter(family: PlantFamily, *, speeds=None, n_grid: int | None = None,
                   subdivide: int = 1, xtol: float = 1e-10, min_score: float = 0.9,
                   max_depth: int = 8) -> FlutterResult:
    """Every crossing of the imaginary axis by an open-loop eigenvalue of a plant family.

    Parameters
    ----------
    family : PlantFamily
        Any family (a gridded family, a loop family, a strip-theory wing).
    speeds : array_like, optional
        Speeds of the search, inside the family's range (the breakpoints are added).
        Default: the grid speeds of a linearly interpolated family, otherwise ``n_grid``
        even speeds over its range.
    n_grid : int, optional
        Number of even speeds (default 101) when ``speeds`` is not given (on a gridded
        family: instead of its grid speeds).
    subdivide : int
        Split every interval of the grid into this many equal parts first (the adaptive
        bisection comes on top).
    xtol : float
        Relative tolerance of a crossing's speed (Newton's step or bracket below
        ``xtol · max(|V|, 1)``).
    min_score : float
        Eigenvector-continuity score below which an interval with a branch near the axis
        is bisected (module docstring).
    max_depth : int
        Bisections per interval at most.

    Returns
    -------
    FlutterResult
        Speeds in the family's ``speed_unit``, frequencies in rad per ``time_unit``;
        ``crossings`` lists every crossing (flutter: a complex pair, reported once with
        ``Im λ > 0``; divergence: a real eigenvalue through 0), lowest speed first;
        ``origin`` is -1 (a family names no structural modes).

    Raises
    ------
    ConfigError
        Bad speeds or settings (before any eigenvalue is computed).

    See Also
    --------
    find_flutter : the same for a bare ``V -> A(V)``, with structural-mode attribution.
    load_family : a gridded family from a file.

    Examples
    --------
    >>> import numpy as np
    >>> from casflutter.aeroelastic import GriddedFamily, family_flutter
    >>> V = np.array([0.0, 1.0, 2.0])
    >>> A = [np.array([[v - 1.0, 5.0], [-5.0, v - 1.0]]) for v in V]   # Re λ = V - 1
    >>> B, C, D = np.ones((3, 2, 1)), np.ones((3, 1, 2)), np.zeros((3, 1, 1))
    >>> f = family_flutter(GriddedFamily(V, A, B, C, D))
    >>> round(f.Vf, 8), round(f.omega_f, 8)
    (1.0, 5.0)
    """
    if not isinstance(family, PlantFamily):
        raise ConfigError(f"family must be a casflutter.aeroelastic.PlantFamily, got "
                          f"{type(family).__name__}")
    if not 0.0 < min_score < 1.0:
        raise ConfigError(f"min_score = {min_score!r} must lie in (0, 1)")
    if not (math.isfinite(xtol) and 0.0 < xtol < 1e-3):
        raise ConfigError(f"xtol = {xtol!r} must lie in (0, 1e-3)")
    if int(max_depth) < 0:
        raise ConfigError(f"max_depth = {max_depth!r} must be >= 0")
    grid = _grid(family, speeds, n_grid, subdivide)
    fn = family.state_matrix
    nodes = [_Node(grid[0], np.asarray(fn(grid[0]), dtype=float))]
    scale = max(float(np.max(np.abs(nodes[0].lam))), 1.0)
    intervals, scores = [], []
    n_refined = n_unresolved = 0
    for Vb in grid[1:]:
        pending = [(_Node(Vb, np.asarray(fn(Vb), dtype=float)), 0)]
        while pending:
            right, depth = pending[-1]
            left = nodes[-1]
            h = right.V - left.V
            Am = np.asarray(fn(0.5 * (left.V + right.V)), dtype=float)
            dA_a = (-3.0 * left.A + 4.0 * Am - right.A) / h
            dA_b = (left.A - 4.0 * Am + 3.0 * right.A) / h
            perm, s = _match(left, right)
            la, lb = left.lam, right.lam[perm]
            (da, ka), (db, kb) = (_derivative(left.W, dA_a, left.R),
                                  _derivative(right.W, dA_b, right.R))
            db, kb = db[perm], kb[perm]
            fa, fb = la.real, lb.real
            crossing = fa * fb < 0
            near = crossing | (np.minimum(np.abs(fa), np.abs(fb))
                               <= np.abs(lb - la) + 1e-12 * scale)
            ok = np.isfinite(da) & np.isfinite(db) & (ka < _KAPPA_MAX) & (kb < _KAPPA_MAX)
            bad = near & (s < min_score)
            hump = _suspect(fa, fb, h * da.real, h * db.real, ok)
            if (bad.any() or hump.any()) and depth < max_depth:
                mid = _Node(0.5 * (left.V + right.V), Am)
                pending[-1] = (right, depth + 1)
                pending.append((mid, depth + 1))
                n_refined += 1
                continue
            pending.pop()
            n_unresolved += int(bad.any())
            nodes.append(right.permuted(perm))
            intervals.append((dA_a, dA_b))
            scores.append(float(np.min(s[near])) if near.any() else 1.0)
    lam = np.array([n.lam for n in nodes])
    tracking = EigenTracking(np.array([n.V for n in nodes]), lam,
                             np.array([n.R for n in nodes]), np.array(scores), n_refined,
                             n_unresolved)
    crossings = []
    for i, k in _sign_changes(lam.real):
        (dA_a, dA_b), a, b = intervals[i], nodes[i], nodes[i + 1]
        if a.lam[k].imag < -1e-9 * scale and b.lam[k].imag < -1e-9 * scale:
            continue                      # the conjugate partner reports this crossing
        Vc, lc, slope, ok = _locate(fn, a, b, dA_a, dA_b, int(k), xtol)
        divergence = abs(lc.imag) <= 1e-7 * scale
        if not divergence and lc.imag < 0:
            continue
        crossings.append(Crossing(
            V=Vc, eigenvalue=lc, omega=0.0 if divergence else abs(lc.imag),
            frequency_hz=0.0 if divergence else abs(lc.imag) / (2 * np.pi), branch=int(k),
            origin_mode=-1, kind="divergence" if divergence else "flutter",
            direction="destabilizing" if b.lam[k].real > a.lam[k].real else "stabilizing",
            slope=slope, converged=ok, bracket=(a.V, b.V)))
    crossings.sort(key=lambda c: c.V)
    return _result(family, tracking, tuple(crossings), scale)


def _result(family: PlantFamily, tracking: EigenTracking, crossings: tuple,
            scale: float) -> FlutterResult:
    su, tu = family.speed_unit, family.time_unit
    flut = next((c for c in crossings if c.kind == "flutter"
                 and c.direction == "destabilizing"), None)
    div = next((c for c in crossings if c.kind == "divergence"
                and c.direction == "destabilizing"), None)
    lo, hi = tracking.V[0], tracking.V[-1]
    if flut is not None:
        status = "flutter"
        msg = (f"{family.name}: flutter at {flut.V:.10g} {su}, {flut.omega:.6g} rad/{tu} "
               f"({flut.omega / (2 * np.pi):.6g} cycles/{tu}), branch {flut.branch}")
    elif div is not None:
        status, msg = "divergence", f"{family.name}: no flutter; divergence at {div.V:.10g} {su}"
    else:
        status = "no_crossing"
        msg = (f"{family.name}: no eigenvalue crosses the imaginary axis for speeds in "
               f"[{lo:g}, {hi:g}] {su}")
    sa0 = float(np.max(tracking.eigenvalues[0].real))
    unstable0 = sa0 > 1e-12 * scale
    if unstable0:
        msg += (f"; WARNING: unstable already at {lo:g} {su} (spectral abscissa {sa0:.3g}): "
                "crossings are not instability onsets")
        _LOG.warning(msg)
    if any(not c.converged for c in crossings):
        msg += "; some crossings were not located to tolerance (see Crossing.converged)"
    if tracking.n_unresolved:
        msg += (f"; {tracking.n_unresolved} intervals kept a poorly matched branch near the "
                "axis after the bisections (refine the grid)")
    return FlutterResult(
        status=status, Vf=None if flut is None else flut.V,
        omega_f=None if flut is None else flut.omega,
        frequency_hz=None if flut is None else flut.frequency_hz, flutter_mode=None,
        flutter=flut, divergence=div, crossings=crossings, unstable_at_start=unstable0,
        spectral_abscissa_start=sa0, tracking=tracking,
        origin=-np.ones(tracking.n_branches, dtype=int), message=msg)
