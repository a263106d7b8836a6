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
full row rank (and no invariant zeros of ``P12`` or ``P21`` on the imaginary axis, which the
solver itself reports).  Many benchmark plants are singular (COMPleib's mostly are: no
direct control weight, or a measurement without its own noise).  A singular plant is
*regularised* first (:func:`regularized`): small outputs ``ε x`` and ``ε u`` join ``z`` and
small inputs join ``w`` on every state and measurement, which makes ``D12`` and ``D21`` of
full rank and leaves ``P12``, ``P21`` without zeros.  Its central controller stabilises the
plant itself (stability depends only on ``A, B2, C2, D22``, which are unchanged), and for a
small ``ε`` its dynamics are those the plant's near-optimal controllers need.  When slycot
is missing no full-order start is made (the function returns ``None``) and the synthesis
runs with its other starts.  The rank test is made *before* calling SLICOT: on singular
problems the γ-iteration of SB10AD can take many seconds before it refuses.

Everything is deterministic (no random choice); the SLICOT routines are SB10AD (central
controller; bisection on γ, then the controller at ``gamma_factor`` times the γ found) and
AB09AD/AB09MD/AB09ND (balanced truncation / singular perturbation, through
:func:`control.balred`); the third reduction (slowest modes, the rest residualised) is
numpy/scipy.
"""

from __future__ import annotations

import hashlib
import logging

import control
import numpy as np
import scipy.linalg as sla

from ._norm import level_crossings, sigma_max
from ._plant import Partition

__all__ = ["full_order_controller", "reduced_controllers", "regularized"]

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


def _size(*blocks: np.ndarray) -> float:
    """The largest 2-norm of the non-empty ``blocks`` (1 where all are empty or zero)."""
    return max([float(np.linalg.norm(M, 2)) for M in blocks if M.size] + [0.0]) or 1.0


def regularized(P: Partition, eps: float) -> Partition:
    """``P`` with the outputs ``ε_z x``, ``ε_z u`` added to ``z`` and the inputs ``ε_w w_x``
    (on every state) and ``ε_w w_y`` (on every measurement) added to ``w``.

    ``ε_z = eps · max(‖C1‖, ‖D12‖)`` and ``ε_w = eps · max(‖B1‖, ‖D21‖)`` (2-norms; 1 in
    place of an all-zero pair), so that the new channels are small beside the plant's own.
    ``D12`` then has full column rank and ``D21`` full row rank, and ``P12``, ``P21`` have no
    invariant zeros (their system matrices have ``ε I`` blocks on every state): the problem
    is regular.  ``A, B2, C2, D22`` are unchanged, so a controller stabilises the result
    exactly when it stabilises ``P``, and the result's norm bounds ``P``'s from above.

    Parameters
    ----------
    P : Partition
        A generalised plant (regular or not).
    eps : float
        Relative size of the added channels (``> 0``).

    Returns
    -------
    Partition
    """
    n, (nw, nz, nu, ny) = P.nx, P.dims
    ez = eps * _size(P.C1, P.D12)
    ew = eps * _size(P.B1, P.D21)
    return Partition(
        A=P.A, B1=np.hstack([P.B1, ew * np.eye(n), np.zeros((n, ny))]), B2=P.B2,
        C1=np.vstack([P.C1, ez * np.eye(n), np.zeros((nu, n))]), C2=P.C2,
        D11=np.block([[P.D11, np.zeros((nz, n + ny))],
                      [np.zeros((n + nu, nw + n + ny))]]),
        D12=np.vstack([P.D12, np.zeros((n, nu)), ez * np.eye(nu)]),
        D21=np.hstack([P.D21, np.zeros((ny, n)), ew * np.eye(ny)]), D22=P.D22)


def full_order_controller(P: Partition, gamma_factor: float = 1.1,
                          regularization: float = 0.0
                          ) -> tuple[control.StateSpace, float] | None:
    """Full-order H∞ central controller of a plant, at ``gamma_factor`` times the optimal
    level.

    Parameters
    ----------
    P : Partition
        The generalised plant (``u = K y`` on its measurement, ``hinfsyn`` convention).
    gamma_factor : float
        The controller is the central one at ``gamma_factor γ_opt`` (``> 1``): at the optimum
        itself the central controller has poles running to infinity.
    regularization : float
        A singular plant (``D12`` or ``D21`` rank deficient) is first
        :func:`regularized` with this ``eps``; ``0``: a singular plant gets none.

    Returns
    -------
    (K, gamma_opt) or None
        The controller and the optimal full-order level found by SB10AD's bisection (of the
        regularised plant where ``P`` is singular: an upper bound on ``P``'s).  Where the
        central controller at ``gamma_factor`` times that level does not achieve it (its
        closed loop unstable or of a larger norm, checked here), the level is doubled until
        it does.  ``None`` when the problem is singular and ``regularization`` is 0, slycot
        is not installed, or SLICOT refuses it.
    """
    key = _key(P, gamma_factor, regularization)
    if key not in _CACHE:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = _full_order(P, gamma_factor, regularization)
    return _CACHE[key]


_CACHE: dict = {}
_CACHE_SIZE = 8
"""Full-order controllers of the last plants (:func:`full_order_controller` is a function of
the plant alone, and a study of several orders on one plant asks for it at each)."""


def _key(P: Partition, *numbers: float) -> str:
    """A digest of ``P``'s blocks (shapes and bytes) and ``numbers``."""
    h = hashlib.sha256(repr(numbers).encode())
    for M in (P.A, P.B1, P.B2, P.C1, P.C2, P.D11, P.D12, P.D21, P.D22):
        M = np.ascontiguousarray(M, dtype=float)
        h.update(repr(M.shape).encode())
        h.update(M.tobytes())
    return h.hexdigest()


def _full_order(P: Partition, gamma_factor: float, regularization: float
                ) -> tuple[control.StateSpace, float] | None:
    """:func:`full_order_controller`, not cached."""
    if not is_regular(P):
        if regularization <= 0:
            log.info("full-order start: singular problem (D12 or D21 rank deficient), "
                     "skipped")
            return None
        log.debug("full-order start: singular problem (D12 or D21 rank deficient), "
                  "regularised with eps = %g", regularization)
        P = regularized(P, regularization)
    try:
        import slycot  # noqa: F401, PLC0415 - optional dependency
    except ImportError:
        log.info("full-order start: slycot not installed, skipped")
        return None
    try:
        # job=1: bisection on γ (no scan), from a level far above any plausible norm
        top = 1e8 * max(1.0, float(np.max(np.abs(P.statespace().D))))
        g_opt = float(_sb10ad(P, top, job=1)[0])
    except Exception as exc:  # noqa: BLE001 - SLICOT refuses with several exception types
        # the whole reason on one line (SLICOT's messages span several)
        log.info("full-order start: SLICOT refused the problem (%s), skipped",
                 " ".join(str(exc).split()) or type(exc).__name__)
        return None
    # SB10AD's bisection can end at a level its own controller does not achieve (on
    # ill-conditioned, e.g. regularised, problems): the level is raised until the central
    # controller's closed loop is stable with a norm below it
    for _ in range(_LEVEL_TRIES):
        K = _central(P, gamma_factor * g_opt)
        if K is not None:
            log.debug("full-order start: gamma_opt %.6g, central controller at %.6g", g_opt,
                      gamma_factor * g_opt)
            return K, g_opt
        g_opt *= 2.0
    log.info("full-order start: no central controller achieved its level, skipped")
    return None


_LEVEL_TRIES = 12
"""Levels tried by :func:`full_order_controller`, doubling from SB10AD's optimum."""


def _sb10ad(P: Partition, level: float, job: int) -> tuple:
    """SLICOT SB10AD on ``P`` at ``level`` (``job=1``: bisection down from it; ``job=4``:
    the central controller at it); raises what SLICOT raises."""
    from slycot import sb10ad  # noqa: PLC0415 - optional dependency, checked by the caller

    S = P.statespace()
    _, _, nu, ny = P.dims
    return sb10ad(P.nx, S.ninputs, S.noutputs, nu, ny, level, S.A, S.B, S.C, S.D, job=job)


def _central(P: Partition, level: float) -> control.StateSpace | None:
    """SB10AD's central controller of ``P`` at ``level``, or ``None`` when SLICOT refuses it
    or its closed loop is not stable with a norm below ``level`` (:func:`_below`)."""
    try:
        out = _sb10ad(P, level, job=4)
    except Exception:  # noqa: BLE001 - SLICOT refuses with several exception types
        return None
    Ak, Bk, Ck, Dk = (np.asarray(M, float) for M in out[1:5])
    if not all(np.all(np.isfinite(M)) for M in (Ak, Bk, Ck, Dk)):
        return None
    Kbar = np.block([[Dk, Ck], [Bk, Ak]])
    try:
        ok = _below(*P.augmented(Ak.shape[0]).closed_loop(Kbar), level)
    except np.linalg.LinAlgError:
        return None
    return control.ss(Ak, Bk, Ck, Dk) if ok else None


def _below(A, B, C, D, level: float) -> bool:
    """Whether ``(A, B, C, D)`` is stable with ``‖T‖∞ < level``, as far as a start needs to
    know: ``A`` Hurwitz, ``σ_max(D) < level``, and ``σ_max(T(jω)) < level`` at ``ω = 0``,
    at the poles' frequencies and wherever the level's Hamiltonian has an imaginary
    eigenvalue (one eigenvalue problem instead of the whole norm; the poles' frequencies
    catch a peak whose crossings an ill-conditioned Hamiltonian blurs off the axis)."""
    if not np.all(np.isfinite(A)):
        return False
    lam = np.linalg.eigvals(A)
    if np.max(lam.real) >= 0 or (D.size and np.linalg.norm(D, 2) >= level):
        return False
    w = np.concatenate([[0.0], np.abs(lam.imag), level_crossings(A, B, C, D, level)])
    return bool(np.all(sigma_max(A, B, C, D, np.unique(w)) < level))


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
