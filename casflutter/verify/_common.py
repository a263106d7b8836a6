"""Small helpers shared by the verification modules (and only by them).

Nothing here is imported from, or shared with, :mod:`casflutter.design`: the
verification layer re-checks the synthesis with independent code.
"""

from __future__ import annotations

from typing import Union

import control
import numpy as np

from ..errors import CasflutterError, ConfigError

__all__ = ["IllPosedError", "NotHurwitzError", "as_statespace", "ssdata", "check_continuous",
           "spectral_abscissa", "is_hurwitz", "rounding_margin"]

#: Anything accepted where a system is expected: a python-control ``StateSpace``
#: (or ``TransferFunction``) or a plain static gain matrix (``StateSpace`` with 0 states).
SystemLike = Union[control.StateSpace, control.TransferFunction, np.ndarray, list, float]


class IllPosedError(CasflutterError, ValueError):
    """An interconnection that is not well posed (``I - D22 Dk`` singular) or a
    parameter family that is not of the supported (affine) form."""


class NotHurwitzError(CasflutterError, ValueError):
    """The nominal matrix of a family is not Hurwitz, so no stability interval
    around it exists."""


def as_statespace(sys: SystemLike, name: str = "system") -> control.StateSpace:
    """Return ``sys`` as a continuous-time :class:`control.StateSpace`.

    Parameters
    ----------
    sys : StateSpace, TransferFunction or array_like
        A system; a 2-D array (or scalar) is a static gain with 0 states.
    name : str
        Used in error messages.

    Raises
    ------
    ConfigError
        For discrete-time systems (only continuous time is supported).
    """
    if isinstance(sys, control.TransferFunction):
        sys = control.ss(sys)
    if not isinstance(sys, control.StateSpace):
        D = np.atleast_2d(np.asarray(sys, dtype=float))
        if D.ndim != 2:
            raise ConfigError(f"{name}: a static gain must be a 2-D matrix, got shape {D.shape}")
        sys = control.ss(np.zeros((0, 0)), np.zeros((0, D.shape[1])),
                         np.zeros((D.shape[0], 0)), D)
    check_continuous(sys, name)
    return sys


def check_continuous(sys: control.StateSpace, name: str = "system") -> None:
    """Reject discrete-time systems (``dt`` other than 0 or None).

    Raises
    ------
    ConfigError
        If ``sys.dt`` is a positive sampling time or ``True``.
    """
    dt = sys.dt
    if dt is None or (dt is not True and dt == 0):
        return
    raise ConfigError(
        f"{name} is discrete time (dt={dt}); casflutter.verify handles continuous-time "
        "systems only: convert with control.d2c-like tools or pass the continuous model")


def ssdata(sys: control.StateSpace) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` as float arrays with consistent 2-D shapes (also for 0 states)."""
    n, m, p = sys.nstates, sys.ninputs, sys.noutputs
    A = np.asarray(sys.A, dtype=float).reshape(n, n)
    B = np.asarray(sys.B, dtype=float).reshape(n, m)
    C = np.asarray(sys.C, dtype=float).reshape(p, n)
    D = np.asarray(sys.D, dtype=float).reshape(p, m)
    return A, B, C, D


def spectral_abscissa(A: np.ndarray) -> float:
    """Largest real part of the eigenvalues of ``A`` (``-inf`` for an empty matrix)."""
    if A.shape[0] == 0:
        return -np.inf
    return float(np.max(np.linalg.eigvals(A).real))


def is_hurwitz(A: np.ndarray) -> tuple[bool, float]:
    """``(stable, alpha)``: ``alpha`` is the spectral abscissa of ``A``; ``stable`` is
    ``alpha < -100 eps max(1, ||A||_F)``, so that a pole at the origin computed as a
    round-off-sized negative number does not count as stable."""
    alpha = spectral_abscissa(A)
    return bool(alpha < -rounding_margin(A)), alpha


def rounding_margin(A: np.ndarray) -> float:
    """``100 eps max(1, ||A||_F)``: how far left of the imaginary axis a pole of ``A`` must
    lie to count as stable (:func:`is_hurwitz`)."""
    return 100 * np.finfo(float).eps * max(1.0, float(np.linalg.norm(A))) if A.size else 0.0
