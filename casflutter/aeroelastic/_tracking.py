"""Eigenvalue branch tracking by eigenvector continuity.

Works on any callable ``V -> state matrix`` (ΣAE(V), a truth simulator's
``state_matrix``).  Between two speed indices Va < Vb the eigenvalues are matched by
the bi-orthogonality of left and right eigenvectors: with ``W(Va)`` the left
eigenvectors (rows of ``inv(R(Va))``, so that ``W R = I`` at Va) and ``R(Vb)`` the
unit-norm right eigenvectors at Vb, the overlap matrix ``M = W(Va) R(Vb)`` tends to a
diagonal matrix as Vb → Va.  Its column-normalised magnitudes
``S_ij = |M_ij| / ||M_:j||`` are the match scores, and the assignment maximising
``Σ S`` is found with :func:`scipy.optimize.linear_sum_assignment`.  This separates
complex-conjugate partners (whose right eigenvectors alone can be almost parallel), and
never sorts eigenvalues.  When the smallest assigned score is below ``min_score`` the
interval is bisected (adaptive grid refinement) up to ``max_refine`` times.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.optimize import linear_sum_assignment

from .._format import result_repr
from ..errors import ConfigError

__all__ = ["EigenTracking", "track_eigenvalues", "eig_sorted_by_reference", "as_matrix_fn"]

MatrixFn = Callable[[float], np.ndarray]


def as_matrix_fn(system) -> MatrixFn:
    """Return ``V -> A(V)`` from a callable or an object with ``state_matrix(V)``."""
    if hasattr(system, "state_matrix"):
        return system.state_matrix
    if callable(system):
        return system
    raise ConfigError(
        f"{type(system).__name__} is neither a callable V -> state matrix nor an object with "
        "a state_matrix(V) method")


def _eig(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    A = np.asarray(A, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.all(np.isfinite(A)):
        raise ConfigError(f"state matrix must be square and finite, got shape {A.shape}")
    lam, R = np.linalg.eig(A)
    R = R / np.linalg.norm(R, axis=0)
    return lam, R


def _scores(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """Column-normalised |W(Va) R(Vb)|, rows = branches at Va, columns = eigenpairs at Vb."""
    try:
        M = np.linalg.solve(R_a, R_b)
    except np.linalg.LinAlgError:
        M = np.linalg.lstsq(R_a, R_b, rcond=None)[0]
    M = np.abs(M)
    return M / np.maximum(np.linalg.norm(M, axis=0), 1e-300)


def _match(R_a: np.ndarray, lam_a: np.ndarray, R_b: np.ndarray, lam_b: np.ndarray
           ) -> tuple[np.ndarray, float]:
    """Permutation ``p`` (branch k at Va -> eigenpair p[k] at Vb) and its worst score."""
    S = _scores(R_a, R_b)
    # eigenvalue proximity only breaks exact ties (e.g. at an exceptional point)
    scale = max(np.max(np.abs(lam_a)), 1.0)
    cost = -S + 1e-6 * np.abs(lam_a[:, None] - lam_b[None, :]) / scale
    rows, cols = linear_sum_assignment(cost)
    perm = np.empty_like(cols)
    perm[rows] = cols
    return perm, float(np.min(S[rows, cols]))


def eig_sorted_by_reference(A: np.ndarray, R_ref: np.ndarray, lam_ref: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray, float]:
    """Eigen-decompose ``A`` and order it like the reference branches ``(lam_ref, R_ref)``.

    Returns
    -------
    lam, R, score
        Eigenvalues, unit right eigenvectors in branch order, and the worst match score.
    """
    lam, R = _eig(A)
    perm, score = _match(R_ref, lam_ref, R, lam)
    return lam[perm], R[:, perm], score


@dataclass(frozen=True)
class EigenTracking:
    """Eigenvalue branches of ``A(V)`` over a (refined) grid of speed indices.

    Attributes
    ----------
    V : ndarray, shape (nV,)
        Speed indices (the requested grid plus refinement points), increasing.
    eigenvalues : ndarray, shape (nV, n)
        ``eigenvalues[k, b]`` is branch b at ``V[k]``.
    eigenvectors : ndarray, shape (nV, n, n)
        Unit-norm right eigenvectors, column b belonging to branch b.
    scores : ndarray, shape (nV - 1,)
        Worst eigenvector-continuity score of each step (1 = perfect match).
    n_refined : int
        Number of points inserted by adaptive refinement.
    n_unresolved : int
        Steps still below ``min_score`` after ``max_refine`` bisections (typically at an
        exceptional point where two eigenvectors coalesce).
    """

    __repr__ = result_repr

    V: np.ndarray
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    scores: np.ndarray
    n_refined: int
    n_unresolved: int

    @property
    def n_branches(self) -> int:
        """Number of branches (the state dimension)."""
        return self.eigenvalues.shape[1]

    @property
    def damping_ratio(self) -> np.ndarray:
        """``ζ = −Re λ / |λ|`` per point and branch (V–g data; g = 2ζ in the classical sense)."""
        lam = self.eigenvalues
        return -lam.real / np.maximum(np.abs(lam), 1e-300)

    @property
    def frequency(self) -> np.ndarray:
        """Im λ [rad/s] per point and branch (signed; conjugate partners are negative)."""
        return self.eigenvalues.imag

    @property
    def frequency_hz(self) -> np.ndarray:
        """Im λ / 2π [Hz] per point and branch (signed)."""
        return self.eigenvalues.imag / (2.0 * np.pi)

    def upper_branches(self) -> np.ndarray:
        """Branch indices with non-negative mean frequency: one of each conjugate pair plus
        the real branches (what V–g / V–f plots show)."""
        scale = max(float(np.max(np.abs(self.eigenvalues))), 1.0)
        return np.flatnonzero(np.mean(self.eigenvalues.imag, axis=0) > -1e-9 * scale)


def track_eigenvalues(matrix_fn, V_grid, *, min_score: float = 0.9, max_refine: int = 8
                      ) -> EigenTracking:
    """Track the eigenvalues of ``A(V)`` along ``V_grid`` by eigenvector continuity.

    Parameters
    ----------
    matrix_fn : callable or object with ``state_matrix``
        ``V -> A(V)`` (square real matrix), e.g. :meth:`AeroelasticSystem.state_matrix`.
    V_grid : array_like
        Increasing speed indices (at least 2).
    min_score : float
        An interval whose worst match score (see module docstring) is below this value is
        bisected.
    max_refine : int
        Maximum bisection depth per grid interval.

    Returns
    -------
    EigenTracking
        The branches at the speeds of ``V_grid`` and at those the bisection added.

    See Also
    --------
    find_flutter : the flutter speed from the tracked branches.

    Examples
    --------
    >>> import numpy as np
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> tr = cf.track_eigenvalues(truth.state_matrix, np.linspace(0.5, 3.0, 51))
    >>> tr.eigenvalues.shape[0]
    51
    """
    fn = as_matrix_fn(matrix_fn)
    V_grid = np.asarray(V_grid, dtype=float).ravel()
    if V_grid.size < 2 or np.any(np.diff(V_grid) <= 0) or not np.all(np.isfinite(V_grid)):
        raise ConfigError("V_grid must hold at least 2 finite, strictly increasing speed indices")
    if not 0.0 < min_score < 1.0:
        raise ConfigError(f"min_score must be in (0, 1), got {min_score}")
    lam0, R0 = _eig(fn(V_grid[0]))
    Vs, lams, Rs, scores = [V_grid[0]], [lam0], [R0], []
    n_ref = n_unres = 0
    for Vb in V_grid[1:]:
        # stack of pending right ends; refine [Va, Vb] until every step matches well
        pending = [(Vb, *_eig(fn(Vb)), 0)]
        while pending:
            Vr, lam_r, R_r, depth = pending[-1]
            Va, lam_a, R_a = Vs[-1], lams[-1], Rs[-1]
            perm, s = _match(R_a, lam_a, R_r, lam_r)
            if s < min_score and depth < max_refine:
                Vm = 0.5 * (Va + Vr)
                pending.append((Vm, *_eig(fn(Vm)), depth + 1))
                pending[-2] = (Vr, lam_r, R_r, depth + 1)
                n_ref += 1
                continue
            pending.pop()
            n_unres += s < min_score
            Vs.append(Vr)
            lams.append(lam_r[perm])
            Rs.append(R_r[:, perm])
            scores.append(s)
    return EigenTracking(np.asarray(Vs), np.asarray(lams), np.asarray(Rs), np.asarray(scores),
                         n_ref, int(n_unres))
