"""The certified speed interval on which a controller holds a plant family, piece by piece.

A plant family (:class:`casflutter.aeroelastic.PlantFamily`) says how its matrices depend on
the speed: polynomials of degree ``d`` in V between its breakpoints (``speed_degree``,
``breakpoints``: ``d = 2`` for strip theory's ΣAE(V) of eq. 8-9, ``d = 1`` between the speeds
of a linearly interpolated grid).  On a piece ``[a, b]``, with ``t = (V - a)/(b - a)``, the
loop closed with ``u = s K y`` (``s = ±1``) is

    ż = P(t) z + Q(t) u,   M(t) u = R(t) z,   z = (x, x_K),

``P, Q, R, M`` polynomials of degree ``d`` in t (the controller does not depend on V).  When
the controller is strictly proper ``M = I`` and ``A_cl(t) = P + Q R`` is a polynomial; when
both feed-throughs are nonzero ``A_cl = P + Q M⁻¹ R`` is rational in t.  Two certificates:

* **Eigenvalue inclusion** (each step O(n³)).  At a speed ``t`` where ``A_cl`` is Hurwitz,
  ``A_cl(t + δ) = A0 + δ A1 + F(δ)`` with ``A1`` the exact derivative and ``‖F(δ)‖₂ ≤ f(h)``
  on ``0 ≤ δ ≤ h`` (zero for an affine piece; from the polynomial coefficients, and a
  Neumann-series majorant of ``M⁻¹``, otherwise).  In the eigenvector basis of ``A0``
  (``Λ``, ``E = V⁻¹ A1 V``) the similarity ``X = I + δ G``, ``G_ij = E_ij / (λ_j - λ_i)``
  between eigenvalues that are not (numerically) equal, removes the first-order coupling:
  the Gershgorin discs of ``X⁻¹ V⁻¹ A_cl V X`` are centred at ``λ_i + δ E_ii`` (the exact
  first-order eigenvalue motion) with radii of order δ² (bounded entrywise through
  ``|X⁻¹| ≤ (I - δ|G|)⁻¹``), plus ``√n ‖X⁻¹‖ ‖X‖ κ(V) f(h)`` and the eigen-decomposition's
  own residual.  All discs in the open left half-plane for every ``δ ≤ h`` proves the loop
  stable on ``[t, t + h]``; the largest such h is the step, and steps are chained.  A
  lightly damped mode whose damping changes slowly is passed in few steps, and near a loss
  of stability the steps shrink geometrically onto it (the discs move with the eigenvalue),
  so the chain's last certified speed lies within ``xtol`` of a speed shown unstable.
* **Guardian map** (exact, O(n⁶); where the chain stalls, or from a marginally stable
  start such as ``V = 0`` for a loop family): an eigenvalue pair crosses the imaginary axis
  only where ``λ_i + λ_j = 0``, i.e. where ``A_cl X + X A_clᵀ = 0`` has an antisymmetric
  solution X; with ``Y = M⁻¹ R X`` this is ``P X + X Pᵀ + Q Y - Yᵀ Qᵀ = 0``,
  ``M Y - R X = 0``, a polynomial eigenvalue problem in t of order ``n(n-1)/2 + k n`` (k the
  smaller of the numbers of controls and measurements; ``n(n-1)/2``, the bialternate sum
  ``2A_cl ⊙ I``, when ``M = I``).  A real eigenvalue crosses where ``[P Q; -R M]`` is
  singular, the loop is ill posed where ``M`` is; stability changes only at these roots and
  the stretches between them are judged at their midpoints
  (:func:`casflutter.verify.polynomial_stability_interval`'s rule).

Neither is a grid scan: every speed of the returned interval lies in a chain step proved
stable or between two guardian roots judged stable (in floating point: the residual of the
computed eigen-decomposition is part of the bound, other rounding errors are not).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ._common import as_statespace, is_hurwitz, spectral_abscissa, ssdata
from ._interval import _pencil_roots, _pick_ends, bialternate_sum

__all__ = ["PieceCertificate", "CertifiedInterval", "certified_interval"]

_log = logging.getLogger(__name__)

#: eigenvalues closer than this (relative) are one cluster: their coupling stays first order
_CLUSTER_TOL = 1e-6
#: a guardian root this close (in t) to a piece's end is a crossing at the breakpoint
_END_TOL = 1e-9
#: where the chain's steps fall below xtol, the loop is probed this many xtol further on
_PROBE = 1000.0


@dataclass(frozen=True)
class PieceCertificate:
    """How one polynomial piece of the family was certified.

    Attributes
    ----------
    lower, upper : float
        The piece's speeds.
    method : str
        ``"inclusion"`` (a chain of eigenvalue-inclusion steps), ``"guardian"`` (the exact
        guardian map decided the rest of the piece after any steps), or ``"unstable at
        start"`` (the loop is not stable at the piece's first speed).
    certified_to : float
        Highest speed of the piece up to which the loop is certified stable (``upper`` when
        the whole piece is).
    steps : int
        Eigenvalue-inclusion steps taken.
    pencil_order : int
        Order of the guardian pencil's linearisation (0 when it was not needed).
    wall_time : float
        Seconds spent on the piece.
    """

    __repr__ = result_repr

    lower: float
    upper: float
    method: str
    certified_to: float
    steps: int
    pencil_order: int
    wall_time: float


@dataclass(frozen=True)
class CertifiedInterval:
    """The certified interval, containing the range's start, on which the loop is stable.

    Attributes
    ----------
    lower, upper : float or None
        The loop is certified stable for ``lower < V < upper``, at ``V = lower`` when
        ``stable_at_start`` and at ``V = upper`` when ``holds_range``; both ``None`` when it
        is not stable just above the range's start.
    stable_at_start : bool
        Whether the loop is stable at the range's start itself (a loop family's lag states,
        ∝ V, put eigenvalues at the origin at ``V = 0``: its loop is only marginally stable
        there).
    speed_range : tuple of float
        The range examined.
    holds_range : bool
        True when the loop is stable on the whole range.
    loss : float or None
        The speed at which the loop is first found unstable: ``upper`` itself for an end
        found by the guardian map, within ``xtol`` above it for an end reached by the chain
        (located there by bisection of the spectral abscissa); ``None`` when the range is
        held.
    crossing : str
        What happens at ``loss``: ``"complex pair"`` (flutter), ``"real through 0"``
        (divergence), ``"ill-posed"``, ``"breakpoint"`` (lost exactly at a breakpoint),
        ``"unstable at start"``, or ``"none"`` (the range is held); `` (bisection)`` is
        added where a guardian pencil missed the root and the end was bisected instead.
    omega : float
        Frequency (rad per time unit) of the eigenvalue on the axis at ``loss`` (0 for a real
        one, ``nan`` when the range is held).
    pieces : tuple of PieceCertificate
        The pieces examined, from the range's start.
    degree : int
        Degree in V of the family's matrices between breakpoints.
    wall_time : float
        Seconds.
    """

    __repr__ = result_repr

    lower: float | None
    upper: float | None
    stable_at_start: bool
    speed_range: tuple
    holds_range: bool
    loss: float | None
    crossing: str
    omega: float
    pieces: tuple
    degree: int
    wall_time: float

    def covers(self, lo: float, hi: float) -> bool:
        """True when every speed of ``[lo, hi]`` is certified stable.

        Parameters
        ----------
        lo, hi : float
            Speeds, ``lo <= hi``.

        Returns
        -------
        bool
        """
        if self.lower is None:
            return False
        low_ok = lo > self.lower or (lo == self.lower and self.stable_at_start)
        high_ok = hi < self.upper or (hi == self.upper and self.holds_range)
        return bool(low_ok and high_ok)


def _shift(coef: list, t0: float) -> list:
    """Coefficients of ``p(t0 + δ)`` in δ from those of ``p(t)`` (binomial re-expansion)."""
    d = len(coef) - 1
    return [sum(math.comb(k, j) * t0 ** (k - j) * coef[k] for k in range(j, d + 1))
            for j in range(d + 1)]


def _horner(coef: list, t: float) -> np.ndarray:
    out = coef[-1].copy()
    for c in coef[-2::-1]:
        out = out * t + c
    return out


def _perron_bound(N: np.ndarray, iterations: int = 8) -> float:
    """An upper bound of the spectral radius of a nonnegative matrix (Collatz–Wielandt:
    ``ρ(N) <= max_i (N x)_i / x_i`` for any positive x; x from a few power iterations)."""
    x = np.ones(N.shape[0])
    for _ in range(iterations):
        y = N @ x + 1e-300
        x = y / y.max()
    x = np.maximum(x, 1e-12)
    return float(np.max((N @ x) / x))


class _ClosedLoop:
    """The controller, its sign and the used channels; closes the loop on plant matrices."""

    def __init__(self, family, K: control.StateSpace, controls, measurements, sign: float):
        self.family, self.sign = family, float(sign)
        self.controls, self.measurements = tuple(controls), tuple(measurements)
        self.Ak, self.Bk, self.Ck, self.Dk = ssdata(as_statespace(K, "the controller"))
        self.strictly_proper = not np.any(self.Dk)
        # the side of the algebraic loop: the controls' unless the measurements are fewer
        k_u, k_y = self.Dk.shape
        self.side = "u" if self.strictly_proper or k_u <= k_y else "y"

    def plant(self, V: float) -> tuple:
        """``(A, B2, C2, D22)`` of the family at V on the used channels."""
        return ssdata(self.family.control_plant(float(V), self.controls, self.measurements))

    def matrix(self, A, B2, C2, D22):
        """Closed-loop state matrix of ``(x, x_K)``, or None when ``I - s D_K D22`` is
        singular (the loop is not well posed)."""
        P, Q, R, M = self.parts(A, B2, C2, D22)
        if self.strictly_proper:
            return P + Q @ R
        if np.linalg.cond(M) > 1e12:
            return None
        return P + Q @ np.linalg.solve(M, R)

    def parts(self, A, B2, C2, D22, constant: bool = True) -> tuple:
        """``(P, Q, R, M)`` of the module docstring on :attr:`side`; with
        ``constant=False`` the terms that do not involve the plant (``A_K``, ``B_K``,
        ``C_K``, ``I``) are left out, as in a coefficient of ``t^j``, ``j >= 1``."""
        s, Ak, Bk, Ck, Dk = self.sign, self.Ak, self.Bk, self.Ck, self.Dk
        c = 1.0 if constant else 0.0
        n, nk = A.shape[0], Ak.shape[0]
        if self.side == "u":
            P = np.block([[A, np.zeros((n, nk))], [Bk @ C2, c * Ak]])
            Q = np.vstack([B2, Bk @ D22])
            R = s * np.hstack([Dk @ C2, c * Ck])
            M = c * np.eye(B2.shape[1]) - s * Dk @ D22
        else:
            P = np.block([[A, s * B2 @ Ck], [np.zeros((nk, n)), c * Ak]])
            Q = np.vstack([s * B2 @ Dk, c * Bk])
            R = np.hstack([C2, s * D22 @ Ck])
            M = c * np.eye(C2.shape[0]) - s * D22 @ Dk
        return P, Q, R, M

    def coefficients(self, coef: list) -> list:
        """``[(P_j, Q_j, R_j, M_j)]`` of a plant polynomial whose A, B2, C2, D22 have the
        coefficient lists ``coef``."""
        return [self.parts(*[c[j] for c in coef], constant=(j == 0))
                for j in range(len(coef[0]))]


class _Piece:
    """One polynomial piece ``[a, b]`` of the family, in ``t = (V - a)/(b - a)``."""

    def __init__(self, loop: _ClosedLoop, a: float, b: float, degree: int, fit_tol: float):
        self.loop, self.a, self.b, self.d = loop, float(a), float(b), int(degree)
        d = self.d
        # Chebyshev nodes: inside the piece (a family may be undefined at its ends, e.g. a
        # truth at V = 0) and well conditioned
        nodes = 0.5 * (1.0 - np.cos((2 * np.arange(d + 1) + 1) * math.pi / (2 * d + 2)))
        samples = [loop.plant(self.speed(t)) for t in nodes]
        vander = np.vander(nodes, d + 1, increasing=True)
        self.coef = []            # coefficient lists of A, B2, C2, D22 in t
        for i in range(4):
            stack = np.stack([s[i].ravel() for s in samples])
            c = np.linalg.solve(vander, stack)
            self.coef.append([c[j].reshape(samples[0][i].shape) for j in range(d + 1)])
        spare = 0.5 / (d + 1) * (1.0 + 1.0 / math.pi)
        true = loop.plant(self.speed(spare))
        scale = max(max(np.linalg.norm(M) for M in s) for s in samples + [true])
        misfit = max(np.linalg.norm(F - T) for F, T in zip(self.plant(spare), true))
        misfit /= max(scale, 1e-300)
        if misfit > fit_tol:
            raise ConfigError(
                f"{loop.family.name}: between V = {self.a:g} and {self.b:g} the plant is not a "
                f"polynomial of degree {d} in V as the family declares (speed_degree = {d}; "
                f"relative misfit {misfit:.3g} at V = {self.speed(spare):.6g}); fix the "
                "family's speed_degree / breakpoints, or pass degree=")
        self.pqrm = loop.coefficients(self.coef)
        self.n = self.pqrm[0][0].shape[0]

    def speed(self, t: float) -> float:
        return self.a + float(t) * (self.b - self.a)

    def plant(self, t: float) -> tuple:
        return tuple(_horner(c, t) for c in self.coef)

    def matrix(self, t: float):
        return self.loop.matrix(*self.plant(t))

    def stable(self, t: float) -> bool:
        At = self.matrix(t)
        return At is not None and spectral_abscissa(At) < 0

    # ------------------------------------------------------------ eigenvalue inclusion
    def taylor(self, t: float):
        """``(A0, A1, f)``: ``A_cl(t + δ) = A0 + δ A1 + F(δ)`` with ``‖F(δ)‖₂ <= f(h)`` on
        ``0 <= δ <= h`` (majorant series of the polynomial and Neumann-series factors)."""
        P, Q, R, M = (_shift([c[i] for c in self.pqrm], t) for i in range(4))
        nrm = [[float(np.linalg.norm(X, 2)) if X.size else 0.0 for X in Y]
               for Y in (P, Q, R, M)]
        p, q, r, m = nrm
        if self.loop.strictly_proper:          # M = I, R = s [0, C_K] is constant
            A0 = P[0] + Q[0] @ R[0]
            A1 = P[1] + Q[1] @ R[0]
            rest = [p[j] + q[j] * r[0] for j in range(2, len(P))]

            def f(h):
                return sum(c * h ** (j + 2) for j, c in enumerate(rest))
            return A0, A1, f
        if np.linalg.cond(M[0]) > 1e12:
            return None
        Phi0 = np.linalg.inv(M[0])
        A0 = P[0] + Q[0] @ Phi0 @ R[0]
        A1 = (P[1] + Q[1] @ Phi0 @ R[0] + Q[0] @ Phi0 @ R[1]
              - Q[0] @ Phi0 @ M[1] @ Phi0 @ R[0])
        phi0 = float(np.linalg.norm(Phi0, 2))

        def f(h):
            mh = sum(m[j] * h ** j for j in range(1, len(m)))
            if phi0 * mh >= 1:
                return math.inf
            qh = sum(q[j] * h ** j for j in range(len(q)))
            rh = sum(r[j] * h ** j for j in range(len(r)))
            whole = qh * phi0 / (1 - phi0 * mh) * rh
            first = q[0] * phi0 * r[0] + h * (q[1] * phi0 * r[0] + q[0] * phi0 ** 2 * m[1]
                                              * r[0] + q[0] * phi0 * r[1])
            return max(whole - first, 0.0) + sum(p[j] * h ** j for j in range(2, len(p)))
        return A0, A1, f

    def step(self, t: float, h_max: float) -> float:
        """The largest h (<= ``h_max``) with the loop proved stable on ``[t, t + h]``; 0
        when none is found (the loop is not stable at t, or the bound is too loose)."""
        ty = self.taylor(t)
        if ty is None:
            return 0.0
        A0, A1, f = ty
        lam, V = np.linalg.eig(A0)
        if np.max(lam.real) >= 0:
            return 0.0
        try:
            Vinv = np.linalg.inv(V)
        except np.linalg.LinAlgError:
            return 0.0
        n = lam.size
        E = Vinv @ A1 @ V
        aN0 = np.abs(Vinv @ A0 @ V - np.diag(lam))       # the decomposition's residual
        gap = lam[None, :] - lam[:, None]
        apart = np.abs(gap) > _CLUSTER_TOL * (1.0 + np.abs(lam)[:, None])
        G = np.where(apart, E / np.where(apart, gap, 1.0), 0.0)
        aG, aE = np.abs(G), np.abs(E)
        aEc = np.where(apart, 0.0, aE)
        aEG = aE @ aG
        rho = _perron_bound(aG)
        lin = np.maximum(0.0, E.diagonal().real) + aEc.sum(1) - np.abs(E.diagonal())
        ones = np.ones(n)
        eG, eEc, eN0 = aEG @ ones, aEc @ ones, aN0 @ ones
        kappa = float(np.linalg.norm(V) * np.linalg.norm(Vinv))
        gF = float(np.linalg.norm(G))
        eye = np.eye(n)

        def ok(h: float) -> bool:
            if h * rho >= 1.0:
                return False
            fh = f(h)
            if fh > 0 and h * gF >= 1.0:
                return False
            W = np.linalg.inv(eye - h * aG)             # >= |X⁻¹| entrywise
            rem = h * h * (eG + aG @ (W @ (eEc + h * eG)))
            res = W @ (aN0 @ ((eye + h * aG) @ ones)) if aN0.any() else 0.0 * eN0
            extra = 0.0
            if fh > 0:
                extra = math.sqrt(n) * (1 + h * gF) / (1 - h * gF) * kappa * fh
            return bool(np.all(lam.real + h * lin + rem + res + extra < 0))

        # first-order bound (an upper bound of the step), then shrink and bisect
        with np.errstate(divide="ignore"):
            h = float(np.min(np.where(lin > 0, -lam.real / lin, np.inf)))
        h = min(h, h_max, 0.999 / rho if rho > 0 else math.inf)
        if ok(h):
            return h
        hi, lo = h, 0.5 * h
        while not ok(lo):              # shrink until a step holds, then refine it
            hi, lo = lo, 0.5 * lo
            if lo < 1e-14:
                return 0.0
        for _ in range(6):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if ok(mid) else (lo, mid)
        return lo

    def chain(self, t: float, budget: int, xtol: float) -> tuple[float, int, str]:
        """Chain inclusion steps from ``t``: ``(t reached, steps, status)``, status
        ``"end"`` (the piece is covered), ``"loss"`` (the loop is unstable within ``xtol``
        above the t reached) or ``"stalled"``."""
        steps, start = 0, t
        while steps < budget:
            h = self.step(t, 1.0 - t)
            steps += 1
            if h >= 1.0 - t:
                return 1.0, steps, "end"
            if steps >= 20 and (1.0 - t) * steps > (budget - steps) * (t - start):
                return t, steps, "stalled"       # at this pace the budget would not do
            if h < xtol:
                # the steps have shrunk onto a loss of stability, or the bound is too loose
                probe = min(1.0, t + _PROBE * xtol)
                return t, steps, ("stalled" if self.stable(probe) else "loss")
            t += h
        return t, steps, "stalled"

    # ---------------------------------------------------------------- guardian map
    def candidates(self, t0: float, imag_tol: float) -> tuple[dict, int]:
        """Real roots t of the guardian pencils (expanded about ``t0``): ``{t: kind}``."""
        lp = self.loop
        n = self.n
        d = len(self.pqrm) - 1
        P, Q, R, M = (_shift([c[i] for c in self.pqrm], t0) for i in range(4))
        kinds: dict[float, str] = {}
        if lp.strictly_proper:
            acl = [P[j] + Q[j] @ R[0] for j in range(d + 1)]
            cplx = _pencil_roots(*[bialternate_sum(X) for X in acl], imag_tol=imag_tol)
            real = _pencil_roots(*acl, imag_tol=imag_tol)
            ill, order = np.zeros(0), n * (n - 1) // 2
        else:
            eye = np.eye(n)
            N = [np.block([[bialternate_sum(P[j]), _qop(Q[j], n)],
                           [-_rop(R[j], n), np.kron(M[j], eye)]]) for j in range(d + 1)]
            cplx = _pencil_roots(*N, imag_tol=imag_tol)
            real = _pencil_roots(*[np.block([[P[j], Q[j]], [-R[j], M[j]]])
                                   for j in range(d + 1)], imag_tol=imag_tol)
            ill = _pencil_roots(*M, imag_tol=imag_tol)
            order = n * (n - 1) // 2 + M[0].shape[0] * n
        for roots, kind in ((cplx, "complex pair"), (real, "real through 0"),
                            (ill, "ill-posed")):
            kinds.update({float(t0 + x): kind for x in roots})
        return kinds, order * d

    def expansion_point(self) -> float:
        """A t where the guardian pencils are far from singular (no eigenvalue pair near
        ``λ_i + λ_j = 0``, well posed), for their expansion."""
        best, score = 0.5, -1.0
        for t0 in (0.5, 0.5 + 0.5 / math.pi, 0.5 - 0.5 / math.e, 0.25, 0.75):
            At = self.matrix(t0)
            if At is None:
                continue
            lam = np.linalg.eigvals(At)
            sums = np.abs(lam[:, None] + lam[None, :])[np.triu_indices(lam.size, 1)]
            sc = float(min(sums.min(initial=np.inf), np.abs(lam).min(initial=np.inf)))
            sc /= max(1.0, float(np.abs(lam).max(initial=1.0)))
            if sc > score:
                best, score = t0, sc
            if sc > 1e-6:
                break
        return best

    def guardian(self, t: float, imag_tol: float, check_tol: float) -> tuple:
        """From ``t`` (certified stable, or the range's marginal start), the end of stability
        in the piece: ``(end t or None when stable to 1, kind, pencil order)``."""
        kinds, order = self.candidates(self.expansion_point(), imag_tol)
        above = sorted(c for c in kinds if t + _END_TOL < c <= 1.0 + _END_TOL)
        nominal = t
        At = self.matrix(t)
        if At is None or not is_hurwitz(At)[0]:
            # a marginal start: walk from the middle of the first stretch, if it is stable
            nominal = 0.5 * (t + min(above[0] if above else 1.0, 1.0))
            if not self.stable(nominal):
                return t, "unstable at start", order
        offsets = {c - nominal: kind for c, kind in kinds.items()}
        si = _pick_ends(offsets, lambda x: self.matrix(nominal + x), nominal, "guardian",
                        check_tol)
        if si.lower > t + _END_TOL:          # unstable between the start and the stretch
            return t, "unstable at start", order
        if si.upper > 1.0 + _END_TOL:
            return None, "none", order
        return min(si.upper, 1.0), si.crossing_upper, order


def _qop(Q: np.ndarray, n: int) -> np.ndarray:
    """``Y ↦ (Q Y - Yᵀ Qᵀ)[p, q]`` (p > q) for ``Y`` (k × n) flattened by rows."""
    p_idx, q_idx = np.tril_indices(n, -1)
    k = Q.shape[1]
    out = np.zeros((p_idx.size, k * n))
    for b in range(n):
        cols = np.arange(k) * n + b
        rq, rp = np.flatnonzero(q_idx == b), np.flatnonzero(p_idx == b)
        out[np.ix_(rq, cols)] += Q[p_idx[rq], :]
        out[np.ix_(rp, cols)] -= Q[q_idx[rp], :]
    return out


def _rop(R: np.ndarray, n: int) -> np.ndarray:
    """``X ↦ R X`` (flattened by rows) on the antisymmetric basis
    ``e_p e_qᵀ - e_q e_pᵀ`` (p > q) of :func:`casflutter.verify.bialternate_sum`."""
    p_idx, q_idx = np.tril_indices(n, -1)
    k = R.shape[0]
    out = np.zeros((k * n, p_idx.size))
    cols = np.arange(p_idx.size)
    for i in range(k):
        out[i * n + q_idx, cols] += R[i, p_idx]
        out[i * n + p_idx, cols] -= R[i, q_idx]
    return out


def _loss(piece: _Piece, t: float, t_unstable: float) -> tuple[float, float]:
    """The first speed found unstable above the certified ``t`` (bisection of the spectral
    abscissa to rounding) and the frequency of the eigenvalue crossing there."""
    lo, hi = t, t_unstable
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        lo, hi = (mid, hi) if piece.stable(mid) else (lo, mid)
    At = piece.matrix(hi)
    omega = math.nan
    if At is not None:
        lam = np.linalg.eigvals(At)
        omega = float(abs(lam[np.argmax(lam.real)].imag))
    return piece.speed(hi), omega


def certified_interval(family, K: control.StateSpace, controls, measurements, sign: float,
                       speed_range: tuple, *, degree: int | None = None,
                       fit_tol: float = 1e-8, budget: int = 400, xtol: float = 1e-9,
                       imag_tol: float = 1e-6, check_tol: float = 1e-9,
                       method: str = "auto") -> CertifiedInterval:
    """The certified stable interval of ``u = sign K y`` on a family, from the range's start.

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The plant family.
    K : control.StateSpace or array_like
        Continuous controller from ``measurements`` to ``controls`` (a matrix is a static
        gain).
    controls, measurements : sequence of str
        The family's inputs K drives and outputs K reads, in K's order.
    sign : float
        ``+1`` (``u = +K y``) or ``-1`` (``u = -K y``).
    speed_range : (float, float)
        Finite range inside the family's.
    degree : int, optional
        Degree in V of the family's matrices between breakpoints (default
        ``family.speed_degree``).
    fit_tol : float
        Largest relative misfit of the polynomial pieces (checked at a spare speed each).
    budget : int
        Eigenvalue-inclusion steps per piece before its guardian map is solved.
    xtol : float
        Fraction of a piece: a chain step shorter than this ends the chain, which then
        stops (the loop is shown unstable ``1000 xtol`` further on: the certified interval
        ends within that of the loss of stability) or hands the piece to the guardian map.
    imag_tol : float
        A guardian root counts as real when its imaginary part is below this fraction of
        its modulus.
    check_tol : float
        Relative width (in t) to which an end a guardian pencil missed is bisected.
    method : {"auto", "guardian"}
        ``"auto"``: the eigenvalue-inclusion chain, the guardian map where it stalls (and
        from a marginally stable start); ``"guardian"``: the guardian map on every piece
        (slower: O(n⁶) per piece).

    Returns
    -------
    CertifiedInterval

    Raises
    ------
    ConfigError
        A family without a known degree in V, a range that is not finite inside the
        family's, or pieces that are not polynomials of the declared degree.
    """
    t_start = time.perf_counter()
    deg = family.speed_degree if degree is None else degree
    if deg is None or int(deg) < 1:
        raise ConfigError(f"{family.name}: speed_degree is {deg!r}: a certificate needs the "
                          "family's matrices to be polynomials in V between breakpoints; "
                          "pass degree=D when they are")
    if method not in ("auto", "guardian"):
        raise ConfigError(f"method = {method!r}: 'auto' or 'guardian'")
    lo, hi = (float(v) for v in speed_range)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ConfigError(f"speed_range = {speed_range!r}: give a finite range lo < hi")
    lo, hi = family.check_speed(lo, "lo"), family.check_speed(hi, "hi")
    loop = _ClosedLoop(family, K, controls, measurements, sign)
    ends = [lo] + sorted(b for b in family.breakpoints if lo < b < hi) + [hi]
    pieces = []
    upper, loss, kind, omega, stable_at_start, empty = hi, None, "none", math.nan, True, False
    for i, (a, b) in enumerate(zip(ends[:-1], ends[1:])):
        t0 = time.perf_counter()
        piece = _Piece(loop, a, b, int(deg), fit_tol)
        A_start = piece.matrix(0.0)
        hurwitz = A_start is not None and is_hurwitz(A_start)[0]
        if i == 0:
            stable_at_start = hurwitz
        elif not hurwitz:                 # lost exactly at the breakpoint
            pieces.append(PieceCertificate(a, b, "unstable at start", a, 0, 0,
                                           time.perf_counter() - t0))
            upper, loss, kind = a, a, "breakpoint"
            omega = _loss(piece, 0.0, 0.0)[1]
            break
        t, steps, status, order, how = 0.0, 0, "stalled", 0, "inclusion"
        if hurwitz and method == "auto":
            t, steps, status = piece.chain(0.0, budget, xtol)
        if status == "loss":
            upper = piece.speed(t)
            loss, omega = _loss(piece, t, min(1.0, t + _PROBE * xtol))
            kind = "complex pair" if omega > 0 else "real through 0"
        elif status == "stalled":
            how = "guardian"
            end, kind, order = piece.guardian(t, imag_tol, check_tol)
            if end is not None:
                if kind == "unstable at start":
                    empty = i == 0 and t == 0.0
                upper = loss = piece.speed(end)
                omega = _loss(piece, end, end)[1]
                status = "loss"
        pieces.append(PieceCertificate(a, b, how, upper if status == "loss" else b, steps,
                                       order, time.perf_counter() - t0))
        _log.debug("piece [%g, %g]: %s, %d steps, pencil %d", a, b, how, steps, order)
        if status == "loss":
            break
    holds = loss is None
    if kind == "bisection":           # a guardian root missed, the end bisected instead
        kind = ("complex pair" if omega > 0 else "real through 0") + " (bisection)"
    if empty:
        return CertifiedInterval(None, None, False, (lo, hi), False, lo, "unstable at start",
                                 omega, tuple(pieces), int(deg), time.perf_counter() - t_start)
    return CertifiedInterval(
        lower=lo, upper=upper, stable_at_start=bool(stable_at_start), speed_range=(lo, hi),
        holds_range=holds, loss=loss, crossing=kind, omega=omega, pieces=tuple(pieces),
        degree=int(deg), wall_time=time.perf_counter() - t_start)
