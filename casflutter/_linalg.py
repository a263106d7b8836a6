"""Small linear-algebra helpers shared by the stages (verification keeps its own)."""

from __future__ import annotations

import numpy as np

__all__ = ["spectral_abscissa"]


def spectral_abscissa(A) -> float:
    """Largest real part of the eigenvalues of ``A`` (``-inf`` for an empty matrix).

    Parameters
    ----------
    A : array_like, shape (n, n)
        A state matrix.

    Returns
    -------
    float
        ``max Re λ(A)``: negative when ``ẋ = A x`` is asymptotically stable.
    """
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return -np.inf
    return float(np.linalg.eigvals(A).real.max())
