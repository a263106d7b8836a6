"""Multi-speed fixed-order synthesis on a plant family (paper §III.C over a speed interval).

The paper designs ``K(s)`` at Vf (eq. 14-16) and reports the speed interval over which the
loop stays stable.  Here the interval is the requirement, and the design takes any
:class:`~casflutter.aeroelastic.PlantFamily` (the ROM loop ΣAE(V) of eq. 8-9, a truth's
linearisation, state-space models on a grid of speeds, several models at once): one
controller of a given order such that the closed loop decays at the rate ``decay`` at every
speed of ``[lo, hi]`` for every model, then, among such controllers, the smallest worst H∞
objective over the speeds the budget allows.  It is a multi-model problem in the manner of
HIFOO (stabilise first, then minimise the worst H∞ norm over the plants) and of
hinfstruct/systune (the worst case over a set of models), with the speeds as the models:

0. **What the family allows.**  A mode that the controls do not reach or the measurements do
   not see is in every closed loop (:mod:`._out_of_reach`): where one does not decay, or
   decays slower than a ``decay`` given, the design is refused before any work; where the
   settings leave ``decay`` open (0.05) and such a mode is slower, the design asks for half
   its rate instead (a warning says so).
1. **Hold the interval.**  The worst closed-loop spectral abscissa over ``n_speeds`` speeds of
   an interval, smoothed by a log-sum-exp of decreasing temperature, is minimised over the
   controller's matrices by BFGS with the exact gradient of the rightmost eigenvalues
   (:class:`._speeds.SpeedLoops`) and the weak Wolfe line search of Lewis and Overton, which
   is made for the kinks of such a maximum (:func:`._bfgs.nonsmooth_bfgs`).  An interval
   counts as held when a dense scan (8x as many speeds, and three more in each gap beside
   its six highest local maxima, where a mode that crosses and comes back between two
   speeds shows its flanks) finds the rate ``decay`` everywhere; a peak the scan finds
   between the objective's speeds joins them and the interval is tried again.  This is
   continued in speed: starting where a controller already decays, one end is pushed towards
   the target, the step growing 1.5x after a success and halving after a failure.
2. **Starts.**  From the low end (where the open loop is usually stable) the target order is
   continued from a seeded controller with small couplings (near zero) and from seeded
   random ones with larger couplings.  When none reaches the top,
   a full-order observer-based (LQG) controller of the plant at the top is continued down to
   the low end (more states give the continuation room to pass a control reversal, where the
   phase a controller needs flips), and its order is then lowered to the target one step at a
   time (balanced truncation, re-held on the fixed interval, a step that misses split in
   half): continuation in the order.
3. **H∞ phase.**  From the controller that holds the interval,
   :func:`casflutter.design.synthesize` minimises the worst H∞ norm of the design plants over
   ``hinf_speeds`` speeds (the disturbance-to-sensor channels, with the control-rate weight
   where a servo saturates, or plants the caller gives, e.g. the paper's LFT at Vf; their
   norm is finite only where their loops are stable, so where the held controller does not
   stabilise them it is first re-held with them, or failing that the first start is
   continued over the interval with them) while the loops at the stability speeds
   keep their decay rate; the dense scan checks the result and where it finds a loop slower
   than the decay rate between the stability speeds, its peaks join them, the rate asked at
   them grows by a quarter (room for the loops between them) and the phase starts again
   from the held controller; the held controller is kept if the H∞ phase still loses the
   interval.

Every budget is counted in iterations and every random choice takes the seed, so the same seed
gives the same controller.  The interval the design reports is its own dense scan's; the
certificate is the verification layer's (:func:`casflutter.verify.verify_family`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import control
import numpy as np

from .._format import result_repr
from .._settings import build_settings, finite_numbers
from .._threads import single_threaded
from ..errors import ConfigError, DimensionError, SynthesisError
from ._bfgs import nonsmooth_bfgs
from ._out_of_reach import modes_out_of_reach
from ._plant import controller_only, partition
from ._problem import verify_closed_loop
from ._speeds import (DesignChannels, Scaling, SpeedLoops, design_partition,
                      unit_free_sensitivity)
from ._synthesis import (STABLE_CONTROLLER_NOTE, SynthesisOptions, SynthesisResult,
                         synthesize)

__all__ = ["MultiSpeedSettings", "MultiSpeedDesign", "HoldRecord", "design_over_speeds",
           "default_objective"]

log = logging.getLogger("casflutter.design")

#: the decay rate asked when the settings leave it open and the family allows it
DEFAULT_DECAY = 0.05
#: BFGS temperatures of the smoothed maximum in multiples of the decay rate, last the maximum
_TAUS = (6.0, 2.0, 0.6, None)
#: a BFGS run stops when 20 iterations lowered its objective by less than this many decay rates
_STALL = 0.01
#: seconds between the continuation's progress lines (only a large family takes that long)
_PROGRESS_S = 60.0
#: the dense scan's local maxima whose neighbouring gaps are scanned again, and how finely
_REFINED, _SUBDIVIDE = 6, 3


@dataclass(frozen=True)
class MultiSpeedSettings:
    """Settings of :func:`design_over_speeds` (checked on construction)."""

    __repr__ = result_repr

    decay: float | None = None
    """Decay rate [rad per time unit] the closed loop needs at every speed of the interval.
    ``None``: 0.05, or half the rate of the open loop's slowest decaying mode at the
    interval's low end, or of the slowest mode that no controller moves, where that is
    slower (the log says so); a rate given that a mode no controller moves does not allow
    is refused before any work."""
    n_speeds: int = 16
    """Speeds of the stability objective on each interval tried (the dense check uses 8x,
    refined beside its highest local maxima)."""
    hinf_speeds: int = 5
    """Speeds of the H∞ objective spread over the interval (0: no H∞ phase)."""
    rate_weight: float = 0.0
    """Weight of the control-rate outputs of the H∞ plants (:class:`._speeds.DesignChannels`;
    0: none)."""
    rate_bandwidth: float = 1.0
    """Bandwidth [rad per time unit] of the control-rate filter (e.g. the servo's)."""
    sensitivity: bool = False
    """The H∞ plants' channels: at each speed the output and the input sensitivity of the
    loop (whose diagonal entries bound the loop-at-a-time margins) instead of the family's
    disturbances to the measurements (:class:`._speeds.DesignChannels`); where the family
    declares its measurements (or controls) in different units, in the design's scaled
    signals, so that their norm does not depend on the units
    (:func:`._speeds.unit_free_sensitivity`)."""
    strictly_proper: bool | None = None
    """Keep ``Dk = 0``; ``None``: strictly proper exactly when some model's controls reach its
    measurements directly (a feed-through would close an algebraic loop that can become
    singular at some speed)."""
    stable_controller: bool = False
    """Keep the controller's own poles decaying at the rate ``decay`` too, in every phase
    (systune's controller-pole requirement): the loop then stays stable when it is opened,
    e.g. by a sensor or actuator that drops out or for a ground test.  Without it a
    controller may be unstable itself (the run's pole check warns)."""
    random_starts: int = 2
    """Seeded random starts at the target order from the low end, after the first one (a
    seeded controller with small couplings, near zero)."""
    full_order: bool = True
    """Continue a full-order LQG controller of the top speed down to the low end, and lower
    its order, when no low-order start reaches the top."""
    reduction_orders: tuple = (20, 14, 10, 8, 6)
    """Intermediate orders of the order continuation (those between the target and the full
    order are used, highest first; a step that misses is split in half)."""
    max_iter: int = 200
    """BFGS iterations per temperature of the smoothed maximum."""
    max_rounds: int = 200
    """Continuation steps at most, per start."""
    first_step: float = 0.05
    """First continuation step, as a fraction of the interval's length."""
    min_step: float = 0.001
    """Smallest continuation step, as a fraction of the interval's length."""
    synthesis: SynthesisOptions = field(default_factory=lambda: SynthesisOptions(
        max_outer=60, extra_outer=240, max_stab_rounds=100, full_order_start=False))
    """Settings of the H∞ phase (:func:`casflutter.design.synthesize`; its ``decay``,
    ``strictly_proper``, ``stable_controller`` and ``zero_start`` are set by the design, and
    its ``qp_solver`` left open is qpOASES)."""

    def __post_init__(self):
        if isinstance(self.synthesis, Mapping):
            object.__setattr__(self, "synthesis",
                               build_settings(SynthesisOptions, self.synthesis, "synthesis"))
        checks = {"decay": (self.decay is None or (isinstance(self.decay, (int, float))
                                                    and math.isfinite(self.decay)
                                                    and self.decay >= 0),
                            "a number >= 0, or None to have it chosen"),
                  "n_speeds": (int(self.n_speeds) == self.n_speeds and self.n_speeds >= 2,
                               "an integer >= 2"),
                  "hinf_speeds": (int(self.hinf_speeds) == self.hinf_speeds
                                  and self.hinf_speeds >= 0, "an integer >= 0"),
                  "rate_weight": (math.isfinite(self.rate_weight) and self.rate_weight >= 0,
                                  "a number >= 0"),
                  "rate_bandwidth": (math.isfinite(self.rate_bandwidth)
                                     and self.rate_bandwidth > 0, "a number > 0"),
                  "random_starts": (int(self.random_starts) == self.random_starts
                                    and self.random_starts >= 0, "an integer >= 0"),
                  "reduction_orders": (all(int(o) == o and o >= 1
                                           for o in self.reduction_orders),
                                       "integers >= 1"),
                  "max_iter": (int(self.max_iter) == self.max_iter and self.max_iter >= 1,
                               "an integer >= 1"),
                  "max_rounds": (int(self.max_rounds) == self.max_rounds
                                 and self.max_rounds >= 1, "an integer >= 1"),
                  "first_step": (0 < self.first_step <= 1, "a number in (0, 1]"),
                  "min_step": (0 < self.min_step <= self.first_step,
                               "a number in (0, first_step]")}
        bad = [f"{k} = {getattr(self, k)!r}: give {need}"
               for k, (ok, need) in checks.items() if not ok]
        if bad:
            raise ConfigError(f"{'; '.join(bad)} (MultiSpeedSettings)")


@dataclass(frozen=True)
class HoldRecord:
    """One start of the design: how far it held the interval.

    Attributes
    ----------
    kind : str
        ``"given"`` (a controller the caller gave), ``"random"`` (a seeded one) or
        ``"full-order"``.
    order : int
        Order of the controller it ended with.
    reached : tuple of float
        ``(lo, hi)`` it holds at the rate ``decay`` on the dense scan (``()`` if it held
        nothing).
    worst_abscissa : float
        Largest closed-loop spectral abscissa on the dense scan of ``reached``.
    steps : int
        Continuation and order steps taken.
    wall_time : float
        Seconds.
    """

    __repr__ = result_repr

    kind: str
    order: int
    reached: tuple
    worst_abscissa: float
    steps: int
    wall_time: float


@dataclass(frozen=True)
class MultiSpeedDesign:
    """Outcome of :func:`design_over_speeds`.

    Attributes
    ----------
    controller : control.StateSpace
        ``K(s)`` from the measurements to the controls (named as the first family names
        them), applied with the family's own ``feedback`` convention.
    order : int
        Its order.
    interval : tuple of float
        The requested ``(lo, hi)``.
    reached : tuple of float
        ``(lo, V)``: the interval from ``lo`` on which the loop decays at the rate ``decay``
        on the design's dense scan, for every model.
    held : bool
        ``reached`` is the requested interval at the requested order.
    worst_abscissa : float
        Largest closed-loop spectral abscissa on the dense scan of ``reached``.
    gamma : float
        Worst H∞ norm of the design plants at ``hinf_speeds`` (``nan`` without an H∞ phase);
        with a control-rate weight it includes the weighted rate.
    hinf_speeds : tuple of float
        Speeds of the H∞ plants.
    synthesis : SynthesisResult or None
        The H∞ phase.
    starts : tuple of HoldRecord
        Every start, in the order tried.
    message : str
        What was held, in a sentence.
    wall_time : float
        Seconds.
    decay : float
        The decay rate held: the settings' unless a mode no controller moves decays slower
        (then half that mode's rate).
    """

    __repr__ = result_repr

    controller: control.StateSpace
    order: int
    interval: tuple
    reached: tuple
    held: bool
    worst_abscissa: float
    gamma: float
    hinf_speeds: tuple
    synthesis: SynthesisResult | None
    starts: tuple
    message: str
    wall_time: float
    decay: float


def _peaks(values: np.ndarray, threshold: float, most: int = 8) -> list[int]:
    """Indices of the ``most`` highest local maxima of a dense scan above ``threshold``."""
    n = len(values)
    peaks = [j for j in range(n) if values[j] > threshold and values[j] >= values[max(j - 1, 0)]
             and values[j] >= values[min(j + 1, n - 1)]]
    return sorted(peaks, key=lambda j: (-values[j], j))[:most]


class _Models:
    """The families a controller must hold together, their design plants at a speed (cached),
    fixed plants it may be asked to hold besides (the caller's H∞ plants, whose objective is
    finite only where their loop is stable) and the scaling shared by the whole design."""

    def __init__(self, families: Sequence, lo: float, hi: float,
                 fixed: Sequence[control.StateSpace] = (), *, own: bool = False):
        self.families = tuple(families)
        sizes = {(len(f.signals.controls), len(f.signals.measurements)) for f in self.families}
        if len(sizes) != 1:
            raise DimensionError(f"the models have different numbers of controls and "
                                 f"measurements {sorted(sizes)}; one controller needs the same "
                                 "controls and measurements on every model")
        self.nu, self.ny = sizes.pop()
        self.fixed = [partition(P, self.ny, self.nu) for P in fixed]
        self.own = bool(own)
        self._cache: dict = {}
        self._fixed_cache: dict = {}
        self._own_cache: dict = {}
        probe = np.linspace(lo, hi, 5)
        parts = [p for V in probe for p in self.parts(V)]
        self.scaling = Scaling.of(parts)
        self.has_d22 = any(np.any(p.D22 != 0) for V in np.linspace(lo, hi, 9)
                           for p in self.parts(V))

    def parts(self, V: float) -> list:
        """The unscaled design plants (without rate outputs) of every model at ``V``."""
        key = float(V)
        if key not in self._cache:
            if len(self._cache) > 4096:
                self._cache.clear()
            self._cache[key] = [design_partition(f, key) for f in self.families]
        return self._cache[key]

    def fixed_plants(self, order: int) -> list:
        """The fixed plants scaled and augmented with ``order`` controller states (cached)."""
        if order not in self._fixed_cache:
            self._fixed_cache[order] = [self.scaling.plant(p, order) for p in self.fixed]
        return self._fixed_cache[order]

    def own_plants(self, order: int) -> list:
        """With ``own``, the plant whose loop is the controller alone (no states of its own,
        no paths: the closed loop's state matrix is ``Ak``), scaled and augmented with
        ``order`` controller states; else none."""
        if not self.own or order == 0:
            return []
        if order not in self._own_cache:
            self._own_cache[order] = [self.scaling.plant(controller_only(self.ny, self.nu),
                                                         order)]
        return self._own_cache[order]

    def fixed_abscissa(self, K: np.ndarray, order: int) -> float:
        """The worst spectral abscissa of the fixed plants' loops closed by ``K`` (scaled
        time; ``-inf`` without fixed plants)."""
        if not self.fixed:
            return -np.inf
        loops = SpeedLoops(self.fixed_plants(order), np.zeros(K.shape, bool), K)
        return float(np.max(loops.abscissae(np.zeros(0))))

    def loops(self, speeds, order: int, free: np.ndarray, base: np.ndarray, *,
              fixed: bool = False) -> SpeedLoops:
        """The scaled closed loops of every model at ``speeds`` (and of the fixed plants)."""
        sc = self.scaling
        extra = (self.fixed_plants(order) if fixed else []) + self.own_plants(order)
        return SpeedLoops([sc.plant(p, order) for V in speeds for p in self.parts(V)] + extra,
                          free, base)

    def scan(self, K: np.ndarray, order: int, speeds, *, fixed: bool = False) -> np.ndarray:
        """The worst closed-loop spectral abscissa over the models at each of ``speeds``, and
        with ``fixed`` over the fixed plants too (scaled time; ``inf`` where a loop is ill
        posed)."""
        free = np.zeros(K.shape, bool)
        none = np.zeros(0)
        values = np.array([float(np.max(self.loops([V], order, free, K).abscissae(none)))
                           for V in speeds])
        if fixed and values.size:
            values = np.maximum(values, self.fixed_abscissa(K, order))
        return values

    def dense(self, K: np.ndarray, order: int, lo: float, hi: float, n: int, *,
              fixed: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """A dense scan of ``[lo, hi]``: ``n`` equally spaced speeds, then ``_SUBDIVIDE``
        more in each gap beside the ``_REFINED`` highest local maxima (a closed-loop mode
        can cross and come back between two speeds of the grid, and its flanks show as a
        local maximum); the speeds in order and :meth:`scan`'s values at them."""
        grid = np.linspace(lo, hi, n) if hi > lo else np.array([lo])
        values = self.scan(K, order, grid, fixed=fixed)
        if grid.size < 3:
            return grid, values
        extra = set()
        for j in _peaks(values, -np.inf, _REFINED):
            for a in (j - 1, j):
                if 0 <= a < grid.size - 1:
                    extra.update(np.linspace(grid[a], grid[a + 1], _SUBDIVIDE + 2)[1:-1])
        more = np.array(sorted(extra))
        speeds = np.concatenate([grid, more])
        values = np.concatenate([values, self.scan(K, order, more, fixed=fixed)])
        rank = np.argsort(speeds, kind="stable")
        return speeds[rank], values[rank]


@dataclass
class _Engine:
    """Holding an interval, continuing it in speed and in the order (module docstring)."""

    models: _Models
    settings: MultiSpeedSettings
    strictly_proper: bool

    @property
    def decay(self) -> float:
        """The decay rate in the scaled time (of the settings :func:`_reachable_decay`
        resolved)."""
        return self.settings.decay / self.models.scaling.w0

    def free(self, order: int) -> np.ndarray:
        nu, ny = self.models.nu, self.models.ny
        F = np.ones((nu + order, ny + order), bool)
        if self.strictly_proper:
            F[:nu, :ny] = False
        return F

    def worst(self, K: np.ndarray, lo: float, hi: float, *, fixed: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
        return self.models.dense(K, K.shape[0] - self.models.nu, lo, hi,
                                 8 * self.settings.n_speeds, fixed=fixed)

    def _minimise(self, loops: SpeedLoops, q: np.ndarray, good: float
                  ) -> tuple[np.ndarray, float]:
        """BFGS on the smoothed worst abscissa at each temperature in turn, keeping a result
        only when it lowers the worst; stops once the worst is at most ``good``, and so does
        each BFGS run (the log-sum-exp lies above the maximum).  A loop pushed further below
        ``good`` than asked is one the H∞ phase then has to undo: on goland_4flaps (orders 2
        and 3, seeds 0-5) stopping there gave a smaller worst H∞ norm in 10 of 12 designs
        (median 1.44 against 3.53 at order 2, 4.68 against 13.9 at order 3)."""
        best = loops.smoothed(q, None, lazy=True)[0]
        unit = self.decay if self.decay > 0 else 0.01
        for tau in _TAUS:
            if best <= good:
                break
            scale = None if tau is None else tau * unit
            res = nonsmooth_bfgs(lambda p: loops.smoothed(p, scale, lazy=True), q,
                                 max_iter=int(self.settings.max_iter),
                                 target=good, stall=_STALL * unit)
            if not np.all(np.isfinite(res.x)):
                continue
            worst = loops.smoothed(res.x, None, lazy=True)[0]
            if worst < best:
                q, best = res.x, worst
        return q, float(best)

    def hold(self, K: np.ndarray, lo: float, hi: float, *, fixed: bool = False
             ) -> tuple[np.ndarray, float, bool]:
        """``K`` re-optimised to decay at the rate ``decay`` on ``[lo, hi]`` (with ``fixed``
        the fixed plants' loops too): ``(K, worst on the dense scan (scaled), held)``; a scan
        peak joins the objective's speeds, twice at most."""
        order = K.shape[0] - self.models.nu
        free = self.free(order)
        speeds = np.linspace(lo, hi, self.settings.n_speeds)
        q = K[free]
        worst = np.inf
        for _ in range(3):
            loops = self.models.loops(speeds, order, free, K, fixed=fixed)
            q, worst = self._minimise(loops, q, -2.0 * self.decay)
            if worst > -self.decay:
                break
            scan, values = self.worst(loops.gain(q), lo, hi, fixed=fixed)
            worst = float(np.max(values))
            if worst <= -self.decay:
                return loops.gain(q), worst, True
            speeds = np.union1d(speeds, scan[_peaks(values, -self.decay)])
        return loops.gain(q), worst, False

    def edge(self, K: np.ndarray, lo: float, hi: float, anchor: str, *, fixed: bool = False
             ) -> float | None:
        """How far from the anchor end ``K`` already decays at the rate ``decay`` (``None``
        if not even at the anchor)."""
        scan, values = self.worst(K, lo, hi, fixed=fixed)
        ok = values <= -self.decay
        if anchor == "high":
            scan, ok = scan[::-1], ok[::-1]
        if not ok[0]:
            return None
        bad = np.flatnonzero(~ok)
        return float(scan[-1] if bad.size == 0 else scan[bad[0] - 1])

    def continue_interval(self, K: np.ndarray, lo: float, hi: float, anchor: str, *,
                          fixed: bool = False) -> tuple[np.ndarray, tuple, int]:
        """Continuation in speed from the ``anchor`` end: ``(K, (a, b) held, steps)``;
        ``()`` when ``K`` does not decay at the anchor and cannot be made to there.  With
        ``fixed`` every step holds the fixed plants' loops too."""
        e = self.edge(K, lo, hi, anchor, fixed=fixed)
        if e is None:
            # first hold the anchor speed alone
            end = lo if anchor == "low" else hi
            K, _, ok = self.hold(K, end, end, fixed=fixed)
            e = self.edge(K, lo, hi, anchor, fixed=fixed) if ok else None
            if e is None:
                return K, (), 1
        cur = (lo, e) if anchor == "low" else (e, hi)
        s = self.settings
        step, smallest, rounds = s.first_step * (hi - lo), s.min_step * (hi - lo), 0
        t0 = last = time.perf_counter()
        while cur != (lo, hi) and step >= smallest and rounds < s.max_rounds:
            rounds += 1
            step = min(step, (hi - cur[1]) if anchor == "low" else (cur[0] - lo))
            trial = ((cur[0], min(hi, cur[1] + step)) if anchor == "low"
                     else (max(lo, cur[0] - step), cur[1]))
            Kn, worst, ok = self.hold(K, *trial, fixed=fixed)
            log.debug("continuation (%s end): [%.5g, %.5g] worst abscissa %.4g -> %s", anchor,
                      *trial, worst * self.models.scaling.w0, "kept" if ok else "halved")
            if ok:
                # the new controller may hold beyond the trial: start the next step there
                e = self.edge(Kn, *((trial[0], hi) if anchor == "low" else (lo, trial[1])),
                              anchor, fixed=fixed)
                if e is not None:
                    trial = (trial[0], max(trial[1], e)) if anchor == "low" else \
                        (min(trial[0], e), trial[1])
                K, cur, step = Kn, trial, 1.5 * step
            else:
                step *= 0.5
            if time.perf_counter() - last > _PROGRESS_S:   # a large family: say it works
                last = time.perf_counter()
                log.info("continuation from the %s end: holds [%.5g, %.5g] of [%.5g, %.5g] "
                         "after %d steps, %.0f s", anchor, *cur, lo, hi, rounds, last - t0)
        return K, cur, rounds

    # ------------------------------------------------------------------ starts
    def random_start(self, order: int, rng: np.random.Generator, scale: float) -> np.ndarray:
        """A seeded random controller of ``order`` in the scaled gain: stable ``Ak`` near
        ``−I`` (the plants' time scale) and couplings of size ``scale``."""
        nu, ny = self.models.nu, self.models.ny
        K = np.zeros((nu + order, ny + order))
        K[nu:, ny:] = -np.eye(order) + 0.3 * rng.standard_normal((order, order))
        K[:nu, ny:] = scale * rng.standard_normal((nu, order))
        K[nu:, :ny] = scale * rng.standard_normal((order, ny))
        if not self.strictly_proper:
            K[:nu, :ny] = scale * rng.standard_normal((nu, ny))
        return K

    def lqg_start(self, V: float, state_weight: float = 0.01, noise_ratio: float = 1.0
                  ) -> np.ndarray | None:
        """A full-order observer-based (LQG) controller of the first model at ``V`` in the
        scaled gain (strictly proper), or ``None`` when the Riccati equations have no
        stabilising solution (an unstable mode the controls cannot reach or the
        measurements cannot see)."""
        sc = self.models.scaling
        P = sc.plant(self.models.parts(V)[0], 0)
        n, nu, ny = P.A.shape[0], self.models.nu, self.models.ny
        try:
            Kx = np.asarray(control.lqr(P.A, P.B2, state_weight * np.eye(n), np.eye(nu))[0])
            L = np.asarray(control.lqe(P.A, np.eye(n), P.C2, np.eye(n),
                                       noise_ratio * np.eye(ny))[0])
        except (ValueError, np.linalg.LinAlgError, control.ControlArgument) as exc:
            log.debug("full-order start at V = %.5g: no LQG controller (%s)", V, exc)
            return None
        if not (np.all(np.isfinite(Kx)) and np.all(np.isfinite(L))):
            return None
        K = np.zeros((nu + n, ny + n))
        K[:nu, ny:] = -Kx
        K[nu:, :ny] = L
        K[nu:, ny:] = P.A - P.B2 @ Kx - L @ P.C2 + L @ P.D22 @ Kx
        return K

    # ------------------------------------------------------------------ order
    def truncate(self, K: np.ndarray, order: int) -> np.ndarray | None:
        """The balanced truncation of ``K`` to ``order`` (unstable modes kept), or ``None``
        when ``K`` has more unstable modes than that."""
        nu, ny = self.models.nu, self.models.ny
        Dk, Ck, Bk, Ak = K[:nu, :ny], K[:nu, ny:], K[nu:, :ny], K[nu:, ny:]
        try:
            Kr = control.balred(control.ss(Ak, Bk, Ck, Dk), order, method="truncate")
        except (ValueError, np.linalg.LinAlgError) as exc:
            log.debug("order %d: no truncation (%s)", order, exc)
            return None
        Ar, Br, Cr = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (Kr.A, Kr.B, Kr.C))
        if Ar.shape[0] != order:
            return None
        out = np.zeros((nu + order, ny + order))
        out[:nu, :ny] = Dk
        out[:nu, ny:] = Cr.reshape(nu, order)
        out[nu:, :ny] = Br.reshape(order, ny)
        out[nu:, ny:] = Ar
        return out

    def reduce(self, K: np.ndarray, lo: float, hi: float, order: int
               ) -> tuple[np.ndarray, int]:
        """Continuation in the order: ``K`` (which holds ``[lo, hi]``) truncated through the
        settings' intermediate orders to ``order``, each step re-held on the interval, a step
        of more than one order that misses split in half.  Returns the lowest-order
        controller that holds the interval and the steps taken."""
        nu = self.models.nu
        n = K.shape[0] - nu
        queue = [o for o in sorted(set(self.settings.reduction_orders), reverse=True)
                 if order < o < n] + [order]
        steps = 0
        while queue and K.shape[0] - nu > order:
            target, cur = queue[0], K.shape[0] - nu
            steps += 1
            Kr = self.truncate(K, target)
            held = False
            if Kr is not None:
                Kr, worst, held = self.hold(Kr, lo, hi)
                log.debug("order continuation: %d -> %d: worst abscissa %.4g -> %s", cur,
                          target, worst * self.models.scaling.w0, "held" if held else "missed")
            if held:
                K = Kr
                queue.pop(0)
            elif cur - target > 1:
                queue.insert(0, (cur + target) // 2)
            else:
                break
        return K, steps


def default_objective(family) -> str:
    """The H∞ objective of the multi-speed design on ``family`` when the caller names none.

    Parameters
    ----------
    family : PlantFamily
        The family.

    Returns
    -------
    str
        ``"sensors"`` (its disturbances to its measurements) when the family names
        disturbance inputs, else ``"sensitivity"`` (the loop's output and input
        sensitivities, which bound every loop-at-a-time margin).
    """
    return "sensors" if family.signals.disturbances else "sensitivity"


def _families(family) -> tuple:
    fams = tuple(family) if isinstance(family, (list, tuple)) else (family,)
    if not fams or not all(callable(getattr(f, "plant", None)) and hasattr(f, "signals")
                           for f in fams):
        raise ConfigError("family must be a casflutter.aeroelastic.PlantFamily (plant(V), "
                          "signals) or a non-empty sequence of them")
    return fams


def _interval(interval, fams) -> tuple[float, float]:
    lo, hi = finite_numbers("interval", interval, 2, what="two numbers (lo, hi)")
    if not lo < hi:
        raise ConfigError(f"interval = {[lo, hi]!r}: need lo < hi")
    for f in fams:
        a, b = f.speed_range
        if lo < a or hi > b:
            raise ConfigError(f"interval = {[lo, hi]!r} leaves the speed range [{a:g}, {b:g}] "
                              f"{f.speed_unit} of {f.name}; design inside it")
    return lo, hi


def _padded(P, dims: tuple) -> control.StateSpace:
    """A stability plant with zero ``w`` and ``z`` channels of the H∞ plants' sizes."""
    nx, nu, ny = P.A.shape[0], P.B2.shape[1], P.C2.shape[0]
    bare = replace(P, B1=np.zeros((nx, 0)), C1=np.zeros((0, nx)), D11=np.zeros((0, 0)),
                   D12=np.zeros((0, nu)), D21=np.zeros((ny, 0)))
    return _as_ss(bare, *dims)


def _as_ss(P, nw: int = 0, nz: int = 0) -> control.StateSpace:
    """The partitioned plant ``P`` as one state-space system, its ``w`` and ``z`` padded
    with zero channels to at least ``nw`` and ``nz`` (plants of one synthesis share their
    sizes; zero channels leave the norm as it is)."""
    pw, pz = max(0, nw - P.B1.shape[1]), max(0, nz - P.C1.shape[0])
    nx, nu, ny = P.A.shape[0], P.B2.shape[1], P.C2.shape[0]
    return replace(P, B1=np.hstack([P.B1, np.zeros((nx, pw))]),
                   C1=np.vstack([P.C1, np.zeros((pz, nx))]),
                   D11=np.pad(P.D11, ((0, pz), (0, pw))),
                   D12=np.vstack([P.D12, np.zeros((pz, nu))]),
                   D21=np.hstack([P.D21, np.zeros((ny, pw))])).statespace()


def design_over_speeds(family, interval, order: int = 3, *,
                       settings: MultiSpeedSettings | Mapping[str, Any] | None = None,
                       seed: int = 0, initial: Sequence = (),
                       hinf_plants: Sequence[control.StateSpace] | None = None
                       ) -> MultiSpeedDesign:
    """One fixed-order controller that keeps a plant family decaying over a speed interval,
    with the smallest worst H∞ objective over the speeds the budget finds (module docstring).

    Parameters
    ----------
    family : PlantFamily or sequence of PlantFamily
        The family (or several, with the same numbers of controls and measurements, that
        one controller must hold together: the worst of them at every speed).
    interval : (lo, hi)
        Speeds, inside every family's range.
    order : int
        Controller order (>= 1 when strictly proper, else >= 0).
    settings : MultiSpeedSettings or dict, optional
        Algorithm settings.
    seed : int
        Seed of the random starts (the same seed gives the same controller).
    initial : sequence of control.StateSpace
        Controllers to start from, first (in the family's convention, e.g. a design at one
        speed); of the target order or lower (padded with decoupled stable states).
    hinf_plants : sequence of control.StateSpace, optional
        H∞ plants in the partitioned form of :func:`synthesize` (inputs ``[w, u]``, outputs
        ``[z, y]``, ``u = +K y``), e.g. the paper's LFT at Vf (eq. 14); default the
        disturbance-to-sensor channels of every model at ``hinf_speeds`` speeds.  Where the
        controller that holds the interval does not stabilise them (their norm is finite
        only where it does), it is first re-held with their loops at the decay rate.

    Returns
    -------
    MultiSpeedDesign
        The requested order; when no controller of it held the interval, the one with the
        farthest reach from ``lo``, and ``held`` false (the message says so).

    Raises
    ------
    ConfigError
        A bad interval (outside a family's range), order or setting; a family with a mode
        that no controller moves (the controls do not reach it or the measurements do not
        see it) and that does not decay, or decays slower than the ``settings.decay`` given,
        named.  Where the settings leave ``decay`` open, the design asks for half such a
        mode's rate instead and logs a warning.
    DimensionError
        Families with different numbers of controls and measurements, or H∞ plants that do
        not fit them.
    SynthesisError
        When no start holds even the low end of the interval.

    See Also
    --------
    casflutter.verify.verify_family : the independent certificate of the interval.
    """
    t0 = time.perf_counter()
    fams = _families(family)
    lo, hi = _interval(interval, fams)
    if isinstance(settings, Mapping):
        settings = build_settings(MultiSpeedSettings, settings, "settings")
    s = settings or MultiSpeedSettings()
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
        raise ConfigError(f"order = {order!r}: an integer >= 0")
    order = int(order)
    with single_threaded():
        models = _Models(fams, lo, hi, fixed=[control.ss(P) for P in hinf_plants or ()],
                         own=s.stable_controller)
        s = _reachable_decay(models, s, lo, hi)
        sp = models.has_d22 if s.strictly_proper is None else bool(s.strictly_proper)
        if sp and order == 0:
            raise ConfigError("order = 0 with a strictly proper controller leaves nothing to "
                              "design; ask for order >= 1 (or strictly_proper = False)")
        eng = _Engine(models, s, sp)
        records, held, best = [], None, None
        rng = np.random.default_rng(seed)
        plan = [("given", _given(models.scaling, K, order, models.nu, models.ny))
                for K in initial]
        plan += [("random", eng.random_start(order, rng, 0.05 if i == 0 else 0.5))
                 for i in range(1 + s.random_starts)]
        for kind, K0 in plan:
            t = time.perf_counter()
            K, reached, steps = eng.continue_interval(K0, lo, hi, "low")
            rec = _record(eng, kind, K, reached, steps, t)
            records.append(rec)
            log.info("start %d (%s): holds %s", len(records), kind, _fmt(reached))
            if reached and (best is None or reached[1] > best[1][1] * (1 + 1e-9)):
                best = (K, reached)
            if reached == (lo, hi):
                held = K
                break
        if held is None and s.full_order:
            t = time.perf_counter()
            K0 = eng.lqg_start(hi)
            if K0 is not None:
                Kf, reached, steps = eng.continue_interval(K0, lo, hi, "high")
                log.info("start %d (full order %d from the top): holds %s", len(records) + 1,
                         K0.shape[0] - models.nu, _fmt(reached))
                if reached == (lo, hi):
                    Kr, more = eng.reduce(Kf, lo, hi, order)
                    steps += more
                    if Kr.shape[0] - models.nu == order:
                        held = Kr
                    else:
                        Kf = Kr
                records.append(_record(eng, "full-order", held if held is not None else Kf,
                                       reached if held is not None or reached != (lo, hi)
                                       else (lo, hi), steps, t))
                if held is not None:
                    best = (held, (lo, hi))
        if best is None:
            note = f" ({STABLE_CONTROLLER_NOTE})" if s.stable_controller else ""
            raise SynthesisError(
                f"no start of order {order} decays at the rate {s.decay:g} even at the low end "
                f"V = {lo:g} of the interval{note}"
                "; check that the plant is stabilisable there, or lower the decay rate",
                best_spectral_abscissa=float("nan"))
        K, reached = (held, (lo, hi)) if held is not None else best
        return _finish(eng, fams, K, order, (lo, hi), reached, held is not None, records,
                       hinf_plants, plan[0][1], t0)


def _reachable_decay(models: _Models, s: MultiSpeedSettings, lo: float, hi: float
                     ) -> MultiSpeedSettings:
    """The settings with a decay rate the family allows.

    A mode that the controls do not reach or the measurements do not see stays in every
    closed loop (:mod:`._out_of_reach`).  Where one decays slower than the rate asked at one
    of five speeds of the interval, no controller can meet that rate: a rate the settings
    give is refused, and where they leave it open the design asks for half the slowest such
    mode's rate instead of ``DEFAULT_DECAY``, and says so.  Where one does not decay at all,
    no controller stabilises the family: refused before any work.  A rate left open is then
    lowered further where the open loop is slower still (:func:`_open_loop_decay`).
    """
    asked = DEFAULT_DECAY if s.decay is None else float(s.decay)
    slowest = None
    for V in np.linspace(lo, hi, 5):
        for fam, P in zip(models.families, models.parts(V)):
            for mode in modes_out_of_reach(P.A, P.B2, P.C2, asked)[:1]:
                if slowest is None or mode.eigenvalue.real > slowest[1].eigenvalue.real:
                    slowest = (float(V), mode, fam)
    if slowest is None:
        return replace(s, decay=asked if s.decay is not None
                       else _open_loop_decay(models, lo, asked))
    V, mode, fam = slowest
    where = f"{fam.name} at V = {V:.5g} {fam.speed_unit}"
    rate = -mode.eigenvalue.real
    if rate <= 0:
        raise ConfigError(
            f"{where}: {mode.describe()} does not decay, and no controller moves it, so none "
            "can stabilise the family; give the family a control that reaches it and a "
            "measurement that sees it, or leave the mode out (e.g. rigid-body positions "
            "that the sensors do not measure: a family file's states with poles at the "
            "origin that feed no output and no other state are left out when it loads, and "
            "from Python family.without_states(family.detached_states()) leaves them out of "
            "a GriddedFamily)")
    what = (f"{where}: {mode.describe()} decays at only {rate:.4g} per {fam.time_unit} and "
            f"no controller moves it, so no loop decays at the rate {asked:g}")
    if s.decay is not None:
        raise ConfigError(f"{what} asked; ask for a decay rate below {rate:.4g} (e.g. "
                          f"{0.5 * rate:.3g}), or leave it out to have it chosen")
    log.warning("%s; the design asks for %.4g (half that mode's rate)", what, 0.5 * rate)
    return replace(s, decay=_open_loop_decay(models, lo, 0.5 * rate))


def _open_loop_decay(models: _Models, lo: float, default: float) -> float:
    """The decay rate asked where the settings leave it open: ``default``, or half the rate
    of the open loop's slowest decaying mode at ``lo`` where that is slower.

    A rate the open loop does not have is a requirement the controller must meet by moving
    that mode, and a slow mode moved from far (an aircraft's phugoid, decaying at 0.001 /s,
    asked to decay at 0.05 /s: 35 times its own rate) costs low-frequency gain and with it
    the loop's margins (on a 65-state aircraft-like family, 0.1 dB and a controller that is
    unstable itself).  The interval's low end is taken because there the open loop is
    usually stable and a mode that crosses higher up (the flutter mode) is still well
    damped; a mode that grows at ``lo``, or sits on the imaginary axis, is not counted (the
    loop must make it decay at the rate asked).
    """
    slowest = None
    for fam, P in zip(models.families, models.parts(lo)):
        lam = np.linalg.eigvals(P.A) if P.A.size else np.zeros(0)
        # a pole on the axis that rounding puts at -1e-15 (a position, an integrator) does
        # not decay: it would make the rate asked zero
        axis = 1e-9 * max(1.0, float(np.max(np.abs(lam), initial=0.0)))
        decaying = lam[lam.real < -axis]
        if decaying.size:
            mode = decaying[int(np.argmax(decaying.real))]
            if slowest is None or mode.real > slowest[1].real:
                slowest = (fam, mode)
    if slowest is None or -0.5 * slowest[1].real >= default:
        return default
    fam, mode = slowest
    rate = -0.5 * float(mode.real)
    log.info("%s at V = %.5g %s: its slowest mode decays at only %.4g per %s (at %.4g rad "
             "per %s); the design asks the loop for %.4g (half that) rather than make the "
             "controller move it to %g (give controller.interval_decay to ask for more)",
             fam.name, lo, fam.speed_unit, -float(mode.real), fam.time_unit,
             abs(float(mode.imag)), fam.time_unit, rate, default)
    return rate


def _units(family, side: str) -> tuple:
    """The units of the signals a sensitivity channel of ``side`` weighs: the family's
    measurements' (``"output"``) or controls' (``"input"``); none for ``""``."""
    sig = family.signals
    if side == "output":
        return tuple(sig.output_units[i] for i in sig.output_index())
    if side == "input":
        return tuple(sig.input_units[i] for i in sig.input_index())
    return ()


def _fmt(reached: tuple) -> str:
    return "nothing" if not reached else f"[{reached[0]:.5g}, {reached[1]:.5g}]"


def _given(sc: Scaling, K, order: int, nu: int, ny: int) -> np.ndarray:
    """The scaled gain of a given controller, padded to ``order`` with decoupled states at
    the plants' time scale."""
    K = control.ss(K)
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (K.A, K.B, K.C, K.D))
    k = K.nstates
    if Dk.shape != (nu, ny):
        raise DimensionError(f"an initial controller maps {Dk.shape[1]} inputs to "
                             f"{Dk.shape[0]} outputs; the family needs {ny} measurements to "
                             f"{nu} controls")
    if k > order:
        raise DimensionError(f"an initial controller has order {k} > the requested {order}")
    A = -sc.w0 * np.eye(order)
    B, C = np.zeros((order, ny)), np.zeros((nu, order))
    if k:
        A[:k, :k], B[:k], C[:, :k] = Ak, Bk.reshape(k, ny), Ck.reshape(nu, k)
    return sc.gain(A, B, C, Dk)


def _record(eng: _Engine, kind: str, K: np.ndarray, reached: tuple, steps: int, t: float
            ) -> HoldRecord:
    worst = (float(np.max(eng.worst(K, *reached)[1])) * eng.models.scaling.w0 if reached
             else float("nan"))
    return HoldRecord(kind, K.shape[0] - eng.models.nu, tuple(float(v) for v in reached),
                      worst, int(steps), time.perf_counter() - t)


def _controller(eng: _Engine, K: np.ndarray) -> control.StateSpace:
    Ak, Bk, Ck, Dk = eng.models.scaling.controller(K)
    return control.ss(Ak, Bk, Ck, Dk)


def _hold_fixed(eng: _Engine, K: np.ndarray, Kss, lo: float, e: float, first: np.ndarray):
    """Where the held controller does not stabilise the caller's H∞ plants (their norm is
    finite only where it does), a controller that holds ``[lo, e]`` with them: the held one
    re-held, else the first start continued in speed with them from ``lo`` (the held
    controller can be far from any that stabilises them): ``(K, Kss)``, the held controller
    where neither succeeds."""
    if eng.models.fixed_abscissa(K, K.shape[0] - eng.models.nu) <= -eng.decay:
        return K, Kss
    Kf, _, ok = eng.hold(K, lo, e, fixed=True)
    if not ok:
        Kf, reached, _ = eng.continue_interval(first, lo, e, "low", fixed=True)
        ok = reached == (lo, e)
    if ok:
        return Kf, _controller(eng, Kf)
    log.info("H-infinity phase: the held controller does not stabilise the H-infinity "
             "plants, and none was found that does while holding [%.5g, %.5g]", lo, e)
    return K, Kss


def _hinf_phase(eng: _Engine, hinf: list, dims: tuple, K: np.ndarray, Kss, lo: float,
                e: float, order: int, rounds: int = 3):
    """The H∞ phase from the held controller (module docstring, step 3): ``(synthesis or
    None, K, Kss)``.  The synthesis keeps the decay rate at the stability speeds only; where
    the dense scan finds a loop slower than that between them, its peaks join the stability
    speeds, the rate asked at them grows by a quarter (room for the loops between them; the
    required rate where no controller reaches that) and the synthesis starts again from the
    held controller (``rounds`` times at most).  ``None`` keeps the held controller."""
    s, models = eng.settings, eng.models
    opts = replace(s.synthesis, decay=float(s.decay), strictly_proper=eng.strictly_proper,
                   stable_controller=s.stable_controller, zero_start=False,
                   full_order_start=False, qp_solver=s.synthesis.qp_solver or "qpoases")
    speeds = np.linspace(lo, e, s.n_speeds)
    for k in range(rounds):
        stab = [_padded(P, dims) for V in speeds for P in models.parts(V)]
        syn = None
        # the faster rate first; where no controller reaches it, the required one
        for rate in dict.fromkeys((float(s.decay) * (1 + k / 4), float(s.decay))):
            try:
                syn = synthesize(hinf, models.ny, models.nu, order, starts=0, initial=Kss,
                                 stability_plants=stab, options=replace(opts, decay=rate))
                break
            except SynthesisError as exc:
                error = exc
        if syn is None:
            log.info("H-infinity phase: %s; the held controller is kept", error)
            return None, K, Kss
        Kh = models.scaling.gain(*(np.atleast_2d(np.asarray(M, dtype=float)).reshape(r, c)
                                   for M, (r, c) in zip(
            (syn.controller.A, syn.controller.B, syn.controller.C, syn.controller.D),
            ((order, order), (order, models.ny), (models.nu, order), (models.nu, models.ny)))))
        scan, values = eng.worst(Kh, lo, e)
        if float(np.max(values)) <= -eng.decay:
            return syn, Kh, syn.controller
        log.info("H-infinity phase: the dense scan finds abscissa %.4g > %.4g between the "
                 "stability speeds; they join them", float(np.max(values)) * models.scaling.w0,
                 -s.decay)
        speeds = np.union1d(speeds, scan[_peaks(values, -eng.decay)])
    log.info("H-infinity phase: the decay rate was lost between the stability speeds %d "
             "times; the held controller is kept", rounds)
    return None, K, Kss


def _finish(eng: _Engine, fams, K: np.ndarray, order: int, interval: tuple, reached: tuple,
            held: bool, records: list, hinf_plants, first: np.ndarray, t0: float
            ) -> MultiSpeedDesign:
    """The H∞ phase on the interval held (module docstring) and the result; ``first`` is
    the first start (scaled gain)."""
    s, models = eng.settings, eng.models
    lo, e = reached
    Kss = _controller(eng, K)
    channels = [DesignChannels(s.rate_weight, s.rate_bandwidth, side)
                for side in (("output", "input") if s.sensitivity else ("",))]
    hv = tuple(float(v) for v in np.linspace(lo, e, s.hinf_speeds)) if s.hinf_speeds else ()
    if hinf_plants is None:
        sc = models.scaling
        for side in (ch.sensitivity for ch in channels if ch.sensitivity):
            n = models.ny if side == "output" else models.nu
            if n > 1 and not any(_units(fams[0], side)):
                log.debug("H-infinity phase: the %s sensitivity weighs the %d %s as given, "
                          "their units not declared (declare them, e.g. the family file's "
                          "%s_units, to have signals in different units weighed alike)",
                          side, n, "measurements" if side == "output" else "controls", side)
        parts = [unit_free_sensitivity(design_partition(f, V, ch), ch, sc.su, sc.sy,
                                       _units(f, ch.sensitivity))
                 for V in hv for f in fams for ch in channels]
        nw = max((P.B1.shape[1] for P in parts), default=0)
        nz = max((P.C1.shape[0] for P in parts), default=0)
        hinf = [_as_ss(P, nw, nz) for P in parts]
    else:
        hinf = [control.ss(P) for P in hinf_plants]
        hv = ()
    syn, gamma = None, float("nan")
    if hinf:
        nw = hinf[0].ninputs - models.nu
        nz = hinf[0].noutputs - models.ny
        if nw < 1 or nz < 1:
            raise DimensionError(f"the H∞ plants have {hinf[0].ninputs} inputs and "
                                 f"{hinf[0].noutputs} outputs: they need [w, u] with "
                                 f"{models.nu} controls and [z, y] with {models.ny} "
                                 "measurements, and at least one w and one z")
        if models.fixed:
            K, Kss = _hold_fixed(eng, K, Kss, lo, e, first)
        syn, K, Kss = _hinf_phase(eng, hinf, (nw, nz), K, Kss, lo, e, order)
        gamma = (float(syn.gamma) if syn is not None else
                 max(verify_closed_loop(P, Kss, models.ny, models.nu)[0] for P in hinf))
    worst = float(np.max(eng.worst(K, lo, e)[1])) * models.scaling.w0
    what = f"order {order} holds [{lo:.5g}, {e:.5g}]"
    if held:
        message = f"{what}, the whole interval, at the decay rate {s.decay:g}"
    else:
        message = (f"{what} at the decay rate {s.decay:g}, not the requested "
                   f"[{interval[0]:.5g}, {interval[1]:.5g}]: the farthest any start reached")
    if syn is not None and not syn.converged:
        budget = (f"{s.synthesis.max_outer}, up to "
                  f"{s.synthesis.max_outer + s.synthesis.extra_outer} while the objective "
                  "kept falling" if s.synthesis.extra_outer else f"{s.synthesis.max_outer}")
        message += (f"; its H∞ phase stopped after {syn.best.outer_iterations} iterations "
                    f"({budget}) without converging ({syn.best.reason}): the objective is the "
                    "best found, not a local minimum")
    if np.isfinite(gamma):
        log.info("multi-speed design: %s; worst H-infinity objective %.5g", message, gamma)
    else:
        log.info("multi-speed design: %s; no H-infinity phase", message)
    sig = fams[0].signals          # K reads the measurements and drives the controls
    Kss = control.ss(Kss.A, Kss.B, Kss.C, Kss.D, inputs=list(sig.measurements),
                     outputs=list(sig.controls), name="K")
    return MultiSpeedDesign(controller=Kss, order=order, interval=interval,
                            reached=(float(lo), float(e)), held=bool(held),
                            worst_abscissa=worst, gamma=gamma, hinf_speeds=hv, synthesis=syn,
                            starts=tuple(records), message=message,
                            wall_time=time.perf_counter() - t0, decay=float(s.decay))
