"""What a controller of order ``k`` can reach at a few frequencies: a rank relaxation.

For ``K(s) = Dk + Ck (sI − Ak)⁻¹ Bk`` of order ``k`` every frequency response satisfies

    K(jω) − K(j∞) = Ck (jωI − Ak)⁻¹ Bk = U W(ω) V,      U = Ck (ncon × k), V = Bk (k × nmeas),

so at the frequencies ``ω_1 … ω_m`` the gains ``K_i = K(jω_i)`` differ from the feed-through
``K∞ = Dk`` by matrices that share one column space of dimension ``k`` and one row space of
dimension ``k``.  When ``k < ncon`` a control direction ``q`` (``qᵀ Ck = 0``) is static,
``qᵀK(jω) = qᵀDk`` at every ω; when ``k < nmeas`` a measurement combination is.  Because
``T(jω_i)`` depends on the controller only through ``K_i``, and ``T(j∞)`` only through
``K∞``,

    γ_k  >=  min over K∞, U, V, W_i of  max( σ̄ T(j∞; K∞), max_i σ̄ T(jω_i; K∞ + U W_i V) ),

with the realness of ``K∞, U, V`` (and of ``W_i`` at ω = 0) kept and the structure
``W(ω) = (jωI − Ak)⁻¹`` dropped.  The inequality holds for every stabilising controller of
order ``k`` whose ``Ak`` has no eigenvalue at the ``jω_i`` (stability is not required of the
relaxation, which only makes its minimum smaller).  With one frequency, ``ω = 0``, it is the
static-direction bound: low-frequency action (integral action on a weighted tracking error)
in a direction with no controller state costs the same gain at high frequency, where the
control weight sees it.  It is nontrivial when ``k < min(ncon, nmeas)`` (one frequency) or
``k < max(ncon, nmeas)`` (two or more).

The relaxation is nonconvex.  It is minimised locally from several seeded starts (BFGS with
exact gradients on the ``p``-norm of all the singular values, ``p`` raised in steps, so
that the minimiser of the smooth function approaches one of the maximum); the result is
*the best local minimum found*, an estimate of the lower bound, not a certificate: it is a
lower bound on ``γ_k`` only when it is the global minimum.  The spread of the local minima
over the starts is returned so that this can be judged.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import control
import numpy as np
from scipy.optimize import minimize

from ..errors import ConfigError, DimensionError
from ._plant import Partition, partition

__all__ = ["OrderBound", "order_relaxation"]

log = logging.getLogger("casflutter.design")

_P_STEPS = (8.0, 32.0, 128.0, 512.0)


@dataclass(frozen=True)
class OrderBound:
    """Outcome of :func:`order_relaxation`.

    Attributes
    ----------
    order : int
        Controller order ``k``.
    frequencies : tuple of float
        The finite frequencies ω_i (rad/s); ``ω = ∞`` is always included.
    value : float
        Best local minimum found of the relaxation (the largest σ̄ over the frequencies at
        the best point): a lower bound on the order-``k`` γ if it is the global minimum.
    start_values : tuple of float
        The local minimum reached from each start (their spread shows how reliably the
        global minimum was found).
    sigma_at_infinity : float
        σ̄ T(j∞) at the best point.
    sigma_at_frequencies : tuple of float
        σ̄ T(jω_i) at the best point.
    trivial : bool
        True when the order is large enough for the rank structure to constrain nothing
        (``k >= min(ncon, nmeas)`` with one frequency, ``k >= max(ncon, nmeas)`` with more):
        the value is then only the best each frequency allows on its own.
    """

    order: int
    frequencies: tuple
    value: float
    start_values: tuple
    sigma_at_infinity: float
    sigma_at_frequencies: tuple
    trivial: bool


def _blocks(P: Partition, w: float) -> list[np.ndarray]:
    """``P(jω)`` partitioned (``ω = inf``: the feed-through)."""
    if not np.isfinite(w):
        return [P.D11.astype(complex), P.D12.astype(complex), P.D21.astype(complex),
                P.D22.astype(complex)]
    n, nw = P.nx, P.B1.shape[1]
    M = 1j * w * np.eye(n) - P.A
    if n and np.linalg.cond(M) > 1e12:
        raise ConfigError(f"frequency {w!r} rad/s is (numerically) a pole of the plant: "
                          "choose frequencies away from the plant's poles on the axis")
    R = np.linalg.solve(M, np.hstack([P.B1, P.B2])) if n else np.zeros((0, nw + P.B2.shape[1]))
    return [P.D11 + P.C1 @ R[:, :nw], P.D12 + P.C1 @ R[:, nw:], P.D21 + P.C2 @ R[:, :nw],
            P.D22 + P.C2 @ R[:, nw:]]


class _Relaxation:
    """Parameters ``x = [K∞, U, V, W_1, …]`` (real; complex ``W_i`` as real and imaginary
    parts, real at ω = 0), the singular values and the exact gradient of their p-norm."""

    def __init__(self, P: Partition, order: int, freqs: Sequence[float]):
        self.nw, self.nz, self.nu, self.ny = P.dims
        self.k = order
        self.freqs = list(freqs)
        self.G = [_blocks(P, np.inf)] + [_blocks(P, w) for w in self.freqs]
        k, nu, ny = order, self.nu, self.ny
        self.cplx = [w != 0.0 for w in self.freqs]
        self.sizes = [nu * ny, nu * k, k * ny] + [k * k * (2 if c else 1) for c in self.cplx]
        self.n = int(sum(self.sizes))

    def unpack(self, x):
        k, nu, ny = self.k, self.nu, self.ny
        parts, o = [], 0
        for s in self.sizes:
            parts.append(x[o:o + s])
            o += s
        Kinf = parts[0].reshape(nu, ny)
        U = parts[1].reshape(nu, k)
        V = parts[2].reshape(k, ny)
        Ws = [(m[:k * k].reshape(k, k) + 1j * m[k * k:].reshape(k, k)) if c
              else m.reshape(k, k).astype(complex) for m, c in zip(parts[3:], self.cplx)]
        return Kinf, U, V, Ws

    def gains(self, x) -> list[np.ndarray]:
        Kinf, U, V, Ws = self.unpack(x)
        return [Kinf.astype(complex)] + [Kinf + U @ W @ V for W in Ws]

    def _lft(self, Gb, K):
        P11, P12, P21, P22 = Gb
        Mi = np.linalg.inv(np.eye(self.ny) - P22 @ K)          # (I − P22 K)⁻¹
        L = P12 @ np.linalg.inv(np.eye(self.nu) - K @ P22)      # P12 (I − K P22)⁻¹
        R = Mi @ P21
        return P11 + P12 @ K @ R, L, R

    def sigmas(self, x) -> list[np.ndarray]:
        out = []
        for Gb, K in zip(self.G, self.gains(x)):
            try:
                T = self._lft(Gb, K)[0]
                out.append(np.linalg.svd(T, compute_uv=False))
            except np.linalg.LinAlgError:
                out.append(np.array([np.inf]))
        return out

    def fun_grad(self, x, p: float) -> tuple[float, np.ndarray]:
        Kinf, U, V, Ws = self.unpack(x)
        Ks = self.gains(x)
        try:
            pieces = []
            for Gb, K in zip(self.G, Ks):
                T, L, R = self._lft(Gb, K)
                Us, s, Vh = np.linalg.svd(T, full_matrices=False)
                pieces.append((L, R, Us, s, Vh))
        except np.linalg.LinAlgError:
            return np.inf, np.zeros_like(x)
        smax = max(float(pc[3][0]) for pc in pieces)
        if not np.isfinite(smax) or smax <= 0:
            return np.inf, np.zeros_like(x)
        tot = sum(float(np.sum((pc[3] / smax) ** p)) for pc in pieces)
        f = smax * tot ** (1.0 / p)
        gK = []
        for L, R, Us, s, Vh in pieces:
            c = (s / f) ** (p - 1.0)
            GT = (Us * c[None, :]) @ Vh                   # ∂f/∂T (df = Re tr(GTᴴ dT))
            gK.append(L.conj().T @ GT @ R.conj().T)       # ∂f/∂K through dT = L dK R
        k = self.k
        g_inf = np.real(gK[0]).copy()
        gU = np.zeros_like(U)
        gV = np.zeros_like(V)
        gW = []
        for Gk, W, c in zip(gK[1:], Ws, self.cplx):
            g_inf += np.real(Gk)
            gU += np.real(Gk @ (W @ V).conj().T)
            gV += np.real((U @ W).conj().T @ Gk)
            Z = U.T @ Gk @ V.T
            gW.append(np.concatenate([np.real(Z).ravel(), np.imag(Z).ravel()]) if c
                      else np.real(Z).ravel())
        g = np.concatenate([g_inf.ravel(), gU.ravel(), gV.ravel()] + gW)
        return float(f), g


def order_relaxation(plant: control.StateSpace | Partition, nmeas: int, ncon: int, order: int,
                     frequencies: Sequence[float] = (0.0,), *, starts: int = 6,
                     seed: int = 0) -> OrderBound:
    """Best local minimum of the rank relaxation of order-``k`` H∞ synthesis (module
    docstring): an estimate of a lower bound on the γ any order-``k`` controller can reach.

    Parameters
    ----------
    plant : control.StateSpace or Partition
        Generalised plant (``hinfsyn`` convention, ``u = K y``).
    nmeas, ncon : int
        Number of measurements and controls.
    order : int
        Controller order ``k >= 0``.
    frequencies : sequence of float
        Finite frequencies ω_i >= 0 (rad/s) at which the relaxation looks, besides ω = ∞;
        none may be a pole of the plant on the imaginary axis.  ``(0,)`` gives the
        static-direction bound.
    starts : int
        Number of seeded random starts (``>= 1``).
    seed : int
        Seed of the starts (same seed, same result).

    Returns
    -------
    OrderBound
        The best local minimum, per-start minima and the σ̄ at each frequency there.

    Raises
    ------
    ConfigError
        If ``order``, ``starts`` or a frequency is invalid (negative, not finite, or a pole
        of the plant).
    DimensionError
        If the plant does not fit ``nmeas``, ``ncon``.
    """
    if int(order) != order or order < 0:
        raise ConfigError(f"order must be an integer >= 0, got {order!r}")
    if starts < 1:
        raise ConfigError(f"starts must be >= 1, got {starts}")
    freqs = [float(w) for w in frequencies]
    if not freqs or any(not np.isfinite(w) or w < 0 for w in freqs):
        raise ConfigError(f"frequencies must be finite and >= 0 (at least one), got "
                          f"{list(frequencies)!r}")
    P = plant if isinstance(plant, Partition) else partition(plant, nmeas, ncon)
    if P.dims[2:] != (ncon, nmeas):
        raise DimensionError(f"plant has (ncon, nmeas) = {P.dims[2:]}, expected "
                             f"{(ncon, nmeas)}")
    order = int(order)
    rel = _Relaxation(P, order, freqs)
    rng = np.random.default_rng(seed)
    best, best_x, values = np.inf, None, []
    for s in range(starts):
        x = rng.standard_normal(rel.n) * (0.1, 0.3, 1.0)[s % 3]
        for p in _P_STEPS:
            r = minimize(rel.fun_grad, x, args=(p,), jac=True, method="BFGS",
                         options={"maxiter": 4000, "gtol": 1e-10})
            if np.all(np.isfinite(r.x)):
                x = r.x
        v = max(float(sv[0]) for sv in rel.sigmas(x))
        values.append(v)
        log.info("order relaxation (order %d, %d frequencies): start %d ends at %.6g", order,
                 len(freqs), s, v)
        if v < best:
            best, best_x = v, x
    sv = rel.sigmas(best_x)
    one = len(freqs) == 1
    trivial = order >= (min(ncon, nmeas) if one else max(ncon, nmeas))
    return OrderBound(order=order, frequencies=tuple(freqs), value=float(best),
                      start_values=tuple(float(v) for v in values),
                      sigma_at_infinity=float(sv[0][0]),
                      sigma_at_frequencies=tuple(float(s[0]) for s in sv[1:]),
                      trivial=bool(trivial))
