"""Starts for the fixed-order synthesis from the full-order H∞ controller.

The local optimiser of :mod:`._synthesis` only finds the optimum of the basin it starts in.
On plants whose good controllers need dynamics (near-integral action on weighted tracking
errors, lead on lightly damped modes) the zero and random starts land in poor basins.  The
full-order problem, in contrast, is solved globally by two Riccati equations (Glover & Doyle
1988; Doyle, Glover, Khargonekar & Francis 1989): its central controller at a level slightly
above the optimum ``γ*`` contains the dynamics that matter, and a *balanced truncation* of it
(Moore 1981) — or the singular-perturbation variant that keeps the DC gain — to the requested
order is a start in the right basin.  These starts are then optimised like every other.

The Riccati solution needs a *regular* problem: ``D12`` of full column rank and ``D21`` of
full row rank (and no invariant zeros on the imaginary axis, which the solver itself
reports).  Many benchmark plants are singular; for them, or when the optional slycot package
is missing, no full-order start is made (the function returns an empty list) and the
synthesis runs with its other starts.  The rank test is made *before* calling SLICOT: on
singular problems the γ-iteration of SB10AD can take many seconds before it refuses.

Everything is deterministic (no random choice); the SLICOT routines are SB10AD (central
controller; bisection on γ, then the controller at ``gamma_factor`` times the γ found) and
AB09AD/AB09MD/AB09ND (balanced truncation / singular perturbation, through
:func:`control.balred`); the third reduction (slowest modes, the rest residualised) is
numpy/scipy.
"""

from __future__ import annotations

import logging

import control
import numpy as np
import scipy.linalg as sla

from ._plant import Partition

__all__ = ["full_order_controller", "reduced_controllers"]

log = logging.getLogger("casflutter.design")

_RANK_TOL = 1e-8
_AXIS_TOL = 1e-9
"""Relative distance to the imaginary axis within which a controller pole counts as
unstable (:func:`reduced_controllers`): the count then does not hinge on rounding."""


def _full_rank(M: np.ndarray, rows: bool) -> bool:
    """Numerical full row (``rows``) or column rank of ``M`` (relative SVD test)."""
    need = M.shape[0] if rows else M.shape[1]
    if need == 0:
        return True
    if M.size == 0 or (M.shape[1] if rows else M.shape[0]) < need:
        return False
    s = np.linalg.svd(M, compute_uv=False)
    return bool(s.size >= need and s[need - 1] > _RANK_TOL * max(1.0, float(s[0])))


def is_regular(P: Partition) -> bool:
    """``D12`` of full column rank and ``D21`` of full row rank (the rank conditions of the
    Riccati solution of the full-order problem)."""
    return _full_rank(P.D12, rows=False) and _full_rank(P.D21, rows=True)


def full_order_controller(P: Partition, gamma_factor: float = 1.1
                          ) -> tuple[control.StateSpace, float] | None:
    """Full-order H∞ central controller of a regular plant, at ``gamma_factor`` times the
    optimal level.

    Parameters
    ----------
    P : Partition
        The generalised plant (``u = K y`` on its measurement, ``hinfsyn`` convention).
    gamma_factor : float
        The controller is the central one at ``gamma_factor γ_opt`` (``> 1``): at the optimum
        itself the central controller has poles running to infinity.

    Returns
    -------
    (K, gamma_opt) or None
        The controller and the optimal full-order level found by bisection; ``None`` when the
        problem is singular, slycot is not installed, or SLICOT refuses it.
    """
    if not is_regular(P):
        log.info("full-order start: singular problem (D12 or D21 rank deficient), skipped")
        return None
    try:
        from slycot import sb10ad  # noqa: PLC0415 - optional dependency
    except ImportError:
        log.info("full-order start: slycot not installed, skipped")
        return None
    nw, nz, nu, ny = P.dims
    A = P.A
    B = np.hstack([P.B1, P.B2])
    C = np.vstack([P.C1, P.C2])
    D = np.block([[P.D11, P.D12], [P.D21, P.D22]])
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    try:
        # job=1: bisection on γ (no scan), from a level far above any plausible norm
        g_opt = float(sb10ad(n, m, p, nu, ny, 1e8 * max(1.0, float(np.max(np.abs(D)))),
                             A, B, C, D, job=1)[0])
        out = sb10ad(n, m, p, nu, ny, gamma_factor * g_opt, A, B, C, D, job=4)
    except Exception as exc:  # noqa: BLE001 - SLICOT refuses with several exception types
        # the whole reason on one line (SLICOT's messages span several)
        log.info("full-order start: SLICOT refused the problem (%s), skipped",
                 " ".join(str(exc).split()) or type(exc).__name__)
        return None
    Ak, Bk, Ck, Dk = (np.asarray(M, float) for M in out[1:5])
    if not all(np.all(np.isfinite(M)) for M in (Ak, Bk, Ck, Dk)):
        return None
    log.debug("full-order start: gamma_opt %.6g, central controller at %.6g", g_opt,
              gamma_factor * g_opt)
    return control.ss(Ak, Bk, Ck, Dk), g_opt


def slow_modal(K: control.StateSpace, order: int) -> control.StateSpace | None:
    """Keep the ``order`` slowest modes of ``K`` and replace the others by their DC gain.

    An ordered real Schur form puts the slow poles first; a Sylvester equation decouples the
    two parts exactly, and the fast part is residualised (``D - C2 A22⁻¹ B2``).  The slow
    dynamics of an H∞ controller are its (near-)integral action on weighted tracking errors,
    which balanced truncation of the controller alone may discard.  ``None`` when the split
    would cut a complex pair or the fast part is singular.
    """
    A, B, C, D = (np.asarray(M, float) for M in (K.A, K.B, K.C, K.D))
    n = A.shape[0]
    if not 0 < order < n:
        return None
    mags = np.sort(np.abs(np.linalg.eigvals(A)))
    if mags[order] <= mags[order - 1] * (1 + 1e-9):
        return None
    thr = 0.5 * (mags[order - 1] + mags[order])
    try:
        T, Z, sdim = sla.schur(A, output="real", sort=lambda x, y: np.hypot(x, y) <= thr)
        if sdim != order:
            return None
        A11, A12, A22 = T[:order, :order], T[:order, order:], T[order:, order:]
        Bz, Cz = Z.T @ B, C @ Z
        X = sla.solve_sylvester(A11, -A22, -A12)       # [I X; 0 I] block-diagonalises T
        B1 = Bz[:order] - X @ Bz[order:]
        C2 = Cz[:, order:] + Cz[:, :order] @ X
        Dr = D - C2 @ np.linalg.solve(A22, Bz[order:])
    except (np.linalg.LinAlgError, ValueError):
        return None
    return control.ss(A11, B1, Cz[:, :order], Dr)


def reduced_controllers(K: control.StateSpace, order: int) -> list[control.StateSpace]:
    """Reductions of ``K`` to at most ``order`` states: balanced truncation, balanced
    singular perturbation (DC gain kept) and the slowest modes with the others residualised
    (:func:`slow_modal`); ``[K]`` when it is already small enough.

    Reductions that fail (e.g. more unstable controller poles than ``order``) are left out.
    """
    if K.nstates <= order:
        return [K]
    out = []
    Km = slow_modal(K, order)
    if Km is not None:
        out.append(Km)
    # poles within _AXIS_TOL of the imaginary axis (an integrator of the central controller)
    # count as unstable whatever the sign of their rounded real part
    lam = np.linalg.eigvals(np.asarray(K.A, float))
    unstable = int(np.sum(lam.real >= -_AXIS_TOL * np.maximum(np.abs(lam), 1.0)))
    for method in ("truncate", "matchdc"):
        if unstable > order:
            # balred keeps the whole unstable part: the result would exceed the order
            log.debug("full-order start: no balanced reduction to order %d (%d unstable "
                      "controller poles)", order, unstable)
            break
        try:
            Kr = control.balred(K, order, method=method)
        except Exception as exc:  # noqa: BLE001 - SLICOT errors of several types
            log.debug("full-order start: %s reduction to order %d failed (%s)", method, order,
                      type(exc).__name__)
            continue
        mats = [np.asarray(M, float) for M in (Kr.A, Kr.B, Kr.C, Kr.D)]
        if Kr.nstates <= order and all(np.all(np.isfinite(M)) for M in mats):
            out.append(Kr)
    return out
