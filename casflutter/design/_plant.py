"""Plants in partitioned form, the static-gain augmentation, and the exact checks.

A generalised plant ``P`` (python-control's ``hinfsyn`` convention) has inputs
``[w, u]`` and outputs ``[z, y]``::

    xdot = A x + B1 w + B2 u
    z    = C1 x + D11 w + D12 u
    y    = C2 x + D21 w + D22 u

A controller of order ``k``, ``xk' = Ak xk + Bk y``, ``u = Ck xk + Dk y``, is a *static*
gain ``Kbar = [[Dk, Ck], [Bk, Ak]]`` on the augmented plant whose extra input is
``xk'`` and whose extra output is ``xk``; this is how every controller order is handled
by the same code (paper §III.C, the loop of eq. 14 closed by ``K(s)``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import control
import numpy as np
import scipy.linalg as sla

from ..errors import DataError, DimensionError

__all__ = ["Partition", "partition", "load_compleib", "exact_hinf_norm", "spectral_abscissa"]


@dataclass(frozen=True)
class Partition:
    """The blocks of one generalised plant (``D22`` must be zero).

    Attributes
    ----------
    A, B1, B2, C1, C2, D11, D12, D21 : ndarray
        State-space blocks as in the module docstring.
    """

    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C1: np.ndarray
    C2: np.ndarray
    D11: np.ndarray
    D12: np.ndarray
    D21: np.ndarray

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
        return Partition(A, B1, B2, C1, C2, self.D11, D12, D21)

    def closed_loop(self, Kbar: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Closed-loop ``(Acl, Bcl, Ccl, Dcl)`` of this (augmented) plant with the static ``Kbar``."""
        A = self.A + self.B2 @ Kbar @ self.C2
        B = self.B1 + self.B2 @ Kbar @ self.D21
        C = self.C1 + self.D12 @ Kbar @ self.C2
        D = self.D11 + self.D12 @ Kbar @ self.D21
        return A, B, C, D

    def transformed(self, T: np.ndarray, su: np.ndarray, sy: np.ndarray) -> "Partition":
        """State similarity ``x = T x~`` and input/output scaling ``u = su u~``, ``y~ = y / sy``."""
        Ti = np.linalg.inv(T)
        return Partition(Ti @ self.A @ T, Ti @ self.B1, Ti @ self.B2 * su, self.C1 @ T,
                         (self.C2 @ T) / sy[:, None], self.D11, self.D12 * su,
                         self.D21 / sy[:, None])


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
        If the split leaves no ``w`` or ``z``, if ``P`` is discrete-time, or if ``D22 != 0``.
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
    D22 = D[nz:, nw:]
    if np.any(D22 != 0.0):
        raise DimensionError("D22 (from u to y) must be zero; absorb a feedthrough into the "
                             "measurement (y - D22 u) before synthesis")
    return Partition(A=A, B1=B[:, :nw], B2=B[:, nw:], C1=C[:nz, :], C2=C[nz:, :],
                     D11=D[:nz, :nw], D12=D[:nz, nw:], D21=D[nz:, :nw])


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


def spectral_abscissa(A: np.ndarray) -> float:
    """Largest real part of the eigenvalues of ``A`` (``-inf`` for an empty matrix)."""
    if A.size == 0:
        return -np.inf
    return float(np.max(np.linalg.eigvals(A).real))


def _linfnorm(sys: control.StateSpace) -> tuple[float, float]:
    gamma, omega = control.linfnorm(sys)
    return float(gamma), float(omega)


def exact_hinf_norm(sys: control.StateSpace) -> tuple[float, float]:
    """Exact H∞ norm and peak frequency (rad/s) of a *stable* system.

    Uses ``casflutter.verify.hinf_norm`` (Hamiltonian bisection, shares no code with the
    optimiser) when that layer provides it, otherwise python-control's ``linfnorm``
    (SLICOT ``ab13dd``).  Never a gridded value.
    """
    fn = _verify_norm()
    if fn is not None:
        res = fn(sys)
        return float(res.gamma), float(res.omega_peak)
    return _linfnorm(sys)


def _verify_norm() -> Callable | None:
    try:  # the verification layer is written in parallel; use it once it exists
        from ..verify import hinf_norm  # noqa: PLC0415
    except ImportError:
        return None
    return hinf_norm


def sigma_max_grid(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                   omega: Sequence[float]) -> np.ndarray:
    """Largest singular value of ``C (jωI - A)^-1 B + D`` on a grid (numpy, for grid selection)."""
    n = A.shape[0]
    omega = np.asarray(omega, dtype=float)
    M = 1j * omega[:, None, None] * np.eye(n)[None] - A[None]
    X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (len(omega),) + B.shape))
    H = C[None] @ X + D[None]
    return np.linalg.svd(H, compute_uv=False)[:, 0]
