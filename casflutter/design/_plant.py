"""Plants in partitioned form, the static-gain augmentation, and the exact checks.

A generalised plant ``P`` (python-control's ``hinfsyn`` convention) has inputs
``[w, u]`` and outputs ``[z, y]``::

    xdot = A x + B1 w + B2 u
    z    = C1 x + D11 w + D12 u
    y    = C2 x + D21 w + D22 u

``D22`` may be non-zero (accelerometers that see the flap directly, eq. 14 with the
feed-through of :mod:`casflutter.aeroelastic`): the loop ``u = Kbar y`` is then closed
exactly through ``K~ = (I - Kbar D22)⁻¹ Kbar``.  A controller of order ``k``, ``xk' = Ak xk + Bk y``, ``u = Ck xk + Dk y``, is a *static*
gain ``Kbar = [[Dk, Ck], [Bk, Ak]]`` on the augmented plant whose extra input is
``xk'`` and whose extra output is ``xk``; this is how every controller order is handled
by the same code (paper §III.C, the loop of eq. 14 closed by ``K(s)``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import control
import numpy as np
import scipy.linalg as sla

from .._linalg import spectral_abscissa
from ..errors import ConfigError, DataError, DimensionError
from ._norm import hinf_norm

__all__ = ["Partition", "partition", "load_compleib", "exact_hinf_norm", "spectral_abscissa",
           "with_flap_rate"]


@dataclass(frozen=True)
class Partition:
    """The blocks of one generalised plant.

    Attributes
    ----------
    A, B1, B2, C1, C2, D11, D12, D21, D22 : ndarray
        State-space blocks as in the module docstring (``D22`` defaults to zero).
    """

    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C1: np.ndarray
    C2: np.ndarray
    D11: np.ndarray
    D12: np.ndarray
    D21: np.ndarray
    D22: np.ndarray | None = None

    def __post_init__(self):
        if self.D22 is None:
            object.__setattr__(self, "D22", np.zeros((self.C2.shape[0], self.B2.shape[1])))

    @property
    def has_d22(self) -> bool:
        """True when the control reaches the measurement directly (``D22 != 0``)."""
        return bool(np.any(self.D22 != 0.0))

    @property
    def nx(self) -> int:
        """Number of plant states."""
        return self.A.shape[0]

    @property
    def dims(self) -> tuple[int, int, int, int]:
        """``(nw, nz, nu, ny)``."""
        return self.B1.shape[1], self.C1.shape[0], self.B2.shape[1], self.C2.shape[0]

    def augmented(self, order: int) -> "Partition":
        """The plant augmented with ``order`` controller states (static-gain form).

        The gain acts as ``[u; xk'] = Kbar [y; xk]`` with ``Kbar = [[Dk, Ck], [Bk, Ak]]``.
        """
        k = int(order)
        nx = self.nx
        nw, nz, nu, ny = self.dims
        A = sla.block_diag(self.A, np.zeros((k, k)))
        B1 = np.vstack([self.B1, np.zeros((k, nw))])
        B2 = np.zeros((nx + k, nu + k))
        B2[:nx, :nu] = self.B2
        B2[nx:, nu:] = np.eye(k)
        C1 = np.hstack([self.C1, np.zeros((nz, k))])
        C2 = np.zeros((ny + k, nx + k))
        C2[:ny, :nx] = self.C2
        C2[ny:, nx:] = np.eye(k)
        D12 = np.hstack([self.D12, np.zeros((nz, k))])
        D21 = np.vstack([self.D21, np.zeros((k, nw))])
        D22 = np.zeros((ny + k, nu + k))
        D22[:ny, :nu] = self.D22
        return Partition(A, B1, B2, C1, C2, self.D11, D12, D21, D22)

    def loop_gain(self, Kbar: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K~, L, R)``: the gain seen by the loop, ``K~ = L Kbar = Kbar R`` with
        ``L = (I - Kbar D22)⁻¹`` and ``R = (I - D22 Kbar)⁻¹`` (``dK~ = L dKbar R``)."""
        m, p = Kbar.shape
        if not self.has_d22:
            return Kbar, np.eye(m), np.eye(p)
        L = np.linalg.inv(np.eye(m) - Kbar @ self.D22)
        R = np.linalg.inv(np.eye(p) - self.D22 @ Kbar)
        return L @ Kbar, L, R

    def well_posedness(self, Kbar: np.ndarray) -> float:
        """``det(I - Kbar D22)`` (1 without a feed-through; the loop is ill posed at 0)."""
        if not self.has_d22:
            return 1.0
        return float(np.linalg.det(np.eye(Kbar.shape[0]) - Kbar @ self.D22))

    def closed_loop(self, Kbar: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Closed-loop ``(Acl, Bcl, Ccl, Dcl)`` of this (augmented) plant with the static ``Kbar``."""
        Kt = self.loop_gain(Kbar)[0]
        A = self.A + self.B2 @ Kt @ self.C2
        B = self.B1 + self.B2 @ Kt @ self.D21
        C = self.C1 + self.D12 @ Kt @ self.C2
        D = self.D11 + self.D12 @ Kt @ self.D21
        return A, B, C, D

    def statespace(self) -> control.StateSpace:
        """The plant as one ``StateSpace`` (the inverse of :func:`partition`).

        Returns
        -------
        control.StateSpace
            Inputs ``[w, u]``, outputs ``[z, y]``.
        """
        return control.ss(self.A, np.hstack([self.B1, self.B2]), np.vstack([self.C1, self.C2]),
                          np.block([[self.D11, self.D12], [self.D21, self.D22]]))

    def transformed(self, T: np.ndarray, su: np.ndarray, sy: np.ndarray,
                    w0: float = 1.0) -> "Partition":
        """State similarity ``x = T x~``, input/output scaling ``u = su u~``, ``y~ = y / sy``
        and time scaling ``t~ = w0 t`` (frequencies divided by ``w0``)."""
        Ti = np.linalg.inv(T)
        return Partition(Ti @ self.A @ T / w0, Ti @ self.B1 / w0, Ti @ self.B2 * su / w0,
                         self.C1 @ T, (self.C2 @ T) / sy[:, None], self.D11, self.D12 * su,
                         self.D21 / sy[:, None], self.D22 * su[None, :] / sy[:, None])


def controller_only(nmeas: int, ncon: int, nw: int = 1, nz: int = 1) -> Partition:
    """The plant with no states and no paths, with ``nmeas`` measurements, ``ncon``
    controls and ``nw``, ``nz`` zero disturbances and errors.

    Augmented with ``k`` controller states (:meth:`Partition.augmented`), the loop that
    ``Kbar`` closes on it has the state matrix ``Ak``: as a stability plant it asks the
    controller itself to decay.

    Parameters
    ----------
    nmeas, ncon : int
        Numbers of measurements and controls.
    nw, nz : int
        Numbers of (zero) disturbances and errors, to match other plants of a synthesis.

    Returns
    -------
    Partition
    """
    return Partition(A=np.zeros((0, 0)), B1=np.zeros((0, nw)), B2=np.zeros((0, ncon)),
                     C1=np.zeros((nz, 0)), C2=np.zeros((nmeas, 0)), D11=np.zeros((nz, nw)),
                     D12=np.zeros((nz, ncon)), D21=np.zeros((nmeas, nw)))


def partition(P: control.StateSpace, nmeas: int, ncon: int) -> Partition:
    """Split a partitioned ``StateSpace`` (inputs ``[w, u]``, outputs ``[z, y]``).

    Parameters
    ----------
    P : control.StateSpace
        Continuous-time generalised plant.
    nmeas, ncon : int
        Number of measurements ``y`` (last outputs) and controls ``u`` (last inputs).

    Returns
    -------
    Partition

    Raises
    ------
    DimensionError
        If the split leaves no ``w`` or ``z``, or if ``P`` is discrete-time.
    """
    if not isinstance(P, control.StateSpace):
        try:
            P = control.ss(P)
        except Exception as exc:  # pragma: no cover - defensive
            raise DimensionError(f"plant must be a control.StateSpace, got {type(P).__name__}") from exc
    if P.dt not in (0, None):
        raise DimensionError(f"plant must be continuous time (dt=0), got dt={P.dt}; "
                             "convert with control.d2c first")
    nmeas, ncon = int(nmeas), int(ncon)
    ny_tot, nu_tot = P.noutputs, P.ninputs
    if not (0 < nmeas < ny_tot and 0 < ncon < nu_tot):
        raise DimensionError(
            f"plant has {nu_tot} inputs and {ny_tot} outputs; ncon={ncon} and nmeas={nmeas} must "
            "leave at least one exogenous input w and one performance output z")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (P.A, P.B, P.C, P.D))
    nw, nz = nu_tot - ncon, ny_tot - nmeas
    return Partition(A=A, B1=B[:, :nw], B2=B[:, nw:], C1=C[:nz, :], C2=C[nz:, :],
                     D11=D[:nz, :nw], D12=D[:nz, nw:], D21=D[nz:, :nw], D22=D[nz:, nw:].copy())


def load_compleib(path: str | Path) -> tuple[control.StateSpace, int, int, dict[str, Any]]:
    """Read a COMPleib plant in the JSON format of ``problems/compleib/``.

    Parameters
    ----------
    path : str or Path
        File with ``A, B1, B, C1, C, D11, D12, D21`` (and optionally ``D22``) as nested lists.

    Returns
    -------
    P : control.StateSpace
        Partitioned plant with inputs ``[w, u]`` and outputs ``[z, y]``.
    nmeas, ncon : int
        Numbers of measurements and controls.
    meta : dict
        The non-matrix entries of the file (``name``, ``nx``, ``open_loop_stable``, ...) plus
        ``gamma_full_order_lmi`` and ``published_static`` when a ``reference.json`` beside the
        file lists the plant.

    Raises
    ------
    DataError
        If a matrix is missing, not finite, or of inconsistent size.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise DataError(f"cannot read COMPleib plant {path}: {exc}") from exc
    if not isinstance(data, dict):
        raise DataError(f"{path}: expected a JSON object with the plant matrices")
    try:
        A = np.atleast_2d(np.asarray(data["A"], dtype=float))
        B1 = np.atleast_2d(np.asarray(data["B1"], dtype=float))
        B2 = np.atleast_2d(np.asarray(data.get("B", data.get("B2")), dtype=float))
        C1 = np.atleast_2d(np.asarray(data["C1"], dtype=float))
        C2 = np.atleast_2d(np.asarray(data.get("C", data.get("C2")), dtype=float))
    except (KeyError, TypeError, ValueError) as exc:
        raise DataError(f"{path}: missing or malformed matrix ({exc}); need A, B1, B, C1, C") from exc
    nx, nw, nu, nz, ny = A.shape[0], B1.shape[1], B2.shape[1], C1.shape[0], C2.shape[0]

    def _get(key: str, shape: tuple[int, int]) -> np.ndarray:
        if key not in data:
            return np.zeros(shape)
        M = np.asarray(data[key], dtype=float).reshape(shape)
        return M

    try:
        D11, D12 = _get("D11", (nz, nw)), _get("D12", (nz, nu))
        D21, D22 = _get("D21", (ny, nw)), _get("D22", (ny, nu))
    except ValueError as exc:
        raise DataError(f"{path}: a D matrix has the wrong size ({exc})") from exc
    mats = dict(A=A, B1=B1, B=B2, C1=C1, C=C2, D11=D11, D12=D12, D21=D21, D22=D22)
    for key, M in mats.items():
        if not np.all(np.isfinite(M)):
            raise DataError(f"{path}: matrix {key} has non-finite entries")
    if A.shape != (nx, nx) or B1.shape[0] != nx or B2.shape[0] != nx or C1.shape[1] != nx \
            or C2.shape[1] != nx:
        raise DataError(f"{path}: matrix sizes do not fit together (A is {A.shape})")
    P = control.ss(A, np.hstack([B1, B2]), np.vstack([C1, C2]),
                   np.block([[D11, D12], [D21, D22]]))
    meta = {k: v for k, v in data.items() if not isinstance(v, list)}
    meta.setdefault("name", path.stem)
    ref_file = path.parent / "reference.json"
    if ref_file.exists():
        try:
            refs = json.loads(ref_file.read_text())
            for rec in refs:
                if rec.get("plant") == meta["name"]:
                    meta.update({k: v for k, v in rec.items() if k != "plant"})
        except (OSError, json.JSONDecodeError, AttributeError):
            pass
    return P, ny, nu, meta


def exact_hinf_norm(sys: control.StateSpace) -> tuple[float, float]:
    """Exact H∞ norm and peak frequency (rad/s) of a *stable* system.

    The synthesis' own Hamiltonian level iteration (:func:`._norm.hinf_norm`, relative
    accuracy 1e-9), never a gridded value and no code shared with the verification layer.
    """
    return hinf_norm(*(np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D)))


def sigma_max_grid(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                   omega: Sequence[float]) -> np.ndarray:
    """Largest singular value of ``C (jωI - A)^-1 B + D`` on a grid (numpy, for grid selection)."""
    n = A.shape[0]
    omega = np.asarray(omega, dtype=float)
    M = 1j * omega[:, None, None] * np.eye(n)[None] - A[None]
    X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (len(omega),) + B.shape))
    H = C[None] @ X + D[None]
    return np.linalg.svd(H, compute_uv=False)[:, 0]


def with_flap_rate(P: control.StateSpace, nmeas: int, weight: float,
                   bandwidth: float) -> control.StateSpace:
    """``P`` with one more performance output, the weighted flap rate ``z_r = w v̇``.

    The rate is taken through a first-order filter, ``ẋ_r = a (v − x_r)``,
    ``z_r = w a (v − x_r)`` (``v̇`` below the bandwidth ``a``), inserted after the existing
    performance outputs; the measurements stay the last ``nmeas`` outputs and the flap
    ``v`` the last input, as :func:`synthesize` expects.

    Parameters
    ----------
    P : control.StateSpace
        Partitioned plant (inputs ``[w, v]``, outputs ``[z, zm]``), e.g. the LFT's ``P``
        (eq. 14).
    nmeas : int
        Number of measurements (the last outputs).
    weight : float
        ``w`` [1 / (rad per time unit)]: how much one unit of flap rate counts against the
        plant's performance outputs (> 0).
    bandwidth : float
        ``a`` [rad per time unit] (> 0), e.g. the flap servo's bandwidth.

    Returns
    -------
    control.StateSpace
        One state and one output more than ``P``.
    """
    if not (weight > 0 and bandwidth > 0):
        raise ConfigError(f"flap-rate weight {weight!r} and bandwidth {bandwidth!r} must be > 0")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (P.A, P.B, P.C, P.D))
    n, m, nz = A.shape[0], B.shape[1], C.shape[0] - nmeas
    ev = np.zeros((1, m))
    ev[0, -1] = 1.0                                       # the flap command v
    a, w = float(bandwidth), float(weight)
    Aa = np.block([[A, np.zeros((n, 1))], [np.zeros((1, n)), np.full((1, 1), -a)]])
    Ba = np.vstack([B, a * ev])
    Ca = np.vstack([np.hstack([C[:nz], np.zeros((nz, 1))]),
                    np.hstack([np.zeros((1, n)), np.full((1, 1), -w * a)]),
                    np.hstack([C[nz:], np.zeros((nmeas, 1))])])
    Da = np.vstack([D[:nz], w * a * ev, D[nz:]])
    return control.ss(Aa, Ba, Ca, Da)
