"""Intervals of the speed parameter on which the closed loop is certified stable.

* :func:`small_gain_interval`: the small-gain certificate of Lum et al. (2016),
  eq. (10) and (16): stable for ``|ΔV| < 1/γ`` with ``V² = Vf² + ΔV``.
* :func:`stability_interval`: the *exact* maximal interval of ``δ`` around a nominal
  value on which ``A(δ) = A0 + δ A1`` is Hurwitz (guardian maps: Fu & Barmish 1988;
  Saydy, Tits & Abed 1990).  An eigenvalue crosses the imaginary axis only where
  ``det(2A(δ) ⊙ I) = 0`` (a complex pair, λ_i + λ_j = 0) or ``det A(δ) = 0`` (a real
  eigenvalue through 0).  ``2A ⊙ I`` (the bialternate sum, order n(n-1)/2) is linear in
  ``A``, so the candidates are eigenvalues of two generalised pencils.
* :func:`feedback_stability_interval`: the same for the loop ``wf = -δ zf`` closed around
  a system with feedthrough (eq. 15), where ``A(δ)`` is rational in δ; linearised
  exactly by a Sylvester-operator pencil of order ``n(n-1)/2 + k n``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError, DimensionError
from ._common import NotHurwitzError, is_hurwitz, spectral_abscissa

__all__ = ["small_gain_interval", "StabilityInterval", "stability_interval",
           "feedback_stability_interval", "polynomial_stability_interval",
           "speed_family_interval", "bialternate_sum", "speed_interval"]


def small_gain_interval(gamma: float, Vf: float) -> tuple[float, float]:
    """Speed-index interval certified by the small-gain theorem, eq. (10), (16).

    With ``V² = Vf² + ΔV`` and stability for ``|ΔV| < 1/γ``:
    ``V ∈ (sqrt(max(0, Vf² - 1/γ)), sqrt(Vf² + 1/γ))``.

    Parameters
    ----------
    gamma : float
        H∞ norm of the closed loop seen by the ΔV channel (``γ ≥ 0``; ``inf`` gives the
        empty interval ``(Vf, Vf)``, ``0`` gives ``(0, inf)``).
    Vf : float
        Nominal (flutter) speed index, ``Vf ≥ 0``.

    Returns
    -------
    (V_lo, V_hi) : tuple of float
    """
    if not gamma >= 0 or not Vf >= 0:
        raise ConfigError(f"need gamma >= 0 and Vf >= 0, got gamma={gamma!r}, Vf={Vf!r}")
    r = math.inf if gamma == 0 else 1.0 / gamma
    return speed_interval(-r, r, Vf)


def speed_interval(dv_lo: float, dv_hi: float, Vf: float) -> tuple[float, float]:
    """Map a ΔV interval to the speed-index interval, ``V = sqrt(Vf² + ΔV) ≥ 0`` (eq. 10).

    A lower end ``Vf² + ΔV ≤ 0`` gives ``V_lo = 0``.
    """
    lo = math.sqrt(max(0.0, Vf**2 + dv_lo))
    hi = math.inf if math.isinf(dv_hi) else math.sqrt(max(0.0, Vf**2 + dv_hi))
    return lo, hi


def bialternate_sum(A: np.ndarray) -> np.ndarray:
    """The bialternate sum ``2A ⊙ I`` of order ``n(n-1)/2``.

    It is ``A ⊗ I + I ⊗ A`` restricted to the antisymmetric matrices
    (``X ↦ A X + X Aᵀ``) in the orthonormal basis ``(e_p e_qᵀ - e_q e_pᵀ)/√2``,
    ``p > q``; its eigenvalues are ``λ_i + λ_j``, ``i < j``.  Linear in ``A``.
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    p_idx, q_idx = np.tril_indices(n, -1)
    N = p_idx.size
    M = np.zeros((N, N))
    for k in range(N):
        r, s = p_idx[k], q_idx[k]
        # With E = e_r e_sᵀ - e_s e_rᵀ: A E + E Aᵀ = X - Xᵀ, X = A E (E is antisymmetric);
        # its coordinate on the unit basis element of (p, q) is (X - Xᵀ)[p, q].
        X = np.zeros((n, n))
        X[:, s] = A[:, r]
        X[:, r] -= A[:, s]
        Y = X - X.T
        M[:, k] = Y[p_idx, q_idx]
    return M


@dataclass(frozen=True)
class StabilityInterval:
    """Maximal open interval ``(lower, upper)`` of δ around ``nominal`` on which
    ``A0 + δ A1`` is Hurwitz.

    Attributes
    ----------
    lower, upper : float
        Ends of the interval (``-inf``/``inf`` when no crossing exists on that side).
    nominal : float
        The δ the interval was grown from.
    method : str
        ``"bialternate"`` (pencils of ``2A ⊙ I`` and ``A``).
    candidates : tuple of float
        All real candidate values of δ found (sorted), genuine or spurious.
    abscissa_lower, abscissa_upper : float
        Spectral abscissa of ``A(δ)`` at each finite end (≈ 0: the check that the
        end is a genuine crossing); ``nan`` for an infinite end.
    crossing_lower, crossing_upper : str
        ``"complex pair"``, ``"real through 0"`` or ``"none"``.
    """

    __repr__ = result_repr

    lower: float
    upper: float
    nominal: float
    method: str
    candidates: tuple[float, ...]
    abscissa_lower: float
    abscissa_upper: float
    crossing_lower: str
    crossing_upper: str

    def contains(self, delta: float) -> bool:
        """True when ``lower < delta < upper``."""
        return self.lower < delta < self.upper

    @property
    def width(self) -> float:
        """``upper - lower``."""
        return self.upper - self.lower


def _pencil_roots(M0: np.ndarray, *Ms: np.ndarray, imag_tol: float) -> np.ndarray:
    """Real finite δ with ``det(M0 + δ M1 + … + δ^d Md) = 0``, ``M0`` nonsingular.

    ``μ = 1/δ`` are the eigenvalues of the block companion matrix of the reversed
    polynomial, first block row ``-M0⁻¹ [M1 … Md]`` (for ``d = 1`` simply
    ``eig(-M0⁻¹ M1)``); infinite roots map to μ = 0.
    """
    n = M0.shape[0]
    if n == 0:
        return np.zeros(0)
    top = -np.linalg.solve(M0, np.hstack(Ms))
    d = len(Ms)
    companion = np.zeros((d * n, d * n))
    companion[:n] = top
    companion[n:, :-n] = np.eye((d - 1) * n)
    mu = np.linalg.eigvals(companion)
    scale = max(1.0, float(np.max(np.abs(mu)))) if mu.size else 1.0
    mu = mu[np.abs(mu) > 1e-13 * scale]
    real = np.abs(mu.imag) <= imag_tol * np.abs(mu)
    return np.sort(1.0 / mu[real].real)


def stability_interval(A0: np.ndarray, A1: np.ndarray, *, nominal: float = 0.0,
                       imag_tol: float = 1e-6, check_tol: float = 1e-6
                       ) -> StabilityInterval:
    """Exact maximal open interval of δ containing ``nominal`` with ``A0 + δ A1`` Hurwitz.

    Parameters
    ----------
    A0, A1 : (n, n) array_like
        The affine family ``A(δ) = A0 + δ A1``; for the closed loop of eq. (14)-(15),
        ``A0 = Acl`` and ``A1 = -B_wf C_zf`` (δ = ΔV).
    nominal : float
        A value with ``A(nominal)`` Hurwitz.
    imag_tol : float
        A pencil eigenvalue μ counts as real when ``|Im μ| ≤ imag_tol |μ|``.
    check_tol : float
        Relative width to which an end the pencils missed is bisected (the ends are chosen
        by the stability of the pieces between candidates, see :func:`_pick_ends`).

    Returns
    -------
    StabilityInterval

    Raises
    ------
    DimensionError
        If ``A0`` and ``A1`` are not square of the same size.
    NotHurwitzError
        If ``A(nominal)`` is not Hurwitz (no interval around it exists).
    """
    A0 = np.atleast_2d(np.asarray(A0, dtype=float))
    A1 = np.atleast_2d(np.asarray(A1, dtype=float))
    if A0.ndim != 2 or A0.shape[0] != A0.shape[1] or A0.shape != A1.shape:
        raise DimensionError(f"A0 and A1 must be square of equal size, got {A0.shape} "
                             f"and {A1.shape}")
    An = A0 + nominal * A1
    stable, alpha = is_hurwitz(An)
    if not stable:
        raise NotHurwitzError(
            f"A0 + nominal*A1 (nominal={nominal}) is not Hurwitz (spectral abscissa "
            f"{alpha:.6g} >= 0): there is no stability interval around it; pick a "
            "stabilising controller / a nominal value where the loop is stable")
    # δ measured from the nominal value: A(nominal + t) = An + t A1.
    t_cplx = _pencil_roots(bialternate_sum(An), bialternate_sum(A1), imag_tol=imag_tol)
    t_real = _pencil_roots(An, A1, imag_tol=imag_tol)
    kinds = {float(t): "complex pair" for t in t_cplx}
    kinds.update({float(t): "real through 0" for t in t_real})

    def matrix(t: float) -> np.ndarray:
        return An + t * A1

    return _pick_ends(kinds, matrix, nominal, "bialternate", check_tol)


def polynomial_stability_interval(coefficients, *, nominal: float = 0.0,
                                  imag_tol: float = 1e-6, check_tol: float = 1e-6
                                  ) -> StabilityInterval:
    """Exact maximal open interval of δ containing ``nominal`` with ``Σ_k δ^k A_k`` Hurwitz.

    The guardian maps of :func:`stability_interval` for a matrix polynomial: a complex pair
    crosses where ``det(2A(δ) ⊙ I) = 0`` and a real eigenvalue where ``det A(δ) = 0``; the
    bialternate sum is linear in ``A``, so both are polynomial eigenvalue problems in δ,
    solved exactly through their block companion linearisation.  A loop whose state matrix
    is quadratic in the speed index (a truth's strip theory: lags ∝ V, circulatory forces
    ∝ V²) is certified this way in V itself.

    Parameters
    ----------
    coefficients : sequence of (n, n) array_like
        ``A_0, A_1, …, A_d`` (``d >= 1``).
    nominal : float
        A value with ``A(nominal)`` Hurwitz.
    imag_tol, check_tol : float
        As in :func:`stability_interval`.

    Returns
    -------
    StabilityInterval
        ``method = "bialternate-polynomial"``.

    Raises
    ------
    DimensionError
        Fewer than two coefficients, or not all square of one size.
    NotHurwitzError
        If ``A(nominal)`` is not Hurwitz.
    """
    Ak = [np.atleast_2d(np.asarray(M, dtype=float)) for M in coefficients]
    if len(Ak) < 2 or Ak[0].ndim != 2 or Ak[0].shape[0] != Ak[0].shape[1] or \
            any(M.shape != Ak[0].shape for M in Ak):
        raise DimensionError(f"need at least two square coefficient matrices of one size; got "
                             f"shapes {[M.shape for M in Ak]}")
    d = len(Ak) - 1
    # re-expand about the nominal value: A(nominal + t) = Σ_j t^j Â_j,
    # Â_j = Σ_{k>=j} C(k, j) nominal^(k-j) A_k
    shifted = [sum(math.comb(k, j) * nominal ** (k - j) * Ak[k] for k in range(j, d + 1))
               for j in range(d + 1)]
    stable, alpha = is_hurwitz(shifted[0])
    if not stable:
        raise NotHurwitzError(
            f"A(nominal) (nominal={nominal}) is not Hurwitz (spectral abscissa {alpha:.6g} "
            ">= 0): there is no stability interval around it; pick a stabilising controller "
            "/ a nominal value where the loop is stable")
    t_cplx = _pencil_roots(*[bialternate_sum(M) for M in shifted], imag_tol=imag_tol)
    t_real = _pencil_roots(*shifted, imag_tol=imag_tol)
    kinds = {float(t): "complex pair" for t in t_cplx}
    kinds.update({float(t): "real through 0" for t in t_real})

    def matrix(t: float) -> np.ndarray:
        return sum(t ** j * M for j, M in enumerate(shifted))

    return _pick_ends(kinds, matrix, nominal, "bialternate-polynomial", check_tol)


def speed_family_interval(plant_at, controller, nominal: float, *, degree: int = 2,
                          fit_tol: float = 1e-9, imag_tol: float = 1e-6,
                          check_tol: float = 1e-6) -> StabilityInterval:
    """Exact stable speed interval of a plant family closed by one controller, ``v = K zm``.

    For a loop that is not given as the paper's LFT (eq. 14-15), e.g. a truth's own
    linearisation: the closed loop is formed here with python-control (positive feedback,
    paper Fig. 3), its state matrix sampled at ``degree + 3`` speeds around ``nominal``,
    fitted exactly by a polynomial of ``degree`` in V (checked at the two spare speeds),
    and the interval taken by :func:`polynomial_stability_interval`.

    Parameters
    ----------
    plant_at : callable
        ``V -> control.StateSpace`` from the flap command to the sensors (one input), with
        the same states at every speed.
    controller : control.StateSpace
        ``K(s)``, sensors to flap.
    nominal : float
        Speed index (> 0) at which the closed loop is stable.
    degree : int
        Degree in V of the closed-loop state matrix (2 for strip theory).
    fit_tol : float
        Largest relative misfit at the spare speeds for the loop to count as a polynomial.
    imag_tol, check_tol : float
        As in :func:`stability_interval`.

    Returns
    -------
    StabilityInterval
        In V (lower end at least 0: a stable loop down to V = 0 has ``lower = 0``);
        ``method = "bialternate-polynomial"``.

    Raises
    ------
    ConfigError
        ``nominal`` not > 0, ``degree`` < 1, or a closed loop that is not a polynomial of
        that degree in V (the misfit is named).
    NotHurwitzError
        The loop is not stable at ``nominal``.
    """
    if not (nominal > 0 and math.isfinite(nominal)) or int(degree) < 1:
        raise ConfigError(f"need nominal > 0 and degree >= 1; got nominal={nominal!r}, "
                          f"degree={degree!r}")
    d = int(degree)
    speeds = nominal * (1.0 + 0.5 * (np.arange(d + 3) - (d + 2) / 2) / (d + 2))
    K = control.ss(controller)
    mats = [np.asarray(control.feedback(plant_at(float(V)), K, sign=1).A, dtype=float)
            for V in speeds]
    n = mats[0].shape[0]
    vander = np.vander(speeds[:d + 1], d + 1, increasing=True)
    stack = np.stack([M.ravel() for M in mats[:d + 1]])
    coef = np.linalg.solve(vander, stack)
    for V, M in zip(speeds[d + 1:], mats[d + 1:]):
        fit = sum(V ** j * coef[j] for j in range(d + 1)).reshape(n, n)
        misfit = np.linalg.norm(fit - M) / max(np.linalg.norm(M), 1e-300)
        if misfit > fit_tol:
            raise ConfigError(f"the closed loop is not a polynomial of degree {d} in V "
                              f"(relative misfit {misfit:.3g} at V = {V:.4g}); "
                              "pass the right degree")
    r = polynomial_stability_interval([c.reshape(n, n) for c in coef], nominal=nominal,
                                      imag_tol=imag_tol, check_tol=check_tol)
    # speeds are >= 0; an end within the location tolerance of V = 0 (where lag states
    # scaled by V give eigenvalues through 0) is V = 0
    if r.lower <= check_tol * nominal:
        r = replace(r, lower=0.0)
    return r


def _pick_ends(kinds: dict[float, str], matrix, nominal: float, method: str,
               check_tol: float) -> StabilityInterval:
    """The interval's ends among the candidates (offsets from ``nominal``; ``matrix(t)`` is
    ``A(nominal + t)``, or None where the loop is not well posed).

    Stability can change only at a candidate, so between two consecutive candidates the loop
    is stable everywhere or nowhere: each open piece is judged at its midpoint, walking out
    from the nominal value, and an end is the first candidate beyond which the loop is not
    stable.  A candidate where nothing crosses (a numerical root of an ill-conditioned
    pencil) only splits a stable piece in two and is passed over.  Judging the pieces, not
    the candidates, keeps the decision away from the ends themselves, where the spectral
    abscissa is zero to within the eigenvalue error of ``A`` (large when ``||A||`` is).  In
    the first piece found unstable the boundary is located by bisection to ``check_tol``
    relative width, on the stable side: it is the candidate where the piece starts when the
    pencils found the crossing, and otherwise (an ill-conditioned pencil that missed it, whose
    eigenvalue came out complex) the end is the bisected point, labelled ``"bisection"``.
    """
    cands = np.array(sorted(kinds))

    def stable(t: float) -> bool:
        At = matrix(t)
        return At is not None and spectral_abscissa(At) < 0

    def abscissa(t: float) -> float:
        At = matrix(t)
        return math.nan if At is None else spectral_abscissa(At)

    ends = {}
    for side, sign, pool in (("upper", 1.0, cands[cands > 0]),
                             ("lower", -1.0, cands[cands < 0][::-1])):
        end = (sign * math.inf, math.nan, "none")
        prev = 0.0
        for t in list(pool) + [None]:
            far = prev + sign * max(1.0, 2 * abs(prev)) if t is None else float(t)
            if not stable(0.5 * (prev + far)):
                # the stability boundary lies in [prev, midpoint): at the candidate prev when
                # the pencils found it, elsewhere when they missed it; bisection finds it
                # either way, on the stable side
                lo, hi = prev, 0.5 * (prev + far)
                while abs(hi - lo) > check_tol * max(1.0, abs(hi)):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if stable(mid) else (lo, mid)
                at_candidate = prev != 0.0 and abs(lo - prev) <= 4 * check_tol * max(1.0,
                                                                                     abs(prev))
                end = ((prev, abscissa(prev), kinds[prev]) if at_candidate
                       else (lo, abscissa(lo), "bisection"))
                break
            if t is None:
                break
            prev = float(t)
            if matrix(prev) is None:       # loop not well posed here: a genuine end
                end = (prev, math.nan, kinds[prev])
                break
        ends[side] = end
    (tu, au, ku), (tl, al, kl) = ends["upper"], ends["lower"]
    return StabilityInterval(
        lower=nominal + tl, upper=nominal + tu, nominal=float(nominal),
        method=method, candidates=tuple(float(nominal + c) for c in cands),
        abscissa_lower=al, abscissa_upper=au, crossing_lower=kl, crossing_upper=ku)


def feedback_stability_interval(A: np.ndarray, B: np.ndarray, C: np.ndarray,
                                D: np.ndarray | None = None, *, imag_tol: float = 1e-6,
                                check_tol: float = 1e-6) -> StabilityInterval:
    """Exact maximal interval of δ around 0 on which the loop ``w = -δ z`` closed around
    ``(A, B, C, D)`` is well posed and stable (eq. 15 with ``δ = ΔV``).

    The closed loop is ``A(δ) = A - B Φ(δ) C`` with ``Φ(δ) = δ (I + δ D)⁻¹``: affine in δ
    when ``D = 0`` (then equal to :func:`stability_interval` with ``A1 = -B C``),
    rational otherwise (e.g. accelerometer measurements with a controller
    feedthrough).  Both cases are linearised exactly: an eigenvalue pair
    ``λ_i + λ_j = 0`` means that ``A(δ) X + X A(δ)ᵀ = 0`` has an antisymmetric solution
    ``X``; with ``Y = Φ(δ) C X`` this is ``A X + X Aᵀ - B Y + Yᵀ Bᵀ = 0`` and
    ``Y + δ (D Y - C X) = 0``, a pencil in δ of order ``n(n-1)/2 + k n``.  A real
    eigenvalue through 0 solves ``A x - B y = 0``, ``y + δ (D y - C x) = 0``.  Values
    with ``det(I + δ D) = 0`` (loop not well posed) are ends as well.

    Parameters
    ----------
    A, B, C : array_like
        ``(n, n)``, ``(n, k)``, ``(k, n)``: the loop seen from the ΔV channel.
    D : array_like, optional
        ``(k, k)`` feedthrough from ``w`` to ``z`` (default 0).
    imag_tol, check_tol : float
        As in :func:`stability_interval`.

    Returns
    -------
    StabilityInterval
        ``method = "bialternate-lft"``; a crossing may also be ``"ill-posed"``.

    Raises
    ------
    DimensionError
        Inconsistent shapes.
    NotHurwitzError
        If ``A`` is not Hurwitz.
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = np.atleast_2d(np.asarray(B, dtype=float))
    C = np.atleast_2d(np.asarray(C, dtype=float))
    n = A.shape[0]
    k = B.shape[1] if B.ndim == 2 else 0
    D = np.zeros((k, k)) if D is None else np.atleast_2d(np.asarray(D, dtype=float))
    if A.shape != (n, n) or B.shape != (n, k) or C.shape != (k, n) or D.shape != (k, k):
        raise DimensionError(f"need A (n,n), B (n,k), C (k,n), D (k,k); got A{A.shape}, "
                             f"B{B.shape}, C{C.shape}, D{D.shape}")
    stable, alpha = is_hurwitz(A)
    if not stable:
        raise NotHurwitzError(
            f"the nominal closed loop (δ = 0) is not Hurwitz (spectral abscissa "
            f"{alpha:.6g} >= 0): there is no stability interval around it")
    p_idx, q_idx = np.tril_indices(n, -1)
    N2 = p_idx.size
    size = N2 + k * n
    N0 = np.zeros((size, size))
    N1 = np.zeros((size, size))
    # columns for the antisymmetric X basis
    for col in range(N2):
        r, s_ = p_idx[col], q_idx[col]
        X = np.zeros((n, n))
        X[r, s_], X[s_, r] = 1.0, -1.0
        S = A @ X + X @ A.T
        N0[:N2, col] = S[p_idx, q_idx]
        N1[N2:, col] = -(C @ X).ravel()
    # columns for Y (k x n), row-major
    for col in range(k * n):
        Y = np.zeros((k, n))
        Y.flat[col] = 1.0
        S = -B @ Y + Y.T @ B.T
        N0[:N2, N2 + col] = S[p_idx, q_idx]
        N0[N2:, N2 + col] = Y.ravel()
        N1[N2:, N2 + col] = (D @ Y).ravel()
    t_cplx = _pencil_roots(N0, N1, imag_tol=imag_tol)
    R0 = np.block([[A, -B], [np.zeros((k, n)), np.eye(k)]])
    R1 = np.block([[np.zeros((n, n)), np.zeros((n, k))], [-C, D]])
    t_real = _pencil_roots(R0, R1, imag_tol=imag_tol)
    lam = np.linalg.eigvals(D) if k else np.zeros(0)
    lam = lam[(np.abs(lam.imag) <= imag_tol * np.abs(lam)) & (np.abs(lam) > 0)]
    t_ill = -1.0 / lam.real
    kinds = {float(t): "complex pair" for t in t_cplx}
    kinds.update({float(t): "real through 0" for t in t_real})
    kinds.update({float(t): "ill-posed" for t in t_ill})
    eye_k = np.eye(k)

    def matrix(t: float):
        M = eye_k + t * D
        if np.linalg.cond(M) > 1e12:
            return None
        return A - B @ np.linalg.solve(M, t * C)

    return _pick_ends(kinds, matrix, 0.0, "bialternate-lft", check_tol)
