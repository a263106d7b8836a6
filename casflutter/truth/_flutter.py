"""A small, private flutter/divergence finder for the truth models (tests and listings).

The general branch tracker lives in :mod:`casflutter.aeroelastic`; this one only bisects
on the spectral abscissa of ``state_matrix(V)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["FlutterPoint", "find_flutter", "find_divergence"]


@dataclass(frozen=True)
class FlutterPoint:
    """First instability of a truth model on a speed range.

    Attributes
    ----------
    V : float
        Speed index at which the spectral abscissa crosses zero (``nan`` if none).
    omega : float
        ``|Im|`` of the critical eigenvalue there [rad per time unit]
        (0 for a divergence).
    found : bool
        Whether a crossing was bracketed on the range.
    """

    V: float
    omega: float
    found: bool


def _abscissa(model, V: float) -> float:
    return float(np.max(np.linalg.eigvals(model.state_matrix(V)).real))


def find_flutter(model, V_min: float, V_max: float, num: int = 60,
                 xtol: float = 1e-10) -> FlutterPoint:
    """First zero crossing of the spectral abscissa of ``model.state_matrix(V)``.

    Parameters
    ----------
    model : AeroelasticTruth
    V_min, V_max : float
        Speed-index range (the system must be stable at ``V_min``).
    num : int
        Grid points for bracketing before the Brent refinement.
    xtol : float
        Absolute tolerance on ``V``.

    Returns
    -------
    FlutterPoint
    """
    grid = np.linspace(V_min, V_max, num)
    vals = [_abscissa(model, V) for V in grid]
    for k in range(1, num):
        if vals[k - 1] < 0 <= vals[k]:
            Vf = brentq(lambda V: _abscissa(model, V), grid[k - 1], grid[k], xtol=xtol)
            lam = np.linalg.eigvals(model.state_matrix(Vf))
            crit = lam[np.argmax(lam.real)]
            return FlutterPoint(V=float(Vf), omega=float(abs(crit.imag)), found=True)
    return FlutterPoint(V=float("nan"), omega=float("nan"), found=False)


def find_divergence(model, V_lo: float, V_hi: float) -> float:
    """Speed index in ``[V_lo, V_hi]`` where ``det(state_matrix(V))`` changes sign.

    A real eigenvalue through zero is static divergence.
    """
    def det(V):
        return float(np.linalg.slogdet(model.state_matrix(V))[0])

    def f(V):
        sign, logabs = np.linalg.slogdet(model.state_matrix(V))
        return float(sign * np.exp(min(logabs, 50.0)))

    if det(V_lo) == det(V_hi):
        raise ValueError(f"no sign change of det(A(V)) on [{V_lo}, {V_hi}]")
    return float(brentq(f, V_lo, V_hi, xtol=1e-12))
