"""Random fixed-order starts at one end of a speed interval, continued to the other (eq. 8-9).

:func:`~casflutter.design.stabilize_interval` continues one controller; where it stalls
depends on the start.  From the low end the natural start is the paper's design at Vf; from
the high end the only deterministic start is the full-order LQG of
:func:`~casflutter.design.full_order_start`, whose truncations to a low order rarely hold the
top.  :func:`search_random_starts` supplies low-order starts at either end: seeded random
controllers made of lightly damped resonators near the flutter mode's frequency (and one real
pole for an odd order), each optimised for the worst spectral abscissa on a short band at the
anchor end and, when that band decays, continued towards the other end.  From both ends it
brackets what one controller *of a given order* can hold, and whether two of that order, one
from each end, overlap: the question of the paper's order-3 interval (0, 2.4).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from .._format import result_repr
from .._settings import finite_numbers
from .._threads import single_threaded
from ..errors import ConfigError
from ._interval import IntervalReach, _Models, _polish, _speed_interval, stabilize_interval

__all__ = ["RandomStartSearch", "search_random_starts"]

log = logging.getLogger("casflutter.design")

REACH_TIE = 1e-9
"""Relative difference of two reached interval ends below which they tie
(:attr:`RandomStartSearch.best` keeps the earlier start); far below the continuation's
smallest step (``min_step``, 2.5e-3 by default)."""


@dataclass(frozen=True)
class RandomStartSearch:
    """Outcome of :func:`search_random_starts`.

    Attributes
    ----------
    anchor : str
        ``"low"`` or ``"high"``: the end the starts were made at.
    order : int
        Controller order of every start.
    starts : int
        Random starts tried.
    seed : int
        Seed of the search (start ``i`` draws from ``numpy.random.default_rng([seed, i])``).
    reaches : tuple of IntervalReach
        The continuation of every start that decayed on the anchor band, in the order tried.
    start_indices : tuple of int
        The index ``i`` of each of ``reaches``.
    frequency_band : tuple of float
        The band (rad/s) the resonators' frequencies were drawn from.
    """

    __repr__ = result_repr

    anchor: str
    order: int
    starts: int
    seed: int
    reaches: tuple
    start_indices: tuple
    frequency_band: tuple

    @property
    def best(self) -> IntervalReach | None:
        """The continuation that reached farthest from the anchor (``None`` when no start
        held the anchor band); of ends within ``REACH_TIE`` of each other (sums of
        continuation steps that differ only in rounding), the earlier start's."""
        best = None
        for r in self.reaches:
            far = r.reached[0] if self.anchor == "high" else -r.reached[1]
            if best is None or far < best[0] - REACH_TIE * max(1.0, abs(best[0])):
                best = (far, r)
        return None if best is None else best[1]

    @property
    def met(self) -> bool:
        """True when some start held the whole target interval."""
        return any(r.met for r in self.reaches)


def _rightmost_complex_frequency(models: _Models, V: float) -> float:
    """|Im λ| of the rightmost eigenvalue with a nonzero imaginary part of the open loops."""
    lam = np.concatenate([np.linalg.eigvals(lp.A) for lp in models.loops(V)])
    lam = lam[lam.imag > 1e-6 * max(1.0, float(np.max(np.abs(lam))))]
    if lam.size == 0:
        raise ConfigError(f"the open loop at V = {V:.4g} has no oscillatory mode to place "
                          "the start's resonators at; give frequency_band explicitly")
    return float(lam[np.argmax(lam.real)].imag)


def _random_start(rng: np.random.Generator, order: int, m: int, band) -> control.StateSpace:
    """An order-``order`` controller (``m`` sensors, one flap): ``order // 2`` resonators
    with frequencies uniform in ``band`` and damping 0.5-10 %, one real pole at
    ``-10^U(-1.5, 0.5)`` for an odd order, and Gaussian ``B``, ``C`` of log-uniform scale."""
    blocks = []
    if order % 2:
        blocks.append(np.array([[-10.0 ** rng.uniform(-1.5, 0.5)]]))
    for _ in range(order // 2):
        w, z = rng.uniform(*band), rng.uniform(0.005, 0.1)
        wd = w * math.sqrt(1 - z * z)
        blocks.append(np.array([[-z * w, wd], [-wd, -z * w]]))
    A = scipy.linalg.block_diag(*blocks)
    B = rng.standard_normal((order, m)) * 10.0 ** rng.uniform(-1, 1)
    C = rng.standard_normal((1, order)) * 10.0 ** rng.uniform(-1, 1)
    return control.ss(A, B, C, np.zeros((1, m)))


def search_random_starts(system, interval, order: int, *, anchor: str = "high",
                         starts: int = 20, seed: int = 0,
                         frequency_band: tuple[float, float] | None = None,
                         anchor_width: float = 0.1, decay: float = 0.05,
                         max_iter: int = 300, **continuation) -> RandomStartSearch:
    """Seeded random order-``order`` controllers at one end of ``interval``, continued.

    Start ``i`` (``numpy.random.default_rng([seed, i])``) is optimised for the worst
    closed-loop spectral abscissa at the two speeds of the anchor band (``hi - anchor_width``
    and ``hi``, or ``lo`` and ``lo + anchor_width``); when it decays there at the rate
    ``decay``, :func:`stabilize_interval` pushes the other end of its interval towards the
    target's.  The same seed gives the same starts and the same continuations whatever the
    thread count (the work runs single-threaded).

    Parameters
    ----------
    system : LoopFamily or sequence of LoopFamily
        ΣAE(V) of eq. 8-9, as for :func:`stabilize_interval`.
    interval : (lo, hi)
        Target speed-index interval, ``0 <= lo < hi``.
    order : int
        Controller order (>= 1).
    anchor : {"high", "low"}
        The end the starts are made at.
    starts : int
        Random starts (>= 1).
    seed : int
        Seed of the starts (>= 0).
    frequency_band : (float, float), optional
        Band (rad/s) of the resonators' frequencies; default 0.8-1.6 times the frequency of
        the open loop's rightmost oscillatory mode at ``hi`` (the flutter mode): on the seed
        wing and its frozen ROM loop, the order-3 controllers that held V = 2.4 settled
        between 53 and 76 rad/s, 1.0-1.6 times the flutter mode's 48-52 rad/s there.
    anchor_width : float
        Width of the band at the anchor end where a start must decay before it is continued.
    decay : float
        Decay rate (rad/s) required on the anchor band and by the continuation.
    max_iter : int
        BFGS iterations per temperature, on the anchor band and in the continuation.
    **continuation
        Further settings of :func:`stabilize_interval` (``n_speeds``, ``first_step``,
        ``min_step``, ``max_rounds``, ``free_feedthrough``, ``stable_controller``); the last
        two apply on the anchor band as well.

    Returns
    -------
    RandomStartSearch

    Raises
    ------
    ConfigError
        A bad interval, anchor, order, count, seed, band or setting (before any
        optimisation).

    See Also
    --------
    stabilize_interval : the continuation of one start.
    full_order_start : the deterministic full-order start at the top.
    """
    lo, hi = _speed_interval(interval)
    if anchor not in ("low", "high"):
        raise ConfigError(f"anchor = {anchor!r}: 'low' or 'high'")
    if not (isinstance(order, (int, np.integer)) and order >= 1):
        raise ConfigError(f"order = {order!r}: an integer >= 1 (a dynamic controller)")
    if not (isinstance(starts, (int, np.integer)) and starts >= 1):
        raise ConfigError(f"starts = {starts!r}: an integer >= 1")
    if not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise ConfigError(f"seed = {seed!r}: an integer >= 0")
    if not (0 < anchor_width and decay >= 0 and max_iter >= 1):
        raise ConfigError(f"need anchor_width > 0, decay >= 0, max_iter >= 1; got "
                          f"anchor_width={anchor_width!r}, decay={decay!r}, "
                          f"max_iter={max_iter!r}")
    unknown = set(continuation) - {"n_speeds", "first_step", "min_step", "max_rounds",
                                   "free_feedthrough", "stable_controller"}
    if unknown:
        raise ConfigError(f"unknown continuation settings {sorted(unknown)}; see "
                          "stabilize_interval")
    models = _Models.of(system)
    if frequency_band is None:
        w = _rightmost_complex_frequency(models, hi)
        band = (0.8 * w, 1.6 * w)
    else:
        band = finite_numbers("frequency_band", frequency_band, 2,
                              what="two numbers (low, high) in rad/s")
        if not 0 < band[0] <= band[1]:
            raise ConfigError(f"frequency_band = {list(band)!r}: need 0 < low <= high")
    band_speeds = ([max(lo, hi - anchor_width), hi] if anchor == "high"
                   else [lo, min(hi, lo + anchor_width)])
    free = bool(continuation.get("free_feedthrough", False))
    stable = bool(continuation.get("stable_controller", False))
    reaches, indices = [], []
    with single_threaded():
        for i in range(int(starts)):
            rng = np.random.default_rng([int(seed), i])
            K = _random_start(rng, int(order), models.n_sensors, band)
            K, worst = _polish(models, K, band_speeds, max_iter, -2 * decay, free, stable)
            if not worst < -decay:
                log.debug("%s-end start %d: the anchor band does not decay (worst %.4g)",
                          anchor, i, worst)
                continue
            reach = stabilize_interval(models, K, (lo, hi), anchor=anchor, decay=decay,
                                       max_iter=max_iter, **continuation)
            log.debug("%s-end start %d: reached [%.4g, %.4g]", anchor, i, *reach.reached)
            reaches.append(reach)
            indices.append(i)
    return RandomStartSearch(anchor, int(order), int(starts), int(seed), tuple(reaches),
                             tuple(indices), band)
