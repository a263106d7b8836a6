"""Design plants of a plant family, and the closed loops' decay over a set of speeds.

Helpers of :mod:`._multispeed` (the multi-speed fixed-order synthesis).  A
:class:`~casflutter.aeroelastic.PlantFamily` gives the plant at a speed with named inputs and
outputs; the design needs it in the partitioned form of :mod:`._plant` (inputs ``[w, u]``,
outputs ``[z, y]``) with the controller closed as ``u = +K y``:

* ``u`` the family's controls, ``y`` its measurements, the sign of ``u`` flipped for a family
  whose controllers act as ``u = −K y`` (so the controller designed here is the family's own);
* ``w`` the family's disturbance inputs, or, when it has none, disturbances added to the
  controls at the plant's input;
* ``z`` the measurements (the disturbance-to-sensor channels), and optionally the weighted
  rate of every control through a first-order filter (``z_r = w a (u − x_r)``,
  ``ẋ_r = a (u − x_r)``): the flap rate a servo can give is limited;
* or the loop's sensitivities: with ``DesignChannels(sensitivity="output")`` ``w`` is added
  to the measurements and ``z`` is the measurements, so ``w → z`` is the output sensitivity
  ``(I − G K)⁻¹``; with ``"input"`` ``w`` is added to the controls at the plant's input and
  ``z`` is that input, so ``w → z`` is the input sensitivity ``(I − K G)⁻¹``.  The ``i``-th
  diagonal entry of either is the sensitivity of loop ``i`` broken with the others closed,
  so ``‖·‖∞ ≤ M`` gives every such loop a disk margin of at least ``1/M``: the per-loop
  margins that :func:`casflutter.verify.verify_family` reports at both sides.

:class:`SpeedLoops` holds a set of such plants, scaled once for the whole design (balanced
states, inputs and outputs of order one, time scaled by the plants' geometric-mean pole
modulus, as :class:`._problem.Problem` does), and evaluates the closed loops of a controller
written as a static gain on the augmented plant, ``Kbar = [[Dk, Ck], [Bk, Ak]]``: the
spectral abscissa of every loop and the exact gradient of the rightmost eigenvalue,
``∂ Re λ / ∂ Kbar = Re(Lᵀ (B2ᵀ ȳ)(C2 x)ᵀ Rᵀ) / (yᴴ x)`` with the left and right eigenvectors
``y``, ``x`` and the well-posedness factors ``L``, ``R`` of a loop with feed-through.  Only
the eigenvalues are computed for every loop; the two eigenvectors of the one eigenvalue
the gradient needs come from inverse iteration (``_eigenvectors``), which costs a
fraction of the full left-and-right eigendecomposition.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
import scipy.linalg as sla

from .._format import result_repr
from ..errors import ConfigError, DimensionError
from ._plant import Partition
from ._problem import _balance, _io_scales, _time_scale

__all__ = ["DesignChannels", "design_partition", "unit_free_sensitivity", "SpeedLoops",
           "Scaling"]


@dataclass(frozen=True)
class DesignChannels:
    """What the design reads from a family's plant.

    Attributes
    ----------
    rate_weight : float
        ``w`` of the control-rate outputs (0: none).
    rate_bandwidth : float
        ``a`` [rad per time unit] of their filter (> 0).
    sensitivity : {"", "output", "input"}
        ``""``: the family's disturbances to the measurements; ``"output"`` / ``"input"``:
        the output / input sensitivity of the loop (module docstring).
    """

    __repr__ = result_repr

    rate_weight: float = 0.0
    rate_bandwidth: float = 1.0
    sensitivity: str = ""

    def __post_init__(self):
        if not (math.isfinite(self.rate_weight) and self.rate_weight >= 0
                and math.isfinite(self.rate_bandwidth) and self.rate_bandwidth > 0):
            raise ConfigError(f"rate weight {self.rate_weight!r} (>= 0) and bandwidth "
                              f"{self.rate_bandwidth!r} (> 0, rad per time unit)")
        if self.sensitivity not in ("", "output", "input"):
            raise ConfigError(f"sensitivity = {self.sensitivity!r}: allowed '' (the "
                              "disturbance channels), 'output', 'input'")


def design_partition(family, V: float, channels: DesignChannels = DesignChannels()
                     ) -> Partition:
    """The plant of ``family`` at ``V`` in the design's partitioned form (module docstring).

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The family.
    V : float
        Speed.
    channels : DesignChannels
        The control-rate outputs.

    Returns
    -------
    Partition
        ``u = +K y`` closes it (the family's sign convention folded into ``B2``, ``D12``,
        ``D22``).
    """
    P, sig = family.plant(V), family.signals
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (P.A, P.B, P.C, P.D))
    iu, iy = sig.input_index(), sig.output_index()
    iw = sig.input_index(sig.disturbances) if sig.disturbances else iu
    s = family.feedback_sign
    nx, nu = A.shape[0], len(iu)
    B2, C2, D22 = s * B[:, iu], C[iy], s * D[np.ix_(iy, iu)]
    B1, D21 = B[:, iw], D[np.ix_(iy, iw)]
    C1, D11, D12 = C2, D21, D22
    if channels.sensitivity == "output":        # y = G u + w, z = y
        B1, D21 = np.zeros((nx, len(iy))), np.eye(len(iy))
        C1, D11 = C2, D21
    elif channels.sensitivity == "input":       # u_p = s u + w, y = G u_p, z = u_p
        B1, D21 = B[:, iu], D[np.ix_(iy, iu)]
        C1, D11, D12 = np.zeros((nu, nx)), np.eye(nu), s * np.eye(nu)
    if channels.rate_weight > 0:
        a, w = channels.rate_bandwidth, channels.rate_weight
        nw = B1.shape[1]
        A = np.block([[A, np.zeros((nx, nu))], [np.zeros((nu, nx)), -a * np.eye(nu)]])
        B1 = np.vstack([B1, np.zeros((nu, nw))])
        B2 = np.vstack([B2, a * np.eye(nu)])
        C2 = np.hstack([C2, np.zeros((C2.shape[0], nu))])
        C1 = np.block([[C1, np.zeros((C1.shape[0], nu))],
                       [np.zeros((nu, nx)), -w * a * np.eye(nu)]])
        D11 = np.vstack([D11, np.zeros((nu, nw))])
        D12 = np.vstack([D12, w * a * np.eye(nu)])
    return Partition(A=A, B1=B1, B2=B2, C1=C1, C2=C2, D11=D11, D12=D12, D21=D21, D22=D22)


def unit_free_sensitivity(P: Partition, channels: DesignChannels, su: np.ndarray,
                          sy: np.ndarray, units: Sequence[str] = ()) -> Partition:
    """The sensitivity channels of ``P`` in the design's scaled signals where the signals
    are in different units, so that their norm does not depend on the units.

    A loop's sensitivity ``S`` is a matrix: written in other units of its signals it becomes
    ``D⁻¹ S D`` for a diagonal ``D``, whose norm differs (a gyro read in deg/s instead of
    rad/s weighs its couplings into the other loops 57 times more), while the loop-at-a-time
    margins, its diagonal, do not change.  Where every signal of the side is in one unit,
    a change of that unit is ``D = c I``, which cancels: ``S`` is left as it is.  Where they
    are in different units, ``w = D w~`` and ``z~ = D⁻¹ z`` with ``D`` the measurement scales
    ``sy`` (output sensitivity) or the control scales ``su`` (input sensitivity) of
    :func:`._problem._io_scales`, which balance the control-to-measurement gains to order
    one and follow any change of units: the norm is the same in every unit.  ``D`` is
    divided by its geometric mean, so that the control-rate outputs keep the weight they
    are given.

    Parameters
    ----------
    P : Partition
        A design plant of :func:`design_partition` with ``channels``.
    channels : DesignChannels
        Its channels; ``P`` is returned unchanged unless they are a sensitivity.
    su, sy : ndarray
        The design's control and measurement scales (:class:`Scaling`).
    units : sequence of str
        The units of that side's signals (the measurements' for ``"output"``, the
        controls' for ``"input"``; ``""`` where not declared).  All equal (all undeclared
        included): ``P`` is returned unchanged.

    Returns
    -------
    Partition
        ``P``, or ``P`` with ``B1``, ``D11``, ``D21`` scaled by ``D`` on the right and the
        sensitivity rows of ``C1``, ``D11``, ``D12`` by ``D⁻¹`` on the left.
    """
    if not channels.sensitivity or len(set(units)) < 2:
        return P
    d = np.asarray(sy if channels.sensitivity == "output" else su, dtype=float)
    if d.size != len(units):
        raise DimensionError(f"{len(units)} units for {d.size} signals")
    d = np.exp(np.log(d) - np.mean(np.log(d)))
    rows = np.ones(P.C1.shape[0])
    rows[:d.size] = 1.0 / d                         # the sensitivity's rows; the rates follow
    return Partition(A=P.A, B1=P.B1 * d[None, :], B2=P.B2, C1=P.C1 * rows[:, None], C2=P.C2,
                     D11=rows[:, None] * P.D11 * d[None, :], D12=P.D12 * rows[:, None],
                     D21=P.D21 * d[None, :], D22=P.D22)


@dataclass(frozen=True)
class Scaling:
    """Input, output and time scales of a design (:mod:`._problem`'s): ``u = su u~``,
    ``y~ = y / sy``, ``t~ = w0 t``."""

    __repr__ = result_repr

    su: np.ndarray
    sy: np.ndarray
    w0: float

    @classmethod
    def of(cls, parts: Sequence[Partition]) -> "Scaling":
        """The scales of a set of plants.

        Parameters
        ----------
        parts : sequence of Partition
            Plants with the same ``u`` and ``y``.

        Returns
        -------
        Scaling
        """
        su, sy = _io_scales(parts)
        return cls(su, sy, _time_scale(parts))

    def plant(self, P: Partition, order: int) -> Partition:
        """``P`` balanced, scaled and augmented with ``order`` controller states."""
        return P.transformed(_balance(P), self.su, self.sy, self.w0).augmented(order)

    def gain(self, Ak, Bk, Ck, Dk) -> np.ndarray:
        """The scaled static gain ``Kbar`` of an unscaled controller."""
        nu, ny, k = len(self.su), len(self.sy), np.shape(Ak)[0]
        K = np.zeros((nu + k, ny + k))
        K[:nu, :ny] = np.asarray(Dk) * self.sy[None, :] / self.su[:, None]
        K[:nu, ny:] = np.asarray(Ck) / self.su[:, None]
        K[nu:, :ny] = np.asarray(Bk) * self.sy[None, :] / self.w0
        K[nu:, ny:] = np.asarray(Ak) / self.w0
        return K

    def controller(self, K: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(Ak, Bk, Ck, Dk)``, unscaled, of the scaled static gain ``K``."""
        nu, ny = len(self.su), len(self.sy)
        Dk = self.su[:, None] * K[:nu, :ny] / self.sy[None, :]
        Ck = self.su[:, None] * K[:nu, ny:]
        Bk = self.w0 * K[nu:, :ny] / self.sy[None, :]
        return self.w0 * K[nu:, ny:], Bk, Ck, Dk


class SpeedLoops:
    """Closed loops of a controller of one order on a set of scaled, augmented plants.

    Parameters
    ----------
    parts : sequence of Partition
        Scaled plants augmented with the controller's states (:meth:`Scaling.plant`).
    free : ndarray of bool
        Which entries of ``Kbar`` are parameters (the others stay at ``base``).
    base : ndarray
        ``Kbar`` of the fixed entries.
    """

    def __init__(self, parts: Sequence[Partition], free: np.ndarray, base: np.ndarray):
        if not parts:
            raise DimensionError("the closed loops need at least one plant")
        self.parts, self.free, self.base = list(parts), free, base

    def gain(self, q: np.ndarray) -> np.ndarray:
        """``Kbar`` of the parameters ``q``."""
        K = self.base.copy()
        K[self.free] = q
        return K

    def params(self, K: np.ndarray) -> np.ndarray:
        """The parameters of ``Kbar``."""
        return K[self.free].copy()

    @staticmethod
    def _matrix(P: Partition, K: np.ndarray) -> np.ndarray:
        Kt = P.loop_gain(K)[0]
        return P.A + P.B2 @ Kt @ P.C2

    def abscissae(self, q: np.ndarray) -> np.ndarray:
        """The spectral abscissa of every loop (``inf`` where a loop is ill posed or its
        eigenvalues cannot be computed)."""
        K = self.gain(q)
        out = np.empty(len(self.parts))
        for j, P in enumerate(self.parts):
            try:
                M = self._matrix(P, K)
                out[j] = float(np.max(np.linalg.eigvals(M).real)) if np.all(np.isfinite(M)) \
                    else np.inf
            except (np.linalg.LinAlgError, ValueError):
                out[j] = np.inf
        return out

    def rightmost(self, q: np.ndarray, j: int) -> tuple[float, np.ndarray]:
        """Real part of loop ``j``'s rightmost eigenvalue and its gradient in ``q``."""
        K = self.gain(q)
        loop = self._loop(K, j)
        if loop is None:
            return np.inf, np.zeros(int(self.free.sum()))
        return float(np.max(loop[1].real)), self._gradient(j, *loop)

    def _loop(self, K: np.ndarray, j: int):
        """``(M, eigenvalues, L, R)`` of loop ``j`` closed by ``K``, or ``None`` where it is
        ill posed or its eigenvalues cannot be computed."""
        P = self.parts[j]
        try:
            Kt, L, R = P.loop_gain(K)
            M = P.A + P.B2 @ Kt @ P.C2
            if not np.all(np.isfinite(M)):
                return None
            lam = np.linalg.eigvals(M)
        except (np.linalg.LinAlgError, ValueError):
            return None
        return M, lam, L, R

    def _gradient(self, j: int, M: np.ndarray, lam: np.ndarray, L: np.ndarray,
                  R: np.ndarray) -> np.ndarray:
        """The gradient in ``q`` of the real part of the rightmost of ``lam`` (module
        docstring), zero where that eigenvalue is (numerically) defective."""
        P = self.parts[j]
        zero = np.zeros(int(self.free.sum()))
        i = int(np.argmax(lam.real))
        if not np.isfinite(lam[i].real):
            return zero
        x, y = _eigenvectors(M, lam[i])
        yx = y.conj() @ x
        if abs(yx) < 1e-300:
            return zero
        a = (y.conj() @ P.B2) / yx
        b = P.C2 @ x
        G = L.T @ np.real(np.outer(a, b)) @ R.T
        return G[self.free]

    def smoothed(self, q: np.ndarray, tau: float | None, *, lazy: bool = False
                 ) -> tuple[float, np.ndarray | Callable[[], np.ndarray]]:
        """The worst abscissa over the loops, or its log-sum-exp of temperature ``tau``
        (``tau → 0`` is the maximum), and its gradient in ``q``; with ``lazy`` the gradient
        as a callable of no arguments, which computes the eigenvectors it needs only when
        called (:func:`._bfgs.nonsmooth_bfgs` does not, for a rejected trial step)."""
        K = self.gain(q)
        loops = [self._loop(K, j) for j in range(len(self.parts))]
        a = np.array([np.inf if lp is None else float(np.max(lp[1].real)) for lp in loops])
        k = int(np.argmax(a))
        if not np.isfinite(a[k]):
            return np.inf, np.zeros(q.size)
        if tau is None:
            value = float(a[k])

            def grad():
                return self._gradient(k, *loops[k])
        else:
            w = np.exp((a - a[k]) / tau)
            total = float(np.sum(w))
            value = float(a[k] + tau * math.log(total))

            def grad():
                # a loop whose weight is below 1e-16 of the total adds less than that
                return sum((w[j] / total) * self._gradient(j, *loops[j])
                           for j in range(len(loops)) if w[j] > 1e-16 * total)
        return value, (grad if lazy else grad())


_GETRF, _GETRS = sla.get_lapack_funcs(("getrf", "getrs"), dtype=np.complex128)


def _eigenvectors(M: np.ndarray, lam: complex) -> tuple[np.ndarray, np.ndarray]:
    """Right and left eigenvectors ``(x, y)`` of ``M`` for its eigenvalue ``lam``: ``M x = λ x``,
    ``yᴴ M = λ yᴴ``.

    Two steps of inverse iteration on one LU factorisation of ``M − λ I`` (a fraction of the
    cost of all eigenvectors, which the gradient of one eigenvalue does not need), from a
    fixed start; where the residual shows that this did not converge (an eigenvalue in a
    tight cluster), the eigenvector of the full eigendecomposition nearest to ``lam``.
    """
    n = M.shape[0]
    scale = max(1.0, float(np.max(np.abs(M))))
    shifted = M - (lam + 1e-13 * scale) * np.eye(n)
    x = y = np.full(n, 1.0 / math.sqrt(n)) + 1j * np.linspace(-1.0, 1.0, n) / n
    with np.errstate(all="ignore"):
        lu, piv, info = _GETRF(shifted)
        ok = info >= 0
        for _ in range(2 if ok else 0):
            x = _GETRS(lu, piv, x)[0]
            y = _GETRS(lu, piv, y, trans=2)[0]
            x, y = x / np.linalg.norm(x), y / np.linalg.norm(y)
        ok = (ok and np.all(np.isfinite(x)) and np.all(np.isfinite(y))
              and np.linalg.norm(M @ x - lam * x) <= 1e-9 * scale
              and np.linalg.norm(y.conj() @ M - lam * y.conj()) <= 1e-9 * scale)
    if ok:
        return x, y
    w, VL, VR = sla.eig(M, left=True, right=True)
    i = int(np.argmin(np.abs(w - lam)))
    return VR[:, i], VL[:, i]
