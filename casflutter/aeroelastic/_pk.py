"""The p-k flutter solution on a table of generalised aerodynamic forces ``Q(ik)``.

The method NASTRAN users know (SOL145 ``PK``).  With the modal equations of eq. (6),
``u'' + 2 zeta omega u' + omega^2 u = alpha V^2 Q(ik) u`` (``V = U / U_ref``, flap held at
zero), write ``Q(ik) = Q_R + i Q_I`` and treat the imaginary part as aerodynamic damping,
``i Q_I u = (Q_I / k)(b / U) u'``.  At an airspeed ``U`` and a trial reduced frequency
``k`` the eigenvalues ``s`` of the real quadratic problem

    s^2 u + s (2 zeta omega - q (b / U) Q_I(k) / k) u + (omega^2 - q Q_R(k)) u = 0,
    q = alpha (U / U_ref)^2,

are computed and the root of the tracked mode (upper half plane, nearest the previous
estimate) gives the next ``k = Im(s) b / U``; the fixed-point iteration on ``k`` stops when
``k`` no longer changes.  ``Q`` between the tabulated ``k`` is a cubic spline
(:meth:`casflutter.data.GAFTable.interpolate`); ``Q_I / k`` at ``k -> 0`` is ``dQ_I/dk``.
Each mode is followed from its in-vacuo frequency through the speeds, starting every
iteration from the root at the previous speed.

At a flutter point (``Re s = 0``) the equation is the exact flutter determinant
``det(-omega^2 + i omega 2 zeta omega + omega^2 - q Q(ik)) = 0``; away from it the damping
``g = 2 Re(s) / Im(s)`` is the p-k approximation.  The flutter speed is the lowest airspeed at
which the damping of a tracked mode changes sign from negative to positive, refined by
Brent's method on ``U -> Re s(U)``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from .._format import result_repr
from ..data import GAFTable
from ..errors import ConfigError, ConvergenceError, DataError, DimensionError
from ..structure import ModalStructure

__all__ = ["PKResult", "pk_flutter"]

log = logging.getLogger("casflutter.aeroelastic.pk")


@dataclass(frozen=True)
class PKResult:
    """V-g / V-f branches and the flutter point of a p-k solution.

    Attributes
    ----------
    U : numpy.ndarray
        ``(nU,)`` airspeeds [m/s].
    modes : tuple of int
        Tracked modes (0-based indices into the structure).
    mode_names : tuple of str
        Their names.
    eigenvalues : numpy.ndarray
        ``(nU, nm)`` converged roots ``s`` [rad/s] (upper half plane).
    k : numpy.ndarray
        ``(nU, nm)`` reduced frequencies ``Im(s) b / U``.
    iterations : numpy.ndarray
        ``(nU, nm)`` p-k iterations used.
    found : bool
        True when a mode's damping crosses zero upwards inside the speed range.
    flutter_speed : float or None
        Airspeed [m/s] of the first crossing.
    flutter_omega : float or None
        Frequency [rad/s] there.
    flutter_k : float or None
        Reduced frequency there.
    flutter_mode : int or None
        The mode (0-based index into the structure) that goes unstable.
    message : str
        Summary.
    """

    __repr__ = result_repr

    U: np.ndarray
    modes: tuple[int, ...]
    mode_names: tuple[str, ...]
    eigenvalues: np.ndarray
    k: np.ndarray
    iterations: np.ndarray
    found: bool
    flutter_speed: float | None
    flutter_omega: float | None
    flutter_k: float | None
    flutter_mode: int | None
    message: str

    @property
    def omega(self) -> np.ndarray:
        """``(nU, nm)`` frequencies ``Im(s)`` [rad/s] (the V-f diagram)."""
        return self.eigenvalues.imag

    @property
    def g(self) -> np.ndarray:
        """``(nU, nm)`` damping ``g = 2 Re(s) / Im(s)`` (NASTRAN's, the V-g diagram; positive
        is unstable)."""
        om = self.eigenvalues.imag
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(om > 0, 2.0 * self.eigenvalues.real / om, np.nan)

    @property
    def damping_ratio(self) -> np.ndarray:
        """``(nU, nm)`` ``-Re(s) / |s|``."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


class _PK:
    """The p-k iteration at one speed for one mode."""

    def __init__(self, table: GAFTable, structure: ModalStructure, U_ref: float,
                 tol: float, max_iter: int):
        self.t, self.s = table, structure
        self.speed = replace(structure.speed, U_ref=U_ref)   # V = U / U_ref
        self.N = structure.n_modes
        self.tol, self.max_iter = tol, max_iter
        self.dk0 = 1e-9 * max(float(table.k[-1]), 1.0)

    def _QR_QIk(self, k: float, mode: int, U: float):
        N = self.N
        try:
            Q = self.t.interpolate(k)[:, :N]
            if k <= self.dk0:
                QIk = self.t.interpolate(k, derivative=1)[:, :N].imag
            else:
                QIk = Q.imag / k
        except DataError:
            raise DataError(
                f"p-k: mode {mode + 1} ({self.t.mode_names[mode]!r}) at U = {U:g} m/s needs "
                f"k = {k:.4g}, outside the table's k = [{self.t.k[0]:g}, {self.t.k[-1]:g}]; "
                "extend the table or track fewer modes (modes=...)") from None
        return Q.real, QIk

    def roots(self, U: float, k: float, mode: int) -> np.ndarray:
        """All roots ``s`` of the real quadratic problem at ``(U, k)``."""
        s, N = self.s, self.N
        q = s.alpha * self.speed.speed_index(U) ** 2
        QR, QIk = self._QR_QIk(k, mode, U)
        K = np.diag(s.omega ** 2) - q * QR
        C = np.diag(2.0 * s.zeta * s.omega) - q * (self.t.b / U) * QIk
        A = np.block([[np.zeros((N, N)), np.eye(N)], [-K, -C]])
        return np.linalg.eigvals(A)

    def solve(self, U: float, s0: complex, mode: int) -> tuple[complex, int]:
        """Converged root of ``mode`` at ``U`` starting from ``s0``."""
        b = self.t.b
        s_cur = complex(s0)
        k = max(s_cur.imag, 0.0) * b / U
        for it in range(1, self.max_iter + 1):
            lam = self.roots(U, k, mode)
            lam = lam[lam.imag >= -1e-12 * np.abs(lam)]
            s_new = complex(lam[np.argmin(np.abs(lam - s_cur))])
            k_new = max(s_new.imag, 0.0) * b / U
            s_cur = s_new
            if abs(k_new - k) <= self.tol * max(k_new, 1e-3):
                return s_cur, it
            k = k_new
        raise ConvergenceError(
            f"p-k did not converge for mode {mode + 1} ({self.t.mode_names[mode]!r}) at "
            f"U = {U:g} m/s after {self.max_iter} iterations (last k = {k:.6g}); use finer "
            "speed steps or raise max_iter")


def pk_flutter(table: GAFTable, structure: ModalStructure, speeds, *, U_ref: float | None = None,
               modes=None, tol: float = 1e-10, max_iter: int = 200,
               xtol_rel: float = 1e-10) -> PKResult:
    """p-k flutter solution on a ``Q(ik)`` table (module docstring).

    Parameters
    ----------
    table : GAFTable
        ``Q(ik)`` in the eq. (6) normalisation (the flap column, if any, is not used).
    structure : ModalStructure
        ω, ζ, α of the same modes.
    speeds : array_like
        Increasing airspeeds [m/s]; the tracking starts at the first one from the in-vacuo
        frequencies, so start low and step finely enough for the roots to be followed.
    U_ref : float, optional
        Airspeed per unit speed index [m/s]; default ``table.U_ref``.
    modes : sequence of int, optional
        Modes to track (0-based); default all.  The converged ``k`` of every tracked mode must
        lie inside the table.
    tol : float
        Relative tolerance of the p-k iteration on ``k``.
    max_iter : int
        Iterations per speed and mode.
    xtol_rel : float
        Relative tolerance of the flutter speed (Brent).

    Returns
    -------
    PKResult

    Raises
    ------
    DimensionError
        The table and the structure have different numbers of modes.
    ConfigError
        Bad speeds, modes or ``U_ref``.
    DataError
        A tracked mode needs a ``k`` outside the table.
    ConvergenceError
        The p-k iteration did not converge.
    """
    if not isinstance(table, GAFTable):
        raise ConfigError(f"table must be a casflutter.data.GAFTable, got {type(table).__name__}")
    if table.n_modes != structure.n_modes:
        raise DimensionError(f"the table has {table.n_modes} modes but the structure has "
                             f"{structure.n_modes}; use the same modes for Q(ik) and the modal "
                             "data")
    U_ref = table.U_ref if U_ref is None else float(U_ref)
    if U_ref is None or not np.isfinite(U_ref) or U_ref <= 0:
        raise ConfigError("U_ref (airspeed per unit speed index) is needed: give U_ref= or a "
                          "table with U_ref")
    U = np.asarray(speeds, dtype=float).ravel()
    if U.size < 2 or not np.all(np.isfinite(U)) or np.any(U <= 0) or np.any(np.diff(U) <= 0):
        raise ConfigError("speeds must be at least two increasing positive airspeeds [m/s]")
    N = structure.n_modes
    modes = tuple(range(N)) if modes is None else tuple(int(m) for m in modes)
    if not modes or any(not 0 <= m < N for m in modes) or len(set(modes)) != len(modes):
        raise ConfigError(f"modes={modes!r} must be distinct indices in 0..{N - 1}")
    pk = _PK(table, structure, U_ref, float(tol), int(max_iter))
    nm = len(modes)
    lam = np.zeros((U.size, nm), dtype=complex)
    its = np.zeros((U.size, nm), dtype=int)
    for j, m in enumerate(modes):
        s0 = 1j * structure.omega[m]
        for n, Un in enumerate(U):
            s0, its[n, j] = pk.solve(Un, s0, m)
            lam[n, j] = s0
    kk = np.maximum(lam.imag, 0.0) * table.b / U[:, None]

    best = None
    for j, m in enumerate(modes):
        re = lam[:, j].real
        up = np.flatnonzero((re[:-1] < 0) & (re[1:] >= 0))
        if up.size == 0:
            continue
        n = int(up[0])
        s_left = lam[n, j]

        def re_at(Uc, s_left=s_left, m=m):
            return pk.solve(Uc, s_left, m)[0].real

        Uf = U[n + 1] if re[n + 1] == 0 else brentq(
            re_at, U[n], U[n + 1], xtol=xtol_rel * U[n + 1], rtol=max(xtol_rel, 4e-16))
        sf = pk.solve(Uf, s_left, m)[0]
        if best is None or Uf < best[0]:
            best = (float(Uf), sf, m)
    names = tuple(table.mode_names[m] for m in modes)
    if best is None:
        msg = (f"no tracked mode's damping crosses zero for U in [{U[0]:g}, {U[-1]:g}] m/s; "
               "extend the speeds")
        return PKResult(U, modes, names, lam, kk, its, False, None, None, None, None, msg)
    Uf, sf, m = best
    kf = sf.imag * table.b / Uf
    msg = (f"p-k flutter at U = {Uf:.6g} m/s, {sf.imag:.6g} rad/s (k = {kf:.4g}), mode "
           f"{m + 1} ({table.mode_names[m]!r})")
    log.debug(msg)
    return PKResult(U, modes, names, lam, kk, its, True, Uf, float(sf.imag), float(kf), m, msg)
