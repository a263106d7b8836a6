"""Continuation in the controller order: from a good higher-order controller down to the order.

The local optimiser of :mod:`._synthesis` finds the optimum of the basin it starts in.  On
plants whose full-order optimum needs more dynamics than the requested order (several
near-integrating tracking weights, lightly damped modes) a reduction of the full-order
controller straight to a low order lands far from any good basin: each reduction throws away
dynamics that the optimiser then cannot rebuild.  Going down *one state at a time*, and
re-optimising at every intermediate order, lets the remaining states re-arrange themselves
each time a state goes (the homotopy in the order used for fixed-order design, e.g. by
HIFOO's users and in Apkarian & Noll's hinfstruct practice).

This module gives the candidate controllers of one step down: every way of removing one
real mode or one complex pair of ``K`` by *modal residualisation* (the removed mode's DC
contribution is kept in the feed-through, so the low-frequency behaviour, where integral
action acts, is preserved), plus the reductions of :func:`._fullorder.reduced_controllers`.
Everything is deterministic.
"""

from __future__ import annotations

import logging

import control
import numpy as np
import scipy.linalg as sla

from ._fullorder import reduced_controllers

__all__ = ["modal_deletions", "step_down_candidates"]

log = logging.getLogger("casflutter.design")


def _remove_block(A, B, C, D, keep: np.ndarray) -> control.StateSpace | None:
    """Residualise the modes of ``A`` not selected by ``keep`` (eigenvalue mask of the
    ordered real Schur form), keeping the selected ones exactly; ``None`` when the split
    is ill conditioned or the removed part is singular."""
    n = A.shape[0]
    k = int(np.sum(keep))
    lam = np.linalg.eigvals(A)
    try:
        # the selected eigenvalues first: match each Schur eigenvalue against the kept set
        kept = lam[keep]

        def sel(x, y=None):
            z = complex(x, 0.0 if y is None else y)
            return bool(np.min(np.abs(kept - z)) <= 1e-9 * max(1.0, abs(z)))

        T, Z, sdim = sla.schur(A, output="real", sort=sel)
        if sdim != k:
            return None
        A11, A12, A22 = T[:k, :k], T[:k, k:], T[k:, k:]
        Bz, Cz = Z.T @ B, C @ Z
        X = sla.solve_sylvester(A11, -A22, -A12)
        if not np.all(np.isfinite(X)) or np.max(np.abs(X), initial=0.0) > 1e8:
            return None
        B1 = Bz[:k] - X @ Bz[k:]
        C2 = Cz[:, k:] + Cz[:, :k] @ X
        if np.linalg.cond(A22) > 1e12:
            return None
        Dr = D - C2 @ np.linalg.solve(A22, Bz[k:])
    except (np.linalg.LinAlgError, ValueError):
        return None
    if k == 0:
        return control.ss([], [], [], Dr) if Dr.size else None
    return control.ss(A11, B1, Cz[:, :k], Dr)


def modal_deletions(K: control.StateSpace) -> list[control.StateSpace]:
    """Every controller obtained from ``K`` by residualising one real mode or one complex
    pair (the rest kept exactly, the DC gain unchanged).

    Parameters
    ----------
    K : control.StateSpace
        Controller of order ``>= 1``.

    Returns
    -------
    list of control.StateSpace
        One controller per real pole or complex pair of ``K`` (order ``n - 1`` or ``n - 2``),
        in increasing order of the removed mode's H∞-like weight ``|C v| |w B| / |Re λ|``
        (the least important first); modes whose removal is ill conditioned are left out.
    """
    A, B, C, D = (np.asarray(M, float) for M in (K.A, K.B, K.C, K.D))
    n = A.shape[0]
    if n == 0:
        return []
    lam, VL, VR = sla.eig(A, left=True, right=True)
    out = []
    seen = np.zeros(n, bool)
    for i in range(n):
        if seen[i] or lam[i].imag < -1e-12 * max(1.0, abs(lam[i])):
            continue
        drop = np.abs(lam - lam[i]) <= 1e-9 * max(1.0, abs(lam[i]))
        if abs(lam[i].imag) > 1e-12 * max(1.0, abs(lam[i])):
            drop |= np.abs(lam - np.conj(lam[i])) <= 1e-9 * max(1.0, abs(lam[i]))
        seen |= drop
        if np.sum(drop) not in (1, 2):
            continue                      # repeated eigenvalue: not a single mode
        y, x = VL[:, i], VR[:, i]
        yx = abs(y.conj() @ x)
        weight = (np.linalg.norm(C @ x) * np.linalg.norm(y.conj() @ B)
                  / max(yx, 1e-300) / max(abs(lam[i].real), 1e-12 * max(1.0, abs(lam[i]))))
        Kr = _remove_block(A, B, C, D, ~drop)
        if Kr is not None:
            out.append((float(weight), i, Kr))
    out.sort(key=lambda t: (t[0], t[1]))
    return [Kr for _, _, Kr in out]


def step_down_candidates(K: control.StateSpace, order: int) -> list[control.StateSpace]:
    """Candidate starts of order ``<= order`` from a controller ``K`` of higher order.

    Parameters
    ----------
    K : control.StateSpace
        Controller of order ``> order`` (typically ``order + 1``).
    order : int
        Target order.

    Returns
    -------
    list of control.StateSpace
        The reductions of :func:`._fullorder.reduced_controllers` (balanced truncation,
        balanced singular perturbation, slowest modes) followed by the single-mode
        residualisations of :func:`modal_deletions` that have at most ``order`` states.
    """
    out = list(reduced_controllers(K, order))
    if K.nstates <= order:
        return out
    out += [Kr for Kr in modal_deletions(K) if Kr.nstates <= order]
    return out
