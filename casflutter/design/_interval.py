"""How far one fixed controller keeps ΣAE(V) stable: continuation of a speed interval (eq. 8-9).

The paper's controller is designed at Vf and reported stable over a speed interval.  Whether a
single linear controller can hold the whole interval is a simultaneous-stabilisation problem
over the family ΣAE(V), for which no finite test exists; this module answers it
constructively, the way HIFOO's stabilisation phase does for one plant:

* the objective is the worst closed-loop spectral abscissa over ``n_speeds`` speeds of the
  current interval, ``max_j α(A_cl(V_j))``, smoothed by a log-sum-exp of temperature ``τ``
  (``τ → 0`` recovers the max) and minimised over ``(Ak, Bk, Ck)`` by BFGS with the exact
  gradient ``∂λ/∂A_cl = u vᵀ / (uᵀ v)`` of the rightmost eigenvalue (left/right
  eigenvectors ``u``, ``v``) through the closed-loop map of
  :meth:`~casflutter.aeroelastic.AeroelasticSystem.closed_loop_state_matrix`;
* continuation: starting where the given controller already decays, one end of the interval
  is pushed a step towards the target; a step is kept when the loop decays at the rate
  ``decay`` on a dense scan of the new interval (a peak the scan finds between the
  objective's speeds joins them and the step is optimised again, twice at most); the step
  grows 1.5x after a success and halves after a failure, until the target is met or the step
  falls below ``min_step``.

Pushing from the low end with a low-order controller and from the high end with a full-order
one brackets what the family allows: where the two continuations stall, no controller that
either method could reach holds the loop.  The result states the interval reached; its exact
interval is for the independent verification layer to certify.

:func:`reduce_order` then lowers the order of a controller that holds the whole interval,
one truncation at a time (continuation in the order rather than in the speed): each balanced
truncation is re-optimised on the same objective over the fixed interval, and continued from
the low end when the truncation has lost the top.  It is how the order-8 and order-7
controllers that hold the seed wing over (0, 2.4) were found from the full-order one.
:func:`design_interval_controller` chains the two: stability over the interval first, the
order second.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg
from scipy.optimize import minimize

from .._format import result_repr
from .._linalg import spectral_abscissa
from .._settings import finite_numbers
from .._threads import single_threaded
from ..aeroelastic import AeroelasticSystem
from ..errors import ConfigError, DimensionError

__all__ = ["IntervalDesign", "IntervalReach", "OrderReduction", "OrderStep",
           "design_interval_controller", "full_order_start", "reduce_order",
           "stabilize_interval"]

log = logging.getLogger("casflutter.design")


@dataclass(frozen=True)
class IntervalReach:
    """Outcome of :func:`stabilize_interval`.

    Attributes
    ----------
    controller : control.StateSpace
        ``K(s)`` on the physical sensors (``v = K zm``), of the order of the start.
    reached : tuple of float
        ``(lo, hi)``: the last interval on which the loop decays at the rate ``decay`` on the
        dense scan.
    target : tuple of float
        The requested interval.
    anchor : str
        ``"low"`` (the upper end was pushed) or ``"high"`` (the lower end was pushed).
    worst_abscissa : float
        Largest closed-loop spectral abscissa (rad/s) on the dense scan of ``reached``.
    history : tuple of tuple
        ``(lo, hi, worst)`` of every interval tried, in order (``worst`` on its grid).
    met : bool
        True when ``reached`` is the target.
    """

    __repr__ = result_repr

    controller: control.StateSpace
    reached: tuple
    target: tuple
    anchor: str
    worst_abscissa: float
    history: tuple
    met: bool


def _speed_interval(interval) -> tuple[float, float]:
    """``(lo, hi)`` of a target speed interval, checked: ``0 <= lo < hi``, both finite."""
    lo, hi = finite_numbers("interval", interval, 2, what="two numbers (lo, hi)")
    if not 0 <= lo < hi:
        raise ConfigError(f"interval = {[lo, hi]!r}: need 0 <= lo < hi")
    return lo, hi


def _unpack(p: np.ndarray, n: int, m: int, Dk: np.ndarray):
    """``(Ak, Bk, Ck, Dk)`` of an order-``n`` controller on ``m`` sensors from its parameters;
    ``Dk`` is the last ``m`` of them when they are there (a free feed-through), the given one
    otherwise."""
    L = n * n + n * m + n
    D = p[L:L + m].reshape(1, m) if len(p) == L + m else Dk
    return p[:n * n].reshape(n, n), p[n * n:n * n + n * m].reshape(n, m), \
        p[n * n + n * m:L].reshape(1, n), D


def _pack(K: control.StateSpace, free_feedthrough: bool) -> np.ndarray:
    """The parameters of ``K`` that the continuation moves (``Dk`` only when free)."""
    parts = [K.A, K.B, K.C] + ([K.D] if free_feedthrough else [])
    return np.concatenate([np.asarray(M, dtype=float).ravel() for M in parts])


def _controller(p: np.ndarray, n: int, m: int, Dk: np.ndarray) -> control.StateSpace:
    return control.ss(*_unpack(p, n, m, Dk))


class _Models:
    """One loop family, or several that one controller must hold together (the worst of
    them at every speed): a ROM and the models around it."""

    def __init__(self, system):
        fams = tuple(system) if isinstance(system, (list, tuple)) else (system,)
        if not fams or not all(callable(getattr(f, "loop", None)) and
                               callable(getattr(f, "closed_loop_state_matrix", None))
                               for f in fams):
            raise ConfigError("system must be a loop family (loop(V), "
                              "closed_loop_state_matrix(V, K)) or a non-empty sequence of them")
        m = {f.loop(1.0).C2.shape[0] for f in fams}
        if len(m) > 1:
            raise DimensionError(f"the families have different numbers of sensors {sorted(m)}; "
                                 "one controller needs the same sensors on every model")
        self.families, self.n_sensors = fams, m.pop()

    @classmethod
    def of(cls, system) -> "_Models":
        return system if isinstance(system, cls) else cls(system)

    def loops(self, V: float) -> list:
        return [f.loop(float(V)) for f in self.families]

    def closed_loop_state_matrices(self, V: float, K) -> list:
        return [f.closed_loop_state_matrix(float(V), K) for f in self.families]


class _ClosedLoopsAtSpeeds:
    """ΣAE(V_j) at a set of speeds and the closed loop's rightmost eigenvalue and its gradient
    with respect to ``(Ak, Bk, Ck)``, and ``Dk`` when the parameters include it (otherwise
    ``Dk`` is held at the given value).  With ``stable_controller`` the controller's own
    spectral abscissa (of ``Ak``) is one more entry, after the loops': the worst then asks
    for a stable controller too."""

    def __init__(self, models, speeds, order: int, Dk: np.ndarray,
                 stable_controller: bool = False):
        self.order, self.Dk, self.stable_controller = order, Dk, bool(stable_controller)
        models = _Models.of(models)
        self.loops = [lp for V in speeds for lp in models.loops(V)]
        self.m = models.n_sensors

    def abscissae(self, p: np.ndarray) -> np.ndarray:
        """The closed loop's spectral abscissa at every speed (eigenvalues only), then the
        controller's own when it is asked to be stable."""
        Ak, Bk, Ck, Dk = _unpack(p, self.order, self.m, self.Dk)
        a = [float(np.max(np.linalg.eigvals(lp.closed_loop_parts(Ak, Bk, Ck, Dk)[0]).real))
             for lp in self.loops]
        if self.stable_controller:
            a.append(spectral_abscissa(Ak))
        return np.array(a)

    @staticmethod
    def _rightmost_gradient(M: np.ndarray) -> tuple[float, np.ndarray]:
        """Real part of the rightmost eigenvalue of ``M`` and its gradient with respect to
        ``M``, the real part of ``∂λ/∂M = u vᵀ / (uᵀ v)`` (left/right eigenvectors)."""
        lam, VL, VR = scipy.linalg.eig(M, left=True, right=True)
        i = int(np.argmax(lam.real))
        u, v = VL[:, i].conj(), VR[:, i]
        return float(lam[i].real), np.real(np.outer(u, v) / (u @ v))

    def gradient(self, p: np.ndarray, j: int) -> tuple[float, np.ndarray]:
        """The rightmost eigenvalue's real part of loop ``j`` (of the controller itself for
        ``j = len(loops)``) and its gradient."""
        Ak, Bk, Ck, Dk = _unpack(p, self.order, self.m, self.Dk)
        free_d = p.size > self.order * (self.order + self.m + 1)    # Dk among the parameters
        if j == len(self.loops):                  # the controller's own abscissa: Ak only
            a, dAk = self._rightmost_gradient(Ak)
            rest = p.size - self.order * self.order
            return a, np.concatenate([dAk.ravel(), np.zeros(rest)])
        lp = self.loops[j]
        Acl, s, vx, zx = lp.closed_loop_parts(Ak, Bk, Ck, Dk)
        B2, D22 = lp.B2[:, None] / s, lp.D22[:, None]
        alpha, G = self._rightmost_gradient(Acl)         # ∂λ/∂A_cl, real part
        nx = lp.A.shape[0]
        Gxx, Gxk, Gkx, Gkk = G[:nx, :nx], G[:nx, nx:], G[nx:, :nx], G[nx:, nx:]
        dAk = Gkk
        dBk = Gkx @ zx.T + Gkk @ (D22 @ Ck / s).T
        dCk = B2.T @ Gxk + (Bk @ D22 / s).T @ Gkk
        parts = [dAk.ravel(), dBk.ravel(), dCk.ravel()]
        if free_d:
            # Dk enters through 1/s = 1/(1 - Dk D22) and vx = Dk C2 / s
            g = lp.B2 @ Gxx + (Bk @ D22)[:, 0] @ Gkx                   # ∂λ/∂vx
            a = float(lp.B2 @ Gxk @ Ck[0] + (Bk @ D22)[:, 0] @ Gkk @ Ck[0])  # ∂λ/∂(1/s)
            dvx = lp.C2 / s + np.outer(lp.D22, vx[0]) / s           # row j: ∂vx/∂Dk_j
            parts.append(dvx @ g + a * lp.D22 / s ** 2)
        return alpha, np.concatenate(parts)

    def rightmost(self, p: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        """The rightmost eigenvalue's real part at every speed (and of the controller) and
        its gradient."""
        pairs = [self.gradient(p, j)
                 for j in range(len(self.loops) + self.stable_controller)]
        return np.array([a for a, _ in pairs]), [g for _, g in pairs]

    def smoothed(self, p: np.ndarray, tau: float | None) -> tuple[float, np.ndarray]:
        """The worst abscissa, or its log-sum-exp of temperature ``tau``, and the gradient.
        For the worst itself (``tau = None``) only its loop needs eigenvectors; the others
        need their eigenvalues alone."""
        if tau is None:
            a = self.abscissae(p)
            k = int(np.argmax(a))
            return float(a[k]), self.gradient(p, k)[1]
        a, g = self.rightmost(p)
        k = int(np.argmax(a))
        if not np.isfinite(a[k]):
            return float(a[k]), g[k]
        w = np.exp((a - a[k]) / tau)
        total = float(np.sum(w))
        return float(a[k] + tau * math.log(total)), sum((wi / total) * gi for wi, gi in zip(w, g))


def _minimise_worst(fam: _ClosedLoopsAtSpeeds, p: np.ndarray, taus, good: float,
                    max_iter: int) -> tuple[np.ndarray, float]:
    """BFGS on the smoothed worst abscissa at each temperature of ``taus`` in turn (``None``:
    the maximum itself), keeping a result only when it lowers the worst; stops once the worst
    is at most ``good``.  Returns the parameters and their worst abscissa."""
    best = fam.smoothed(p, None)[0]
    for tau in taus:
        if best <= good:
            break
        res = minimize(fam.smoothed, p, args=(tau,), jac=True, method="BFGS",
                       options={"maxiter": int(max_iter)})
        worst = fam.smoothed(res.x, None)[0]
        if np.all(np.isfinite(res.x)) and worst < best:
            p, best = res.x, worst
    return p, float(best)


def _polish(system, K: control.StateSpace, speeds, max_iter: int, good: float,
            free_feedthrough: bool = False, stable_controller: bool = False
            ) -> tuple[control.StateSpace, float]:
    """``K`` re-optimised for the worst spectral abscissa over ``speeds`` (and of ``K``
    itself with ``stable_controller``): BFGS on the log-sum-exp of decreasing temperature,
    then on the maximum itself; stops early once the worst is below ``good``.  Returns the
    best controller met and its worst abscissa."""
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (K.A, K.B, K.C, K.D))
    n, m = K.nstates, Dk.shape[1]
    fam = _ClosedLoopsAtSpeeds(system, speeds, n, Dk, stable_controller)
    taus = (1.0, 0.3, 0.1, 0.03, 0.01, None)
    p, best = _minimise_worst(fam, _pack(K, free_feedthrough), taus, good, max_iter)
    return _controller(p, n, m, Dk), float(best)


def _truncation_polished(system, Kr, Dk, speeds, lo: float, hi: float, decay: float,
                         n_speeds: int, max_iter: int, free_feedthrough: bool = False
                         ) -> tuple[control.StateSpace, float]:
    """A truncated controller re-optimised over ``speeds`` and checked on a dense scan of
    ``[lo, hi]``; the scan's peaks between those speeds are added to them and the controller
    re-optimised, up to three times.  Returns it and its worst dense abscissa."""
    Kn, grid = control.ss(Kr.A, Kr.B, Kr.C, Dk), speeds
    for _ in range(4):
        Kn, _ = _polish(system, Kn, grid, max_iter, -6 * decay, free_feedthrough)
        dense, values = _dense_abscissae(system, Kn, lo, hi, 8 * n_speeds)
        worst = float(np.max(values))
        if worst <= -decay:
            break
        grid = np.union1d(grid, dense[_peaks(values, decay)])
    return Kn, worst


def _peaks(values: np.ndarray, decay: float, most: int = 8) -> list[int]:
    """Indices of the ``most`` highest local maxima of a dense scan above ``-decay``."""
    n = len(values)
    peaks = [j for j in range(n) if values[j] > -decay and values[j] >= values[max(j - 1, 0)]
             and values[j] >= values[min(j + 1, n - 1)]]
    return sorted(peaks, key=lambda j: -values[j])[:most]


def _dense_abscissae(models: _Models, K: control.StateSpace, lo: float, hi: float, n: int
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The speeds of a dense scan of ``[lo, hi]`` and the closed loop's spectral abscissa
    at each, the worst over the models (``inf`` where a loop is algebraically singular)."""
    grid = np.linspace(lo, hi, n)
    values = np.empty(n)
    for j, V in enumerate(grid):
        try:
            mats = models.closed_loop_state_matrices(V, K)
        except DimensionError:                 # a singular algebraic loop
            values[j] = np.inf
            continue
        values[j] = max(float(np.max(np.linalg.eigvals(A).real)) for A in mats)
    return grid, values


def _dense_worst(system, K: control.StateSpace, lo: float, hi: float, n: int) -> float:
    return float(np.max(_dense_abscissae(system, K, lo, hi, n)[1]))


def stabilize_interval(system, controller, interval, *,
                       anchor: str = "low", decay: float = 0.05, n_speeds: int = 40,
                       first_step: float = 0.05, min_step: float = 0.0025,
                       max_iter: int = 300, max_rounds: int = 200,
                       free_feedthrough: bool = False,
                       stable_controller: bool = False) -> IntervalReach:
    """Extend the speed interval over which one controller keeps ΣAE(V) decaying.

    Parameters
    ----------
    system : LoopFamily or sequence of LoopFamily
        ΣAE(V) of eq. 8-9 at any speed index (a
        :class:`~casflutter.aeroelastic.LoopFamily`: an
        :class:`~casflutter.aeroelastic.AeroelasticSystem`, a
        :class:`~casflutter.aeroelastic.ServoSystem`, a
        :class:`~casflutter.aeroelastic.TruthLoop`, ...); several families (same sensors) ask
        one controller to hold all of them: the objective and the dense check take the worst
        closed-loop abscissa over them at every speed.
    controller : control.StateSpace
        The start ``K(s)`` (``v = K zm``, as :meth:`AeroelasticSystem.closed_loop_state_matrix`);
        its order is kept, and its ``D`` is held fixed (0 for a strictly proper controller)
        unless ``free_feedthrough``.  It must stabilise ΣAE at the anchor end of the interval.
    interval : (lo, hi)
        Target speed-index interval, ``0 <= lo < hi``.
    anchor : {"low", "high"}
        The end the continuation starts from; the other end is pushed towards the target.
    decay : float
        Decay rate (rad/s) required at every speed of the interval.
    n_speeds : int
        Speeds of the objective on each interval tried (the dense check uses 8x as many).
    first_step, min_step : float
        First and smallest continuation step in V.
    max_iter : int
        BFGS iterations per temperature of the smoothed maximum (0.3, 0.1, 0.03, exact).
    max_rounds : int
        Continuation steps at most.
    free_feedthrough : bool
        Optimise ``D`` with ``(A, B, C)`` (a static path from the sensors to the flap: two
        more parameters at no cost in order).
    stable_controller : bool
        Keep the controller itself stable as well: its spectral abscissa joins the worst, so
        every step kept leaves its poles decaying at the rate ``decay`` (the start must be
        stable).  An unstable controller may hold the loop, but only while the plant's
        feedback holds it: the loop fails if the flap or a sensor does.

    Returns
    -------
    IntervalReach

    Raises
    ------
    ConfigError
        A bad interval, anchor or setting, a start that does not decay at the anchor end, or
        an unstable start with ``stable_controller``.
    DimensionError
        A controller that does not map the sensors to the flap.

    See Also
    --------
    design_flutter_controller : H∞ design at Vf with stability over an interval.
    casflutter.verify.verify_controller : the independent exact stable interval.
    """
    lo, hi = _speed_interval(interval)
    if anchor not in ("low", "high"):
        raise ConfigError(f"anchor = {anchor!r}: 'low' or 'high'")
    if not (decay >= 0 and n_speeds >= 2 and 0 < min_step <= first_step and max_iter >= 1):
        raise ConfigError(f"need decay >= 0, n_speeds >= 2, 0 < min_step <= first_step, "
                          f"max_iter >= 1; got decay={decay!r}, n_speeds={n_speeds!r}, "
                          f"min_step={min_step!r}, first_step={first_step!r}, "
                          f"max_iter={max_iter!r}")
    K = control.ss(controller)
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (K.A, K.B, K.C, K.D))
    order = K.nstates
    system = _Models.of(system)
    m = system.n_sensors
    if Dk.shape != (1, m) or order == 0:
        raise DimensionError(f"need a dynamic controller with {m} inputs (the sensors) and 1 "
                             f"output (the flap); got order {order}, D of shape {Dk.shape}")
    dense = 8 * n_speeds
    with single_threaded():
        start = hi if anchor == "high" else lo
        own = spectral_abscissa(Ak)
        if stable_controller and not own < 0:
            raise ConfigError(f"stable_controller: the start controller itself is unstable "
                              f"(a pole with real part {own:.4g}); start from a stable one")
        if not _dense_worst(system, K, start, start, 1) < 0:
            raise ConfigError(f"the start controller does not stabilise ΣAE at the anchor "
                              f"V = {start:.4g}; start from a controller designed there")
        # where the start already decays, scanning away from the anchor
        grid = np.linspace(lo, hi, dense)
        if anchor == "high":
            grid = grid[::-1]
        edge = start
        for V in grid:
            if _dense_worst(system, K, V, V, 1) > -decay:
                break
            edge = float(V)
        cur = (lo, edge) if anchor == "low" else (edge, hi)
        p = _pack(K, free_feedthrough)
        step, history = float(first_step), []
        log.debug("interval continuation (%s end, order %d): the start decays on [%.4g, %.4g]",
                  anchor, order, *cur)
        rounds = 0
        while cur != (lo, hi) and step >= min_step and rounds < max_rounds:
            rounds += 1
            trial = ((cur[0], min(hi, cur[1] + step)) if anchor == "low"
                     else (max(lo, cur[0] - step), cur[1]))
            speeds = np.linspace(*trial, n_speeds)
            q = p
            for _ in range(3):
                fam = _ClosedLoopsAtSpeeds(system, speeds, order, Dk, stable_controller)
                q, worst = _minimise_worst(fam, q, (0.3, 0.1, 0.03, None), -2 * decay,
                                           max_iter)
                ok = worst <= -decay
                if not ok:
                    break
                # the dense scan decides; a peak between the objective's speeds joins them
                scan, values = _dense_abscissae(system, _controller(q, order, m, Dk),
                                                *trial, dense)
                ok = float(np.max(values)) <= -decay
                if ok:
                    break
                speeds = np.union1d(speeds, scan[_peaks(values, decay)])
            history.append((trial[0], trial[1], worst))
            log.debug("interval continuation: [%.4g, %.4g] worst abscissa %.4g -> %s", *trial,
                      worst, "kept" if ok else f"step {step / 2:.3g}")
            if ok:
                p, cur, step = q, trial, 1.5 * step
            else:
                step *= 0.5
        Kout = _controller(p, order, m, Dk) if rounds else K
        worst = _dense_worst(system, Kout, *cur, dense)
    return IntervalReach(Kout, cur, (lo, hi), anchor, worst, tuple(history), cur == (lo, hi))


def full_order_start(system: AeroelasticSystem, V: float, *, state_weight: float = 0.01,
                     noise_ratio: float = 1.0) -> control.StateSpace:
    """A full-order observer-based (LQG) controller of ΣAE at one speed, to start from.

    ``v = −Kx x̂`` with the LQR gain of ``(A, B2)`` for ``Q = state_weight·I``, ``R = 1`` and
    the Kalman observer ``x̂' = A x̂ + B2 v + L (zm − C2 x̂ − D22 v)`` for unit process noise
    on every state and measurement noise ``noise_ratio·I``; as ``v = K zm`` (eq. 8-9) it is
    strictly proper, of the loop's order.

    Parameters
    ----------
    system : AeroelasticSystem
        Σf and Σs.
    V : float
        Speed index of the design.
    state_weight, noise_ratio : float
        LQR state weight and Kalman measurement-to-process noise ratio (> 0).

    Returns
    -------
    control.StateSpace
        ``K(s)``, sensors to flap.

    Raises
    ------
    ConfigError
        A weight that is not > 0.

    See Also
    --------
    stabilize_interval : continues the interval such a controller holds.
    """
    if not (state_weight > 0 and noise_ratio > 0):
        raise ConfigError(f"state_weight = {state_weight!r} and noise_ratio = {noise_ratio!r}: "
                          "both > 0")
    lp = system.loop(float(V))
    n, m = lp.A.shape[0], lp.C2.shape[0]
    B2 = lp.B2[:, None]
    Kx, _, _ = control.lqr(lp.A, B2, state_weight * np.eye(n), np.eye(1))
    L, _, _ = control.lqe(lp.A, np.eye(n), lp.C2, np.eye(n), noise_ratio * np.eye(m))
    Kx, L = np.asarray(Kx), np.asarray(L)
    D22 = lp.D22[:, None]
    return control.ss(lp.A - B2 @ Kx - L @ lp.C2 + L @ D22 @ Kx, L, -Kx, np.zeros((1, m)))



@dataclass(frozen=True)
class OrderStep:
    """One order of :func:`reduce_order`.

    Attributes
    ----------
    order : int
        Controller order.
    controller : control.StateSpace
        The re-optimised truncation (``v = K zm``).
    worst_abscissa : float
        Largest closed-loop spectral abscissa (rad/s) on the dense scan of the interval.
    met : bool
        The loop decays at the rate ``decay`` on the whole dense scan.
    continued : bool
        The fixed-interval re-optimisation missed and the interval was continued from the
        low end (:func:`stabilize_interval`).
    """

    __repr__ = result_repr

    order: int
    controller: control.StateSpace
    worst_abscissa: float
    met: bool
    continued: bool


@dataclass(frozen=True)
class OrderReduction:
    """Outcome of :func:`reduce_order`.

    Attributes
    ----------
    interval : tuple of float
        ``(lo, hi)`` held at every order.
    decay : float
        Decay rate (rad/s) required on it.
    steps : tuple of OrderStep
        The orders held, highest first (with the half-way orders of split steps), and last
        the first order that missed, if one did.
    """

    __repr__ = result_repr

    interval: tuple
    decay: float
    steps: tuple

    @property
    def lowest(self) -> OrderStep | None:
        """The lowest-order step that holds the interval (``None`` if none does)."""
        met = [s for s in self.steps if s.met]
        return met[-1] if met else None


def reduce_order(system, controller, interval, orders, *, decay: float = 0.05,
                 n_speeds: int = 48, max_iter: int = 600,
                 free_feedthrough: bool = False) -> OrderReduction:
    """Lower the order of a controller that keeps ΣAE(V) decaying over a speed interval.

    At each order of ``orders`` the previous controller is truncated
    (:func:`control.balred`: balanced truncation of its stable part, its unstable modes
    kept) and re-optimised for the worst closed-loop spectral abscissa over ``n_speeds``
    speeds of the fixed interval (the objective of :func:`stabilize_interval`).  A dense scan
    (8x as many speeds) checks the result; the peaks it finds between the objective's speeds
    are added to them and the controller re-optimised, up to three times.  A step of more
    than one order that still misses the rate ``decay`` is split (the order half-way is
    held first); a one-order step that misses, and still decays at the low end, is continued
    from there with fine steps.  The sequence stops at the first order that misses: a lower
    order would start from a controller that does not hold the interval.

    Parameters
    ----------
    system : LoopFamily or sequence of LoopFamily
        The loop family, or several that the controller must hold together (as
        :func:`stabilize_interval`).
    controller : control.StateSpace
        The start, which should hold the interval (``v = K zm``).
    interval : (lo, hi)
        Speed-index interval, ``0 <= lo < hi``.
    orders : sequence of int
        Strictly decreasing orders, each below the start's, >= 1.
    decay : float
        Decay rate (rad/s) required at every speed of the interval.
    n_speeds : int
        Speeds of the objective (>= 2).
    max_iter : int
        BFGS iterations per temperature of the smoothed maximum.
    free_feedthrough : bool
        Optimise the controller's ``D`` as well (see :func:`stabilize_interval`); otherwise
        the start's ``D`` is kept.

    Returns
    -------
    OrderReduction
        Its exact stable intervals are for the verification layer to certify
        (:func:`casflutter.verify.speed_family_interval`).

    Raises
    ------
    ConfigError
        A bad interval or order sequence, or a setting out of range.
    DimensionError
        A controller that does not map the sensors to the flap.

    See Also
    --------
    stabilize_interval : continuation in speed at a fixed order.
    """
    lo, hi = _speed_interval(interval)
    K = control.ss(controller)
    seq = [int(n) for n in orders]
    if (not seq or any(n < 1 for n in seq) or any(a <= b for a, b in zip(seq, seq[1:]))
            or seq[0] >= K.nstates):
        raise ConfigError(f"orders = {list(orders)!r}: strictly decreasing orders >= 1, each "
                          f"below the start's order {K.nstates}")
    if not (decay >= 0 and n_speeds >= 2 and max_iter >= 1):
        raise ConfigError(f"need decay >= 0, n_speeds >= 2, max_iter >= 1; got "
                          f"decay={decay!r}, n_speeds={n_speeds!r}, max_iter={max_iter!r}")
    system = _Models.of(system)
    m = system.n_sensors
    if np.atleast_2d(np.asarray(K.D)).shape != (1, m):
        raise DimensionError(f"need a controller with {m} inputs (the sensors) and 1 output "
                             f"(the flap); got D of shape {np.shape(K.D)}")
    speeds = np.linspace(lo, hi, n_speeds)
    steps = []
    queue = list(seq)
    with single_threaded():
        while queue:
            n = queue[0]
            try:
                Kr = control.balred(K, n, method="truncate")
            except ValueError as exc:       # more unstable modes than n
                log.debug("order reduction: order %d not reached (%s)", n, exc)
                break
            Kn, worst = _truncation_polished(system, Kr, K.D, speeds, lo, hi, decay,
                                             n_speeds, max_iter, free_feedthrough)
            p = K.nstates
            if worst > -decay and p - n > 1:
                # a smaller step first: the order half-way
                log.debug("order reduction: %d -> %d missed (worst abscissa %.4g); via %d", p,
                          n, worst, (p + n) // 2)
                queue.insert(0, (p + n) // 2)
                continue
            continued = False
            if worst > -decay and _dense_worst(system, Kn, lo, lo, 1) < 0:
                reach = stabilize_interval(system, Kn, (lo, hi), anchor="low", decay=decay,
                                           n_speeds=n_speeds, first_step=0.01,
                                           min_step=0.001, max_iter=max_iter,
                                           free_feedthrough=free_feedthrough)
                continued = True
                if reach.met:
                    Kn, worst = reach.controller, reach.worst_abscissa
            met = bool(worst <= -decay)
            log.debug("order reduction: order %d worst abscissa %.4g on [%.4g, %.4g]%s -> %s",
                      n, worst, lo, hi, " (continued)" if continued else "",
                      "held" if met else "missed")
            steps.append(OrderStep(n, Kn, float(worst), met, continued))
            if not met:
                break
            K = Kn
            queue.pop(0)
    return OrderReduction((lo, hi), float(decay), tuple(steps))


@dataclass(frozen=True)
class IntervalDesign:
    """Outcome of :func:`design_interval_controller`.

    Attributes
    ----------
    controller : control.StateSpace
        The requested order when it holds the interval; otherwise the lowest order that
        does (or the full-order controller when no reduction held, or the full-order
        continuation's result when even that missed).
    order : int
        The requested order.
    full_order : IntervalReach
        The full-order continuation from the interval's top.
    reduction : OrderReduction or None
        The order continuation (``None`` when the full order missed the interval).
    met : bool
        ``controller`` has the requested order and holds the interval.
    """

    __repr__ = result_repr

    controller: control.StateSpace
    order: int
    full_order: IntervalReach
    reduction: OrderReduction | None
    met: bool


def design_interval_controller(system, interval, order: int, *,
                               orders: tuple = (20, 14, 10, 8), decay: float = 0.05,
                               n_speeds: int = 40,
                               free_feedthrough: bool = False) -> IntervalDesign:
    """A fixed-order controller that keeps ΣAE(V) decaying over a whole speed interval.

    Stability over the interval first, the order second: a full-order LQG controller of the
    loop at the interval's top (:func:`full_order_start`) is continued down to its bottom
    (:func:`stabilize_interval`, anchor ``"high"``), then its order is lowered through
    ``orders`` to ``order`` (:func:`reduce_order`).  The paper's design goes the other way
    (γ at Vf, then as far as the order allows).  On the seed wing's scaled ROM with the servo
    (``problems/seed_wing/interval.toml``) that route stops at 1.43 Vf; this one holds
    (0, 2.22 Vf) at order 4 on the ROM loop and the wing itself to 2.19 Vf (continued on the
    wing, the same controller holds it to 2.23 Vf).  γ is not optimised: the verification
    layer measures it.

    Parameters
    ----------
    system : LoopFamily or sequence of LoopFamily
        The loop family, or several that the controller must hold together (as
        :func:`stabilize_interval`); the full-order start is the first one's.
    interval : (lo, hi)
        Speed-index interval, ``0 <= lo < hi``.
    order : int
        Controller order (>= 1).
    orders : tuple of int
        Intermediate orders of the reduction; those between ``order`` and the full order
        are used, highest first.
    decay : float
        Decay rate (rad/s) required at every speed of the interval.
    n_speeds : int
        Speeds of the continuations' objective.
    free_feedthrough : bool
        Optimise the controller's ``D`` as well (see :func:`stabilize_interval`).

    Returns
    -------
    IntervalDesign

    Raises
    ------
    ConfigError
        A bad interval, order or setting.

    See Also
    --------
    design_flutter_controller : the paper's design at Vf, with an interval continuation.
    """
    lo, hi = _speed_interval(interval)
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise ConfigError(f"order = {order!r}: an integer >= 1 (a dynamic controller)")
    models = _Models.of(system)
    start = full_order_start(models.families[0], hi)
    full = stabilize_interval(models, start, (lo, hi), anchor="high", decay=decay,
                              n_speeds=n_speeds, free_feedthrough=free_feedthrough)
    n = full.controller.nstates
    log.info("interval design: full order %d holds [%.4g, %.4g] (target [%.4g, %.4g])", n,
             *full.reached, lo, hi)
    if not full.met:
        return IntervalDesign(full.controller, int(order), full, None, False)
    if order >= n:
        return IntervalDesign(full.controller, int(order), full, None, True)
    seq = [int(o) for o in sorted(set(orders), reverse=True) if order < o < n] + [int(order)]
    red = reduce_order(models, full.controller, (lo, hi), seq, decay=decay,
                       free_feedthrough=free_feedthrough)
    low = red.lowest
    K = full.controller if low is None else low.controller
    return IntervalDesign(K, int(order), full, red, bool(low is not None and low.order == order))
