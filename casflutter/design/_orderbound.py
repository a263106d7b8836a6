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

For one static control direction (or measurement combination) at two frequencies the
relaxation can be solved globally: :func:`static_direction_bound` eliminates everything but
``(q, qᵀDk)`` in closed form and certifies the bound with an S-procedure multiplier.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from fractions import Fraction
from typing import Sequence

import control
import numpy as np
from scipy.optimize import minimize, minimize_scalar

from .._format import result_repr
from ..errors import ConfigError, DimensionError
from . import _exact
from ._plant import Partition, partition

__all__ = ["OrderBound", "order_relaxation", "StaticDirectionBound", "static_direction_bound"]

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
    start_converged : tuple of bool
        Per start: every BFGS run of its sharpening sequence met scipy's convergence test
        (a start that did not still gives a point of the relaxation, just not a
        stationary one).
    trivial : bool
        True when the order is large enough for the rank structure to constrain nothing
        (``k >= min(ncon, nmeas)`` with one frequency, ``k >= max(ncon, nmeas)`` with more):
        the value is then only the best each frequency allows on its own.
    """

    __repr__ = result_repr

    order: int
    frequencies: tuple
    value: float
    start_values: tuple
    sigma_at_infinity: float
    sigma_at_frequencies: tuple
    trivial: bool
    start_converged: tuple = ()


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


def _partitioned(plant: control.StateSpace | Partition, nmeas: int, ncon: int) -> Partition:
    """The plant's blocks, checked against ``nmeas`` and ``ncon``."""
    P = plant if isinstance(plant, Partition) else partition(plant, nmeas, ncon)
    if P.dims[2:] != (ncon, nmeas):
        raise DimensionError(f"plant has (ncon, nmeas) = {P.dims[2:]}, expected "
                             f"{(ncon, nmeas)}")
    return P


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
    P = _partitioned(plant, nmeas, ncon)
    order = int(order)
    rel = _Relaxation(P, order, freqs)
    rng = np.random.default_rng(seed)
    best, best_x, values, converged = np.inf, None, [], []
    for s in range(starts):
        x = rng.standard_normal(rel.n) * (0.1, 0.3, 1.0)[s % 3]
        ok = True
        for p in _P_STEPS:
            r = minimize(rel.fun_grad, x, args=(p,), jac=True, method="BFGS",
                         options={"maxiter": 4000, "gtol": 1e-10})
            ok = ok and bool(r.success)
            if np.all(np.isfinite(r.x)):
                x = r.x
        v = max(float(sv[0]) for sv in rel.sigmas(x))
        values.append(v)
        converged.append(ok)
        log.debug("order relaxation (order %d, %d frequencies): start %d ends at %.6g%s", order,
                  len(freqs), s, v, "" if ok else " (BFGS stopped before convergence)")
        if v < best:
            best, best_x = v, x
    sv = rel.sigmas(best_x)
    one = len(freqs) == 1
    trivial = order >= (min(ncon, nmeas) if one else max(ncon, nmeas))
    return OrderBound(order=order, frequencies=tuple(freqs), value=float(best),
                      start_values=tuple(float(v) for v in values),
                      sigma_at_infinity=float(sv[0][0]),
                      sigma_at_frequencies=tuple(float(s[0]) for s in sv[1:]),
                      trivial=bool(trivial), start_converged=tuple(converged))


# -- the static-direction certificate -----------------------------------------------------

@dataclass(frozen=True)
class StaticDirectionBound:
    """Outcome of :func:`static_direction_bound`: a certified lower bound on γ.

    Attributes
    ----------
    value : float
        Every stabilising controller of order at most ``order`` (so with ``directions``
        static control directions, or measurement combinations on the measurement side) has
        ``‖T_zw‖∞ >= value``.  Certified by an
        S-procedure multiplier (below): positive definite in exact arithmetic (``exact``), or
        with a smallest eigenvalue above ``tolerance``.
    estimate : float
        The largest γ whose best multiplier has a positive ``m``-th eigenvalue, without the
        rounding margin (``value <= estimate``).  With one direction it is the two-frequency
        relaxation's global minimum: by the S-lemma (two quadratic forms, one of them negative
        somewhere) the multiplier exists exactly up to it.
    upper : float
        The first γ above ``estimate`` at which the bisection found no multiplier
        (``inf`` when none failed up to ``1e12`` times the start).
    side : str
        ``"control"`` or ``"measurement"``.
    order : int
        The bound holds for every controller of order up to ``order``.
    directions : int
        The number ``m`` of static directions such a controller has (``ncon − order``, or
        ``nmeas − order`` on the measurement side).
    frequencies : tuple of float
        The two frequencies (rad/s; ``inf`` is the feed-through) whose gains are bounded.
    multiplier : tuple of float
        ``(t1, t2)``, ``t1 + t2 = 1``, with ``t1 Φ1 + t2 Φ2`` having fewer than ``m`` negative
        eigenvalues at ``value`` (positive definite for ``m = 1``; matrices normalised to unit
        norm); empty when ``value`` is the per-frequency floor.
    margin : float
        The ``m``-th smallest eigenvalue of that combination (``nan`` when there is none).
    tolerance : float
        The margin required of it in floating point: ``100 · eps · κ``, κ the largest
        condition number of ``jωI − A`` at the two frequencies (1 at ω = ∞), for the rounding
        in ``P(jω)`` (not used when ``exact``).
    exact : bool
        True when ``value`` was proven in exact rational arithmetic on the plant's numbers
        (the multiplier's combination's inertia by exact elimination).
    per_frequency : tuple of float
        The bound each frequency gives on its own for any controller, ``‖Π⊥ P11(jω)‖`` with
        Π⊥ the projector off the range of ``P12(jω)``: ``value`` is at least their maximum.
    """

    __repr__ = result_repr

    value: float
    estimate: float
    upper: float
    side: str
    order: int
    directions: int
    frequencies: tuple
    multiplier: tuple
    margin: float
    tolerance: float
    exact: bool
    per_frequency: tuple


def _transposed(P: Partition) -> Partition:
    """The dual plant: ``T_zw`` of ``(P, K)`` is the transpose of ``T`` of ``(Pᵀ, Kᵀ)``."""
    return Partition(P.A.T, P.C1.T, P.C2.T, P.B1.T, P.B2.T, P.D11.T, P.D21.T, P.D12.T,
                     P.D22.T)


class _StaticDirectionForms:
    """The quadratic forms of the static-direction relaxation at one frequency.

    A controller with a static control direction ``q`` (``qᵀ K(s) = rᵀ`` at every ``s``) has,
    with ``Q = K (I − P22 K)⁻¹`` and ``T = P11 + P12 Q P21``,
    ``aᵀ Q = rᵀ`` for ``a = q − P22ᵀ r``.  The unit vector ``e = P12 G⁻¹ ā / n``
    (``G = P12ᴴ P12``, ``n² = aᵀ G⁻¹ ā``) is orthogonal to everything ``Q`` can still move
    inside the range of ``P12``, so ``eᴴ T = (aᵀ P12⁺ P11 + rᵀ P21) / n =: mᵀ`` whatever the
    rest of ``Q``; with ``Π⊥`` the projector off that range, ``Π⊥ T = Π⊥ P11 =: A0``.  As
    ``Π⊥ + e eᴴ`` is an orthogonal projector, ``σ̄ T >= σ̄ [A0; mᵀ]``, and ``σ̄ [A0; mᵀ] < γ``
    is, for ``γ > σ̄ A0``, the quadratic inequality ``zᵀ Φ(γ) z < 0`` in ``z = (q, r)``.
    """

    def __init__(self, P: Partition, w: float, side: str = "control"):
        P11, P12, P21, P22 = _blocks(P, w)
        nu = P12.shape[1]
        # rounding in P(jω) grows with the condition of (jωI − A): it sets the certificate's margin
        self.kappa = (float(np.linalg.cond(1j * w * np.eye(P.nx) - P.A))
                      if np.isfinite(w) and P.nx else 1.0)
        sv = np.linalg.svd(P12, compute_uv=False)
        if sv.size < nu or sv[-1] <= 1e-12 * max(sv[0], 1e-300):
            what = (("P12", "controls", "control direction does not reach z", "D12")
                    if side == "control" else
                    ("P21ᵀ", "measurements", "measurement does not see w", "D21"))
            raise ConfigError(
                f"{what[0]} at ω = {w!r} rad/s has rank below the number of {what[1]} ({nu}): "
                f"some {what[2]} there, and the static-direction certificate on the {side} "
                f"side needs it to; choose another frequency (a finite one when {what[3]} is "
                "rank-deficient) or the other side")
        G = P12.conj().T @ P12
        P12p = np.linalg.solve(G, P12.conj().T)
        self.A0 = P11 - P12 @ (P12p @ P11)
        self.W = np.vstack([P12p @ P11, P21 - P22 @ P12p @ P11])
        L = np.hstack([np.eye(nu), -P22.T])
        self.N = np.real(L.T @ np.linalg.solve(G, L.conj()))
        self.floor = float(np.linalg.norm(self.A0, 2))
        self.nw = P11.shape[1]

    def phi(self, gamma: float) -> np.ndarray:
        """``Φ(γ)``: ``zᵀ Φ z < 0`` exactly when ``σ̄ [A0; m(z)ᵀ] < γ`` (``γ > σ̄ A0``)."""
        R = np.linalg.inv(gamma ** 2 * np.eye(self.nw) - self.A0.conj().T @ self.A0)
        F = np.real(self.W @ R @ self.W.conj().T) - self.N
        return 0.5 * (F + F.T)


def _multiplier(phis: list[np.ndarray], m: int = 1) -> tuple[float, float, tuple[float, float]]:
    """``max over t ∈ [0, 1]`` of the ``m``-th smallest eigenvalue ``λ_m((1 − t) Φ̂1 + t Φ̂2)``
    (unit-norm ``Φ̂``; concave in t for ``m = 1``, searched on a grid and refined otherwise):
    ``(t, λ_m, (w1, w2))`` with ``w1 Φ1 + w2 Φ2`` that combination."""
    norms = [float(np.linalg.norm(p, 2)) for p in phis]
    a, b = (p / n for p, n in zip(phis, norms))

    def neg(t):
        return -float(np.linalg.eigvalsh((1.0 - t) * a + t * b)[m - 1])

    grid = np.linspace(0.0, 1.0, 201)
    # the optimum can sit very close to an end (forms of very different scale): look there too
    grid = np.unique(np.concatenate([grid, np.logspace(-12, -2, 41), 1.0 - np.logspace(-12, -2, 41)]))
    vals = [neg(t) for t in grid]
    i = int(np.argmin(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    res = minimize_scalar(neg, bounds=(lo, hi), method="bounded", options={"xatol": 1e-15})
    t, v = (res.x, -res.fun) if -res.fun > -vals[i] else (grid[i], -vals[i])
    return float(t), float(v), ((1.0 - t) / norms[0], t / norms[1])


class _ExactStaticDirectionForms:
    """:class:`_StaticDirectionForms` in exact rational arithmetic (ω = 0 or ∞, where
    ``P(jω)`` is real): the plant's floats taken as the rationals they are."""

    def __init__(self, P: Partition, w: float):
        D = [_exact.fractions(M) for M in (P.D11, P.D12, P.D21, P.D22)]
        if np.isinf(w):
            P11, P12, P21, P22 = D
        elif w == 0.0:
            nw = P.B1.shape[1]
            try:    # (−A)⁻¹ [B1 B2]
                X = _exact.solve(_exact.fractions(-P.A), _exact.fractions(np.hstack([P.B1, P.B2])))
            except ZeroDivisionError:
                raise ConfigError("A is singular: ω = 0 is a pole of the plant; exact=True "
                                  "needs ω = 0 and ∞") from None
            X1, X2 = [r[:nw] for r in X], [r[nw:] for r in X]
            C1, C2 = _exact.fractions(P.C1), _exact.fractions(P.C2)
            one = Fraction(1)
            P11 = _exact.combine([(one, _exact.matmul(C1, X1)), (one, D[0])])
            P12 = _exact.combine([(one, _exact.matmul(C1, X2)), (one, D[1])])
            P21 = _exact.combine([(one, _exact.matmul(C2, X1)), (one, D[2])])
            P22 = _exact.combine([(one, _exact.matmul(C2, X2)), (one, D[3])])
        else:
            raise ConfigError(f"exact=True works at ω = 0 and ∞ only (real responses), got "
                              f"{w!r}")
        one = Fraction(1)
        P12t = _exact.transpose(P12)
        G = _exact.matmul(P12t, P12)
        H = _exact.solve(G, _exact.matmul(P12t, P11))                  # P12⁺ P11
        A0 = _exact.combine([(one, P11), (-one, _exact.matmul(P12, H))])
        self.W = H + _exact.combine([(one, P21), (-one, _exact.matmul(P22, H))])
        nu = len(P12t)
        L = [row + [-x for x in trow] for row, trow in zip(_exact.identity(nu),
                                                             _exact.transpose(P22))]
        self.N = _exact.matmul(_exact.transpose(L), _exact.solve(G, L))
        self.AtA = _exact.matmul(_exact.transpose(A0), A0)
        self.nw = len(self.AtA)

    def phi(self, gamma: Fraction):
        """``Φ(γ)`` exactly (a list of rows of ``Fraction``)."""
        R = _exact.solve(_exact.combine([(gamma * gamma, _exact.identity(self.nw)),
                                         (Fraction(-1), self.AtA)]), _exact.identity(self.nw))
        one = Fraction(1)
        return _exact.combine([(one, _exact.matmul(_exact.matmul(self.W, R),
                                                   _exact.transpose(self.W))), (-one, self.N)])


class _DirectionCertificate:
    """The multiplier search of :func:`static_direction_bound`: the best ``t`` at a level γ,
    whether it proves the bound, and the bisection for the largest such γ."""

    def __init__(self, forms: list, exact_forms: list | None, m: int, rtol: float):
        self.forms, self.exact_forms, self.m, self.rtol = forms, exact_forms, m, rtol
        self.tol = 100.0 * np.finfo(float).eps * max(f.kappa for f in forms)
        self.floor = max(f.floor for f in forms)    # any controller: γ >= σ̄ A0(jω) at each ω
        self.scale = max(float(np.linalg.norm(f.W, 2)) for f in forms)

    def multiplier(self, g):
        """Best ``(t, λ_m, weights)`` at γ = g (λ_m = -inf where rounding overwhelms)."""
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                phis = [f.phi(g) for f in self.forms]
            if not all(np.all(np.isfinite(p)) for p in phis):
                return 0.0, -np.inf, None
            return _multiplier(phis, self.m)
        except np.linalg.LinAlgError:
            return 0.0, -np.inf, None

    def certified(self, g, t, lam, weights) -> bool:
        """The multiplier at γ = g proves the bound: in exact arithmetic, or past rounding."""
        if self.exact_forms is None:
            return lam > self.tol
        if not lam > 0:
            return False
        gf = Fraction(g)
        try:
            phis = [f.phi(gf) for f in self.exact_forms]
        except ZeroDivisionError:           # γ² is an eigenvalue of A0ᵀA0: not certified
            return False
        neg = _exact.negative_eigenvalues(
            _exact.combine([(Fraction(w), ph) for w, ph in zip(weights, phis)]))
        return neg is not None and neg < self.m

    def largest(self, accept):
        """Bisection for the largest γ whose best multiplier is accepted:
        ``(γ, first γ that failed, t, λ_m)``; γ = floor (t None) when none is."""
        lo, hi, t_lo, lam_lo = self.floor, np.inf, None, np.nan
        g = max(1.01 * self.floor, 1e-6 * self.scale, 1e-300)
        cap = 1e12 * g
        while g < cap:      # double until the multiplier fails
            t, lam, wts = self.multiplier(g)
            if not accept(g, t, lam, wts):
                hi = g
                break
            lo, t_lo, lam_lo = g, t, lam
            g *= 2.0
        while np.isfinite(hi) and hi - lo > self.rtol * hi and hi > 1e-12 * self.scale:
            mid = 0.5 * (lo + hi)
            t, lam, wts = self.multiplier(mid)
            if accept(mid, t, lam, wts):
                lo, t_lo, lam_lo = mid, t, lam
            else:
                hi = mid
        return lo, hi, t_lo, lam_lo


def static_direction_bound(plant: control.StateSpace | Partition, nmeas: int, ncon: int, *,
                           order: int | None = None, side: str = "control",
                           frequencies: Sequence[float] = (0.0, np.inf),
                           rtol: float = 1e-6, exact: bool = False) -> StaticDirectionBound:
    """Certified lower bound on the γ of every controller with fewer states than controls.

    A controller of order ``k`` has ``K(s) = Dk + Ck (sI − Ak)⁻¹ Bk`` with ``Ck`` of size
    ``ncon × k``.  When ``k < ncon`` some real unit ``q`` has ``qᵀ Ck = 0``, so
    ``qᵀ K(s) = qᵀ Dk =: rᵀ`` at every frequency: one combination of the controls is a
    static output feedback.  At one frequency this costs nothing (``r`` is free), but the
    same ``r`` acts at two frequencies, e.g. integral action a low-frequency weight demands
    (ω = 0) against the control weight at high frequency (ω = ∞).  For each frequency,
    ``σ̄ T(jω) >= σ̄ [A0; m(q, r)ᵀ]`` with ``m`` a ratio of linear functions of ``(q, r)``
    (:class:`_StaticDirectionForms`), so ``max_ω σ̄ T(jω) < γ`` at both frequencies asks two
    quadratic forms to be negative at one ``z = (q, r) ≠ 0``.  A multiplier ``t ∈ [0, 1]``
    with ``(1 − t) Φ1(γ) + t Φ2(γ) ⪰ 0`` rules that out (S-procedure), so every such
    controller has ``‖T‖∞ >= γ``; the largest such γ is found by bisection.  For two forms
    the S-lemma is lossless, so the value is the global minimum of this two-frequency
    relaxation (``estimate``; ``value`` is below it by the rounding margin), found without
    local searches.  The relaxation drops the controller's dynamics everywhere except
    through ``q`` and ``r``, and stability (only used for ``‖T‖∞ >= σ̄ T(jω)``): where it is
    tight, the order-``k`` optimum is close to it.

    An order ``k`` lower by ``m − 1`` leaves ``m = ncon − k`` static directions, the columns
    of an orthonormal ``Q_s`` with ``Q_sᵀ K(s) = Rᵀ``; the same algebra gives an ``m × m``
    matrix inequality ``Zᵀ Φ(γ) Z ≺ 0`` in ``Z = [Q_s; R]`` at each frequency, and a
    combination ``(1 − t) Φ1 + t Φ2`` with fewer than ``m`` negative eigenvalues rules it out
    (no ``m``-dimensional subspace on which it is negative definite).  For ``m > 1`` this is
    sufficient only: ``estimate`` is then what the certificate reaches, not necessarily the
    relaxation's minimum.

    With ``side = "measurement"`` the same is done on the dual plant: a controller with
    ``k < nmeas`` has ``nmeas − k`` static measurement combinations ``K(s) p = Dk p``.

    Parameters
    ----------
    plant : control.StateSpace or Partition
        Generalised plant (``hinfsyn`` convention, ``u = K y``).
    nmeas, ncon : int
        Number of measurements and controls.
    order : int, optional
        The controller order ``k`` to bound (the bound holds for every order up to ``k``);
        ``0 <= k < ncon`` (``< nmeas`` on the measurement side).  Default: one less than
        ``ncon`` (``nmeas``), one static direction.
    side : {"control", "measurement"}
        Which static directions to use.
    frequencies : pair of float
        Two distinct frequencies in ``[0, inf]`` (rad/s); ``inf`` is the feed-through.
        ``P12(jω)`` (``P21(jω)ᵀ`` for the measurement side) must have full column rank at both,
        and a finite one must not be a pole of the plant.
    rtol : float
        Relative accuracy of the bisections.
    exact : bool
        Accept a multiplier only when the combination's inertia (fewer than ``m`` negative
        eigenvalues) holds in exact rational arithmetic on the plant's own numbers
        (``fractions.Fraction``; frequencies 0 and ∞ only): ``value`` is then proven, not
        computed with a rounding margin.  The
        cost grows quickly with the number of states (about 0.1 s per check at 20 states).

    Returns
    -------
    StaticDirectionBound

    Raises
    ------
    ConfigError
        If ``order``, ``side``, ``frequencies`` or ``rtol`` are invalid, or the plant's ``P12`` lacks
        rank at a frequency (the message says which), or ``exact`` is asked at another
        frequency than 0 and ∞.
    DimensionError
        If the plant does not fit ``nmeas``, ``ncon``.

    Notes
    -----
    At ω = 0 an integrator of the controller leaves ``K(0)`` undefined but not ``Q(0)``,
    a closed-loop map of a stabilising controller, and ``aᵀ Q = rᵀ`` holds there by
    continuity; the bound stands.  Rounding: without ``exact`` a multiplier is accepted only
    when the ``m``-th smallest eigenvalue of the unit-norm combination exceeds ``100 · eps · κ``, with
    κ the largest condition number of ``jωI − A`` at the two frequencies (1 at ω = ∞); with
    ``exact`` the multiplier found in floating point is re-checked on exact rationals.
    """
    if side not in ("control", "measurement"):
        raise ConfigError(f"side must be 'control' or 'measurement', got {side!r}")
    freqs = tuple(float(w) for w in frequencies)
    if (len(freqs) != 2 or freqs[0] == freqs[1] or any(np.isnan(w) or w < 0 for w in freqs)):
        raise ConfigError(f"frequencies must be two distinct values in [0, inf] (rad/s), "
                          f"got {list(frequencies)!r}")
    if not (0.0 < rtol < 0.1):
        raise ConfigError(f"rtol must be in (0, 0.1), got {rtol!r}")
    P = _partitioned(plant, nmeas, ncon)
    n_dir = ncon if side == "control" else nmeas
    k = n_dir - 1 if order is None else order
    if int(k) != k or not 0 <= k < n_dir:
        raise ConfigError(f"order must be an integer in [0, {n_dir - 1}] on the {side} side "
                          f"({n_dir} {'controls' if side == 'control' else 'measurements'}: "
                          f"a controller of order >= {n_dir} has no static direction), "
                          f"got {order!r}")
    k = int(k)
    m = n_dir - k
    Pd = P if side == "control" else _transposed(P)
    cert = _DirectionCertificate([_StaticDirectionForms(Pd, w, side) for w in freqs],
                                 [_ExactStaticDirectionForms(Pd, w) for w in freqs]
                                 if exact else None, m, rtol)
    value, _, t_val, lam_val = cert.largest(cert.certified)
    estimate, upper, _, _ = cert.largest(lambda g, t, lam, w: lam > 0)
    log.info("static-direction bound (%s side, order <= %d, ω = %s): γ >= %.6g certified%s "
             "(without margin %.6g)", side, k, freqs, value, " exactly" if exact else "",
             estimate)
    return StaticDirectionBound(value=float(value), estimate=float(estimate),
                                upper=float(upper), side=side, order=k, directions=m,
                                frequencies=freqs,
                                multiplier=() if t_val is None else (1.0 - t_val, t_val),
                                margin=float(lam_val), tolerance=float(cert.tol),
                                exact=bool(exact and t_val is not None),
                                per_frequency=tuple(f.floor for f in cert.forms))
