"""Dense eigenvalue sweep of the closed loop over the speed index (the brute-force
check of the exact interval, and the data of a pole-loci plot like Fig. 10 of
Lum et al. 2016)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ._common import SystemLike, as_statespace
from ._lft import lft_closed_loop
from ._report import delta_family

__all__ = ["SpeedSweep", "speed_sweep"]


@dataclass(frozen=True)
class SpeedSweep:
    """Closed-loop poles along a grid of speed indices.

    Attributes
    ----------
    V : numpy.ndarray
        Speed indices, shape ``(nV,)``.
    dV : numpy.ndarray
        ``V² - Vf²`` (eq. 10).
    poles : numpy.ndarray
        Shape ``(nV, n)``, each row sorted by decreasing real part; ``nan`` where the
        loop is not well posed.
    spectral_abscissa : numpy.ndarray
        Largest real part per V (``inf`` where not well posed).
    """

    __repr__ = result_repr

    V: np.ndarray
    dV: np.ndarray
    poles: np.ndarray
    spectral_abscissa: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        """Boolean mask of the grid points where the closed loop is stable."""
        return self.spectral_abscissa < 0


def speed_sweep(P: SystemLike, K: SystemLike, nmeas: int, ncon: int, *, Vf: float,
                n_delta: int, V) -> SpeedSweep:
    """Closed-loop poles of ``F_l(P, K)`` with ``wf = -ΔV zf``, ``ΔV = V² - Vf²``
    (eq. 10, 15), for every ``V`` of a grid.

    Parameters
    ----------
    P, K, nmeas, ncon
        As in :func:`verify_controller`.
    Vf : float
        Nominal speed index of the LFT.
    n_delta : int
        Size of the ΔV channel.
    V : array_like
        Speed indices (``>= 0``).

    Returns
    -------
    SpeedSweep

    See Also
    --------
    verify_controller : the exact stable interval this grid illustrates.

    Examples
    --------
    >>> import control
    >>> import casflutter as cf
    >>> P = control.ss([[1.0]], [[1.0, 1.0]], [[1.0], [1.0]], [[0.0, 0.0], [0.0, 0.0]])
    >>> import numpy as np
    >>> K = control.ss([], [], [], [[-3.0]])
    >>> sw = cf.speed_sweep(P, K, 1, 1, Vf=1.0, n_delta=1, V=np.linspace(0.5, 1.5, 5))
    >>> np.round(sw.spectral_abscissa, 3)
    array([-1.25 , -1.562, -2.   , -2.562, -3.25 ])
    """
    V = np.atleast_1d(np.asarray(V, dtype=float))
    if V.ndim != 1 or np.any(V < 0) or not np.all(np.isfinite(V)):
        raise ConfigError("V must be a 1-D grid of finite speed indices >= 0")
    cl = lft_closed_loop(as_statespace(P, "plant P"), K, nmeas, ncon)
    A, Bf, Cf, Dff = delta_family(cl, n_delta)
    dV = V**2 - Vf**2
    n, k = A.shape[0], Bf.shape[1]
    poles = np.full((V.size, n), np.nan + 0j)
    alpha = np.full(V.size, np.inf)
    for i, d in enumerate(dV):
        M = np.eye(k) + d * Dff
        if np.linalg.cond(M) > 1e12:
            continue
        ev = np.linalg.eigvals(A - Bf @ np.linalg.solve(M, d * Cf))
        poles[i] = ev[np.argsort(-ev.real, kind="stable")]
        alpha[i] = ev.real.max() if n else -np.inf
    return SpeedSweep(V, dV, poles, alpha)
