"""Rational-function approximation (RFA) of frequency-domain aerodynamics ``Q(ik)``.

The RFA is the linear realisation of a table of generalised aerodynamic forces (see
:mod:`casflutter.data`), as ERA + Tustin is for the identified ROM.  With the
non-dimensional Laplace variable ``p = s b / U`` (``p = ik`` on the imaginary axis):

Roger's method
    ``Q(p) ~= A0 + A1 p + A2 p^2 + sum_j A_{j+2} p / (p + gamma_j)``,
    one full ``N x M`` matrix per lag root ``gamma_j > 0`` (``n_lags * M`` lag states).
Karpel's minimum-state method
    ``Q(p) ~= A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p``,  ``R = -diag(gamma)``,
    one lag state per root, ``D`` ``N x n_lags``, ``E`` ``n_lags x M``.

Both are written in the common form ``A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p`` (for Roger
``R = -diag(gamma_j I_M)``, ``E = [I_M; ...; I_M]``, ``D = [A_3 ... A_{n+2}]``), which is what
:class:`casflutter.aeroelastic.RFASystem` turns into a state space whose lag states scale
with ``U / b``.  ``poly_order`` (0, 1 or 2) keeps ``A0`` only, ``A0, A1`` or all three; 0 gives
a proper RFA, whose frozen Σf (eq. 5) is exact (see ``RFASystem.frozen_sigma_f``).

Fitting is least squares on the real and imaginary parts at the table's ``k``, each element
weighted by the inverse of its RMS magnitude (``weighting="element"``; small elements are
floored at ``element_floor`` of the largest) or uniformly.  The matrices enter linearly given
the lag roots (and, for minimum-state, given ``E``): they are eliminated by variable
projection, a linear least-squares solve written symbolically, and the remaining nonlinear
unknowns -- ``log gamma`` (and ``E`` for minimum-state, rows normalised to unit length) -- are
optimised by Ipopt through :mod:`casflutter._nlp`, minimising the logarithm of the relative
residual, with the roots kept ordered and apart by ``min_separation`` (a ratio) inside
``lag_bounds``.  Roger's optimum seeds the minimum-state fit (``E`` from the rank-one part of
each of Roger's lag matrices).  After the solve the matrices are recomputed by ordinary
linear least squares, and the fit error is reported per element.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from .._format import result_repr
from .._nlp import NLPResult, solve_nlp
from ..data import GAFTable
from ..errors import ConfigError, ConvergenceError, DataError

__all__ = ["RFASettings", "RationalApproximation", "fit_rfa", "fit_roger", "fit_minimum_state"]

log = logging.getLogger("casflutter.realize.rfa")

_METHODS = ("roger", "minimum_state")
_WEIGHTINGS = ("element", "uniform")


@dataclass(frozen=True)
class RFASettings:
    """Settings of :func:`fit_rfa`.

    Parameters
    ----------
    method : {"roger", "minimum_state"}
        Roger's method or Karpel's minimum-state method (module docstring).
    n_lags : int
        Number of lag roots ``gamma_j`` (1..40).
    poly_order : int
        Highest power of ``p`` in the polynomial part: 0 (``A0``), 1 (``A0, A1``) or 2
        (``A0, A1, A2``, the classical form).
    lag_bounds : (float, float), optional
        Bounds of the lag roots (reduced-frequency units); default
        ``(0.001 k_max, 2 k_max)`` of the fitted table.
    initial_lags : tuple of float, optional
        Starting lag roots (``n_lags`` values inside the bounds); default log-spaced over
        ``(0.05 k_max, k_max)``.
    min_separation : float
        Successive roots satisfy ``gamma_{j+1} >= (1 + min_separation) gamma_j``.
    weighting : {"element", "uniform"}
        Least-squares weight of each element: inverse RMS magnitude, or one for all.
    element_floor : float
        With ``"element"``, elements smaller than this fraction of the largest are weighted
        as if they had that size (so that near-zero elements do not dominate).
    k_max : float, optional
        Fit only the table's frequencies ``k <= k_max``.
    max_iter : int
        Ipopt iteration limit.
    tol : float
        Ipopt tolerance.
    """

    method: str = "roger"
    n_lags: int = 4
    poly_order: int = 2
    lag_bounds: tuple[float, float] | None = None
    initial_lags: tuple[float, ...] | None = None
    min_separation: float = 0.05
    weighting: str = "element"
    element_floor: float = 1e-2
    k_max: float | None = None
    max_iter: int = 1000
    tol: float = 1e-10

    def __post_init__(self):
        if self.method not in _METHODS:
            raise ConfigError(f"method={self.method!r} is not allowed; choose one of {_METHODS}")
        if not isinstance(self.n_lags, (int, np.integer)) or not 1 <= self.n_lags <= 40:
            raise ConfigError(f"n_lags={self.n_lags!r} must be an integer in 1..40")
        if self.poly_order not in (0, 1, 2):
            raise ConfigError(f"poly_order={self.poly_order!r} must be 0, 1 or 2")
        if self.lag_bounds is not None:
            lo, hi = (float(x) for x in self.lag_bounds)
            if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
                raise ConfigError(f"lag_bounds={self.lag_bounds!r} must be (low, high) with "
                                  "0 < low < high")
            object.__setattr__(self, "lag_bounds", (lo, hi))
        if self.initial_lags is not None:
            g = tuple(float(x) for x in self.initial_lags)
            if len(g) != self.n_lags or not all(np.isfinite(x) and x > 0 for x in g):
                raise ConfigError(f"initial_lags={self.initial_lags!r} must be n_lags = "
                                  f"{self.n_lags} positive numbers")
            object.__setattr__(self, "initial_lags", tuple(sorted(g)))
        if not (np.isfinite(self.min_separation) and 0 <= self.min_separation < 1):
            raise ConfigError(f"min_separation={self.min_separation!r} must lie in [0, 1)")
        if self.weighting not in _WEIGHTINGS:
            raise ConfigError(f"weighting={self.weighting!r} is not allowed; choose one of "
                              f"{_WEIGHTINGS}")
        if not (np.isfinite(self.element_floor) and 0 < self.element_floor <= 1):
            raise ConfigError(f"element_floor={self.element_floor!r} must lie in (0, 1]")
        if self.k_max is not None and not (np.isfinite(self.k_max) and self.k_max > 0):
            raise ConfigError(f"k_max={self.k_max!r} must be a positive number")
        if not isinstance(self.max_iter, (int, np.integer)) or self.max_iter < 1:
            raise ConfigError(f"max_iter={self.max_iter!r} must be a positive integer")
        if not (np.isfinite(self.tol) and self.tol > 0):
            raise ConfigError(f"tol={self.tol!r} must be a positive number")


@dataclass(frozen=True)
class RationalApproximation:
    """A fitted RFA ``Q(p) ~= A0 + A1 p + A2 p^2 + D (p I - diag(R))^-1 E p``.

    Attributes
    ----------
    method : str
        ``"roger"`` or ``"minimum_state"``.
    b : float
        Reference semichord [m]: ``p = s b / U``.
    gamma : numpy.ndarray
        The distinct lag roots ``gamma_j > 0`` (ascending), reduced-frequency units.
    A : numpy.ndarray
        ``(3, N, M)``: ``A0, A1, A2`` (zero above ``poly_order``).
    poly_order : int
        Highest power of ``p`` kept in the polynomial part.
    D : numpy.ndarray
        ``(N, n_x)`` output matrix of the lag states.
    R : numpy.ndarray
        ``(n_x,)`` lag-state roots in ``p`` (``-gamma``, repeated ``M`` times for Roger).
    E : numpy.ndarray
        ``(n_x, M)`` input matrix of the lag states.
    k : numpy.ndarray
        Reduced frequencies of the fit.
    error_rms : numpy.ndarray
        ``(N, M)``: RMS over ``k`` of ``|Q_fit - Q|`` per element.
    error_rel : numpy.ndarray
        ``(N, M)``: ``error_rms`` divided by the element's RMS magnitude (floored at
        ``element_floor`` of the largest element).
    error_max_rel : numpy.ndarray
        ``(N, M)``: largest ``|Q_fit - Q|`` over ``k``, divided as ``error_rel``.
    fit_error : float
        Square root of the weighted residual over the weighted data (the objective).
    mode_names, input_names : tuple of str
        Rows and columns of Q.
    nlp : NLPResult
        The Ipopt solve of the lag roots (``Solve_Succeeded``, ``Solved_To_Acceptable_Level``,
        or ``Search_Direction_Becomes_Too_Small`` when the data are exactly rational in the
        roots and the residual sits at the rounding floor).
    """

    __repr__ = result_repr

    method: str
    b: float
    gamma: np.ndarray
    A: np.ndarray
    poly_order: int
    D: np.ndarray
    R: np.ndarray
    E: np.ndarray
    k: np.ndarray
    error_rms: np.ndarray
    error_rel: np.ndarray
    error_max_rel: np.ndarray
    fit_error: float
    mode_names: tuple[str, ...]
    input_names: tuple[str, ...]
    nlp: NLPResult = field(repr=False)

    @property
    def n_modes(self) -> int:
        """N (rows of Q)."""
        return int(self.A.shape[1])

    @property
    def n_inputs(self) -> int:
        """M (columns: N modes, and the flap when present)."""
        return int(self.A.shape[2])

    @property
    def has_flap(self) -> bool:
        """True when the last column is the flap."""
        return self.n_inputs == self.n_modes + 1

    @property
    def n_lags(self) -> int:
        """Number of distinct lag roots."""
        return int(self.gamma.size)

    @property
    def n_lag_states(self) -> int:
        """Lag states of the realisation (``n_lags * M`` for Roger, ``n_lags`` minimum-state)."""
        return int(self.R.size)

    def evaluate_p(self, p) -> np.ndarray:
        """``Q(p)`` of the RFA at complex ``p`` (array), shape ``p.shape + (N, M)``."""
        pp = np.asarray(p, dtype=complex)
        flat = pp.ravel()
        out = (self.A[0][None] + flat[:, None, None] * self.A[1][None]
               + (flat ** 2)[:, None, None] * self.A[2][None])
        lag = flat[:, None] / (flat[:, None] - self.R[None, :])     # p / (p - R)
        out = out + np.einsum("ix,nx,xm->nim", self.D, lag, self.E)
        return out.reshape(pp.shape + out.shape[1:])

    def evaluate(self, k) -> np.ndarray:
        """``Q(ik)`` of the RFA at reduced frequencies ``k``, shape ``k.shape + (N, M)``."""
        return self.evaluate_p(1j * np.asarray(k, dtype=float))

    def summary(self) -> str:
        """One line: method, lag roots, overall and worst element fit error, Ipopt status."""
        i, j = np.unravel_index(np.argmax(self.error_rel), self.error_rel.shape)
        return (f"{self.method} RFA, {self.n_lags} lag roots {np.round(self.gamma, 4).tolist()}, "
                f"{self.n_lag_states} lag states; fit error {self.fit_error:.2e}, worst element "
                f"({self.mode_names[i]}, {self.input_names[j]}) {self.error_rel[i, j]:.2e}; "
                f"Ipopt {self.nlp.return_status}")


# ---- bases --------------------------------------------------------------------------------
def _poly_basis(k: np.ndarray, order: int) -> np.ndarray:
    """Real-stacked ``[1, p, p^2][:order+1]`` at ``p = ik``: shape ``(2 nk, order + 1)``."""
    z = np.zeros_like(k)
    cols = [np.concatenate([np.ones_like(k), z]), np.concatenate([z, k]),
            np.concatenate([-k * k, z])]
    return np.column_stack(cols[:order + 1])


def _lag_basis(k, gamma):
    """Real-stacked ``p / (p + gamma)`` at ``p = ik``; numpy or CasADi ``gamma``."""
    k2 = k * k
    if isinstance(gamma, (ca.SX, ca.MX)):
        cols = []
        for j in range(gamma.numel()):
            g = gamma[j]
            den = g * g + k2
            cols.append(ca.vertcat(k2 / den, g * k / den))
        return ca.horzcat(*cols)
    g = np.asarray(gamma, float)[None, :]
    den = g * g + k2[:, None]
    return np.vstack([k2[:, None] / den, g * k[:, None] / den])


def _stack(Q: np.ndarray) -> np.ndarray:
    """``(nk, N, M)`` complex -> ``(2 nk, N M)`` real (elements row-major)."""
    nk = Q.shape[0]
    F = Q.reshape(nk, -1)
    return np.vstack([F.real, F.imag])


def _element_scale(Q: np.ndarray, settings: RFASettings) -> np.ndarray:
    rms = np.sqrt(np.mean(np.abs(Q) ** 2, axis=0))
    top = float(rms.max())
    if top == 0:
        raise DataError("Q is zero at every k: there is nothing to fit")
    if settings.weighting == "uniform":
        return np.full(rms.shape, top)
    return np.maximum(rms, settings.element_floor * top)


# ---- the fits -----------------------------------------------------------------------------
def _roger_lstsq(k, Y, gamma, order):
    """Linear least squares of every column of ``Y`` on ``[poly, lags(gamma)]``."""
    Phi = np.hstack([_poly_basis(k, order), _lag_basis(k, gamma)])
    X, *_ = np.linalg.lstsq(Phi, Y, rcond=None)
    return X


def _ms_lstsq(k, Y, w, gamma, E, order, N, M):
    """Minimum-state matrices given ``gamma, E``: ``D`` row by row (the polynomial part
    projected out), then the polynomial part."""
    P0 = _poly_basis(k, order)
    G = _lag_basis(k, gamma)
    H = G - P0 @ np.linalg.lstsq(P0, G, rcond=None)[0]
    Yp = Y - P0 @ np.linalg.lstsq(P0, Y, rcond=None)[0]
    D = np.empty((N, gamma.size))
    for i in range(N):
        S = np.vstack([w[i, l] * H * E[:, l][None, :] for l in range(M)])
        D[i] = np.linalg.lstsq(S, Yp[:, i * M:(i + 1) * M].T.ravel(), rcond=None)[0]
    lagpart = np.einsum("rj,ij,jl->ril", G, D, E).reshape(G.shape[0], N * M) \
        * w.reshape(1, -1)
    X0, *_ = np.linalg.lstsq(P0, Y - lagpart, rcond=None)
    return D, X0


def _initial_lags(settings: RFASettings, kmax: float, bounds) -> np.ndarray:
    if settings.initial_lags is not None:
        g = np.array(settings.initial_lags, float)
    else:
        n = settings.n_lags
        g = kmax * np.logspace(np.log10(0.05), 0.0, n) if n > 1 else np.array([0.3 * kmax])
    lo, hi = bounds
    sep = np.log1p(settings.min_separation)
    lg = np.clip(np.log(g), np.log(lo), np.log(hi))
    for j in range(1, lg.size):                          # make the start feasible
        lg[j] = max(lg[j], lg[j - 1] + sep)
    if lg[-1] > np.log(hi) + 1e-12:
        raise ConfigError(f"{settings.n_lags} lag roots separated by a factor "
                          f"{1 + settings.min_separation} do not fit in lag_bounds = {bounds}; "
                          "widen the bounds, lower min_separation or use fewer lags")
    return lg


def _order_constraints(lg, n):
    return ca.vertcat(*[lg[j + 1] - lg[j] for j in range(n - 1)]) if n > 1 else ca.SX(0, 1)


def _solve(nlp, x0, lbx, ubx, lbg, ubg, settings, name) -> NLPResult:
    # the objective is log(residual / data): a gradient of 1e-5 changes it negligibly, and at
    # fits near the rounding floor the gradient is noise of about that size
    opts = {"ipopt.max_iter": int(settings.max_iter), "ipopt.tol": float(settings.tol),
            "ipopt.acceptable_tol": 1e-5, "ipopt.acceptable_iter": 10}
    res = solve_nlp(nlp, x0, options=opts, name=name, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg,
                    accept_acceptable=True)
    # exactly rational data: the residual reaches the floor of the objective, its curvature
    # there is enormous and Ipopt stops on a vanishing step -- at the global minimum
    exact = (res.return_status == "Search_Direction_Becomes_Too_Small"
             and res.f < np.log(1e3 * _FIT_FLOOR))
    if not (res.success or exact):
        raise ConvergenceError(
            f"the {name} lag-root optimisation did not converge (Ipopt: {res.return_status} "
            f"after {res.iterations} iterations); raise max_iter, change n_lags or "
            "initial_lags", res)
    return res


def _projected_lags(k, Y, settings, lg):
    """``Yp = P Y`` and an orthonormal basis ``Qh`` (with ``H = Qh Rh``) of ``H = P G(exp(lg))``,
    ``P`` the projector orthogonal to the polynomial basis (which eliminates the polynomial
    matrices).  Orthogonalisation (not normal equations) keeps the residual accurate when
    lag roots far above the data act together and their columns are nearly parallel."""
    P0 = _poly_basis(k, settings.poly_order)
    Yp = Y - P0 @ np.linalg.lstsq(P0, Y, rcond=None)[0]
    G = _lag_basis(k, ca.exp(lg))
    H = G - ca.mtimes(ca.DM(P0), ca.mtimes(ca.DM(np.linalg.pinv(P0)), G))
    Qh, Rh = ca.qr(H)
    return Yp, Qh, Rh


#: floor of the relative residual inside the logarithm: keeps the objective bounded (and its
#: Hessian finite) when the data are exactly rational in the lag roots (a fit error of 1e-10)
_FIT_FLOOR = 1e-20


def _log_objective(J, Yp):
    """``log(J / ||Yp||^2 + floor)``: the scale-free objective of both fits."""
    return ca.log(J / float(np.sum(Yp ** 2)) + _FIT_FLOOR)


def _fit_roger_lags(k, Y, settings, bounds, lg0) -> tuple[np.ndarray, NLPResult]:
    n = settings.n_lags
    lg = ca.SX.sym("log_gamma", n)
    Yp, Qh, _ = _projected_lags(k, Y, settings, lg)
    J = ca.sumsqr(ca.DM(Yp) - ca.mtimes(Qh, ca.mtimes(Qh.T, ca.DM(Yp))))
    sep = np.log1p(settings.min_separation)
    res = _solve({"x": lg, "f": _log_objective(J, Yp), "g": _order_constraints(lg, n)}, lg0,
                 np.log(bounds[0]), np.log(bounds[1]), sep, np.inf, settings, "roger_rfa")
    return np.exp(res.x), res


def _fit_ms_lags(k, Y, w, settings, bounds, lg0, E0, N, M):
    # MX (matrix-valued) expressions: the element-by-element SX graph of this objective
    # is large and its exact Hessian slow to build; D comes from its normal equations row by
    # row, the residual is then formed explicitly (accurate to first order in D's rounding)
    n, nk = settings.n_lags, k.size
    lg = ca.MX.sym("log_gamma", n)
    Ev = ca.MX.sym("E", n * M)
    E = ca.reshape(Ev, M, n).T                            # (n, M), row-major in Ev
    P0 = _poly_basis(k, settings.poly_order)
    Yp = Y - P0 @ np.linalg.lstsq(P0, Y, rcond=None)[0]
    gam = ca.exp(lg)
    k2 = ca.DM(k * k)
    den = ca.repmat(k2, 1, n) + ca.repmat((gam * gam).T, nk, 1)
    G = ca.vertcat(ca.repmat(k2, 1, n) / den,
                   ca.repmat(ca.DM(k), 1, n) * ca.repmat(gam.T, nk, 1) / den)
    H = G - ca.mtimes(ca.DM(P0), ca.mtimes(ca.DM(np.linalg.pinv(P0)), G))
    H = H / ca.repmat(ca.sqrt(ca.sum1(H * H)), 2 * nk, 1)
    K = ca.mtimes(H.T, H)
    C = ca.mtimes(H.T, ca.DM(Yp))                          # (n, N M)
    J = 0
    for i in range(N):
        Ew = E * ca.repmat(ca.DM(w[i]).T, n, 1)
        rhs = ca.sum2(Ew * C[:, i * M:(i + 1) * M])
        Di = ca.solve(K * ca.mtimes(Ew, Ew.T), rhs)       # row i of D (unit-column basis)
        model = ca.mtimes(H, Ew * ca.repmat(Di, 1, M))
        J = J + ca.sumsqr(ca.DM(Yp[:, i * M:(i + 1) * M]) - model)
    sep = np.log1p(settings.min_separation)
    g = ca.vertcat(*[lg[j + 1] - lg[j] for j in range(n - 1)],
                   *[ca.sumsqr(E[j, :]) for j in range(n)])
    lbg = np.concatenate([np.full(n - 1, sep), np.ones(n)])
    ubg = np.concatenate([np.full(n - 1, np.inf), np.ones(n)])
    x0 = np.concatenate([lg0, E0.ravel()])
    lbx = np.concatenate([np.full(n, np.log(bounds[0])), np.full(n * M, -np.inf)])
    ubx = np.concatenate([np.full(n, np.log(bounds[1])), np.full(n * M, np.inf)])
    res = _solve({"x": ca.vertcat(lg, Ev), "f": _log_objective(J, Yp), "g": g}, x0, lbx, ubx,
                 lbg, ubg, settings, "minimum_state_rfa")
    return np.exp(res.x[:n]), res.x[n:].reshape(n, M), res


#: minimum-state start: Roger's fit with one root per this many lag states
_MS_PER_ROOT = 2


def _ms_start(k, Y, w, s: RFASettings, kmax, bounds, N, M):
    """Starting roots and ``E`` of the minimum-state fit: Roger's optimum with
    ``ceil(n_lags / per_root)`` roots, each root's lag matrix split into its ``per_root`` leading
    singular directions (rows of ``E``), the copies of a root spread by the separation factor."""
    per_root = _MS_PER_ROOT
    n = s.n_lags
    nr = int(np.ceil(n / per_root))
    sr = replace(s, method="roger", n_lags=nr, initial_lags=None)
    gamma, _ = _fit_roger_lags(k, Y, sr, bounds, _initial_lags(sr, kmax, bounds))
    X = _roger_lstsq(k, Y, gamma, s.poly_order) / w.reshape(1, -1)
    lagm = X[s.poly_order + 1:].reshape(nr, N, M)
    counts = np.full(nr, n // nr)
    counts[:n % nr] += 1
    factor = 1.0 + max(s.min_separation, 1e-3)
    roots, rows = [], []
    for j in range(nr):
        Vt = np.linalg.svd(lagm[j])[2]
        for c in range(counts[j]):
            roots.append(gamma[j] * factor ** (c - 0.5 * (counts[j] - 1)))
            rows.append(Vt[c % Vt.shape[0]])
    order = np.argsort(roots)
    lg = np.log(np.asarray(roots)[order])
    lo, hi = np.log(bounds[0]), np.log(bounds[1])
    sep = np.log1p(s.min_separation)
    lg = np.clip(lg, lo, hi)
    for j in range(1, n):
        lg[j] = max(lg[j], lg[j - 1] + sep)
    for j in range(n - 2, -1, -1):
        lg[j] = min(lg[j], lg[j + 1] - sep)
    return lg, np.asarray(rows)[order]


def fit_rfa(table: GAFTable, settings: RFASettings | None = None,
            **overrides) -> RationalApproximation:
    """Fit Roger's or Karpel's minimum-state RFA to a ``Q(ik)`` table.

    Parameters
    ----------
    table : GAFTable
        Reduced frequencies and complex ``Q(ik)`` (eq. 6 normalisation; the fit does not
        depend on the normalisation).
    settings : RFASettings, optional
        Method, number of lag roots, polynomial order, bounds, weighting (defaults: Roger,
        4 lags, ``A0, A1, A2``).
    **overrides
        Fields of :class:`RFASettings` replacing those of ``settings``.

    Returns
    -------
    RationalApproximation
        With the fit error per element.

    Raises
    ------
    DataError
        Too few reduced frequencies for the number of coefficients, or ``Q`` zero.
    ConvergenceError
        Ipopt did not converge on the lag roots.
    """
    s = replace(settings or RFASettings(), **overrides) if overrides else (settings
                                                                           or RFASettings())
    if not isinstance(table, GAFTable):
        raise ConfigError(f"table must be a casflutter.data.GAFTable, got {type(table).__name__}")
    sel = table.k <= (s.k_max if s.k_max is not None else np.inf)
    k, Q = table.k[sel], table.Q[sel]
    nk, N, M = Q.shape
    npar = s.poly_order + 1 + s.n_lags
    if 2 * nk < npar + s.n_lags + 1 or k.max() <= 0:
        raise DataError(f"{nk} reduced frequencies (k <= {k.max():g}) are too few to fit "
                        f"{npar} coefficients per element and {s.n_lags} lag roots; give more "
                        "frequencies (about 3 per coefficient) or fewer lags")
    kmax = float(k.max())
    bounds = s.lag_bounds or (1e-3 * kmax, 2.0 * kmax)
    scale = _element_scale(Q, s)
    w = 1.0 / scale                                       # (N, M)
    Y = _stack(Q) * w.reshape(1, -1)
    if s.method == "roger":
        gamma, res = _fit_roger_lags(k, Y, s, bounds, _initial_lags(s, kmax, bounds))
        log.debug("Roger lag roots %s (%d Ipopt iterations, %s)", np.round(gamma, 5),
                  res.iterations, res.return_status)
        X = _roger_lstsq(k, Y, gamma, s.poly_order) / w.reshape(1, -1)
        A = np.zeros((3, N, M))
        A[:s.poly_order + 1] = X[:s.poly_order + 1].reshape(-1, N, M)
        D = np.hstack(list(X[s.poly_order + 1:].reshape(s.n_lags, N, M)))
        R = np.repeat(-gamma, M)
        E = np.vstack([np.eye(M)] * s.n_lags)
    else:
        lg0, E0 = _ms_start(k, Y, w, s, kmax, bounds, N, M)
        gamma, E, res = _fit_ms_lags(k, Y, w, s, bounds, lg0, E0, N, M)
        log.debug("minimum-state lag roots %s (%d Ipopt iterations, %s)", np.round(gamma, 5),
                  res.iterations, res.return_status)
        D, X0 = _ms_lstsq(k, Y, w, gamma, E, s.poly_order, N, M)
        A = np.zeros((3, N, M))
        A[:s.poly_order + 1] = (X0 / w.reshape(1, -1)).reshape(-1, N, M)
        R = -gamma
    rfa = RationalApproximation(
        method=s.method, b=table.b, gamma=np.asarray(gamma, float), A=A,
        poly_order=s.poly_order, D=D, R=R, E=E, k=k, error_rms=np.zeros((N, M)),
        error_rel=np.zeros((N, M)), error_max_rel=np.zeros((N, M)), fit_error=0.0,
        mode_names=table.mode_names, input_names=table.input_names, nlp=res)
    err = np.abs(rfa.evaluate(k) - Q)
    e_rms = np.sqrt(np.mean(err ** 2, axis=0))
    fit_error = float(np.sqrt(np.sum((_stack(rfa.evaluate(k) - Q) * w.reshape(1, -1)) ** 2)
                              / np.sum(Y ** 2)))
    return replace(rfa, error_rms=e_rms, error_rel=e_rms / scale,
                   error_max_rel=err.max(axis=0) / scale, fit_error=fit_error)


def fit_roger(table: GAFTable, n_lags: int = 4, **kwargs) -> RationalApproximation:
    """Roger's RFA with ``n_lags`` optimised lag roots; see :func:`fit_rfa`."""
    return fit_rfa(table, RFASettings(method="roger", n_lags=n_lags, **kwargs))


def fit_minimum_state(table: GAFTable, n_lags: int = 4, **kwargs) -> RationalApproximation:
    """Karpel's minimum-state RFA with ``n_lags`` lag states; see :func:`fit_rfa`."""
    return fit_rfa(table, RFASettings(method="minimum_state", n_lags=n_lags, **kwargs))
