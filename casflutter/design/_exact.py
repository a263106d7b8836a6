"""Exact rational linear algebra, for certificates that are proofs.

A plant's matrices are binary floating-point numbers, i.e. exact rationals.  A certificate
re-checked on them with :class:`fractions.Fraction` (no rounding anywhere) is a proof about
that plant, not a computation with a margin.  Dense Gauss-Jordan elimination: the numbers
grow with the dimension, which suits the tens of states of a benchmark plant, not hundreds.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Sequence

import numpy as np

Matrix = list  # list of rows of Fraction

__all__ = ["fractions", "matmul", "transpose", "combine", "identity", "solve",
           "negative_eigenvalues", "is_positive_definite"]


def fractions(M) -> Matrix:
    """The exact rational values of a real float array (2-D; a 1-D array is one row)."""
    A = np.atleast_2d(np.asarray(M, dtype=float))
    if not np.all(np.isfinite(A)):
        raise ValueError("exact arithmetic needs finite entries")
    return [[Fraction(float(x)) for x in row] for row in A]


def identity(n: int) -> Matrix:
    return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]


def transpose(A: Matrix) -> Matrix:
    return [list(r) for r in zip(*A)] if A else []


def matmul(A: Matrix, B: Matrix) -> Matrix:
    cols = list(zip(*B))
    return [[sum((a * b for a, b in zip(row, col)), Fraction(0)) for col in cols] for row in A]


def combine(terms: Sequence[tuple[Fraction, Matrix]]) -> Matrix:
    """``Σ c_i A_i`` for equally sized matrices."""
    rows, cols = len(terms[0][1]), len(terms[0][1][0])
    return [[sum((c * A[i][j] for c, A in terms), Fraction(0)) for j in range(cols)]
            for i in range(rows)]


def solve(A: Matrix, B: Matrix) -> Matrix:
    """``A⁻¹ B`` by Gauss-Jordan elimination (raises ``ZeroDivisionError`` if ``A`` is
    singular)."""
    n = len(A)
    M = [list(A[i]) + list(B[i]) for i in range(n)]
    for c in range(n):
        p = next((r for r in range(c, n) if M[r][c] != 0), None)
        if p is None:
            raise ZeroDivisionError("singular matrix")
        M[c], M[p] = M[p], M[c]
        pivot = M[c][c]
        M[c] = [x / pivot for x in M[c]]
        for r in range(n):
            f = M[r][c]
            if r != c and f != 0:
                M[r] = [x - f * y for x, y in zip(M[r], M[c])]
    return [row[n:] for row in M]


def negative_eigenvalues(S: Matrix) -> int | None:
    """The number of negative eigenvalues of the symmetric ``S``, from the signs of the pivots
    of its symmetric elimination ``S = L D Lᵀ`` (Sylvester's law of inertia); ``None`` when a
    pivot is zero (the elimination, without pivoting, then says nothing)."""
    A = [list(r) for r in S]
    n, neg = len(A), 0
    for c in range(n):
        if A[c][c] == 0:
            return None
        neg += A[c][c] < 0
        for r in range(c + 1, n):
            f = A[r][c] / A[c][c]
            if f != 0:
                A[r] = [x - f * y for x, y in zip(A[r], A[c])]
    return neg


def is_positive_definite(S: Matrix) -> bool:
    """True exactly when the symmetric ``S`` is positive definite (every pivot positive)."""
    return negative_eigenvalues(S) == 0
