"""Order selection for the HWL ROM by free-run error on held-out data.

Every candidate ``(mu, na, nb, r, p, q)`` of a grid is identified on the estimation part of
the records and scored by the free-run (simulation) error of eq. 3 on the held-out part,
started from the measured outputs.  All candidates are scored on the same samples (the first
``max_lag`` of the largest candidate are skipped for every one).  The choice is parsimonious:
among the candidates whose score is within ``rel_tol`` of the best, the one with the fewest
parameters (then the lowest score) wins, because a model with more terms than the system
needs fits the held-out data as well as the right one, up to its estimation noise.
Among candidates with the same number of parameters whose scores agree to ``SCORE_TIE_RTOL``
(1e-6 relative), the first of the grid wins: the choice never hinges on the last bits of
the scores, which change from machine to machine.
"""

from __future__ import annotations

import itertools
import time
import warnings
from dataclasses import dataclass, replace
from typing import Any, Iterable, Mapping

import numpy as np

from .._format import result_repr
from ..data import IOData
from ..errors import CasflutterError, ConfigError, DataError
from ._identify import (IdentificationResult, IdentificationSettings, fit_report, identify)
from ._model import HWLModel
from ._orders import _NAMES, HWLOrders
from ._structure import HWLStructure

__all__ = ["OrderCandidate", "OrderSelection", "select_orders", "order_grid", "parse_grid"]

#: default grid around the base orders: autoregressive order and both polynomial degrees
DEFAULT_GRID = {"na": (1, 2, 3, 4), "p": (1, 2, 3), "q": (1, 2, 3)}
MAX_CANDIDATES = 1000
#: relative difference of held-out scores below which two candidates of the same size tie
#: (the earlier of the grid wins); far below the parsimony tolerance ``rel_tol`` (0.02) and
#: far above the scores' rounding (~1e-13 relative)
SCORE_TIE_RTOL = 1e-6


@dataclass(frozen=True)
class OrderCandidate:
    """One candidate of :func:`select_orders`.

    Attributes
    ----------
    orders : HWLOrders
    n_params : int
    score : float
        Free-run error on the held-out data, ``100 ||y - y_sim|| / ||y||`` averaged (RMS)
        over the outputs; ``inf`` when the candidate failed or diverged.
    error_percent_validation, error_percent_estimation : ndarray (N,) or None
        Per-output free-run error % on the held-out and on the estimation data.
    status : str
        The identification's status, or the error class when it raised.
    message : str
        Why the candidate failed (empty otherwise).
    wall_time : float
        Seconds to identify and score it.
    model : HWLModel or None
    """

    __repr__ = result_repr

    orders: HWLOrders
    n_params: int
    score: float
    error_percent_validation: np.ndarray | None
    error_percent_estimation: np.ndarray | None
    status: str
    message: str
    wall_time: float
    model: HWLModel | None = None

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.score))


@dataclass(frozen=True)
class OrderSelection:
    """Outcome of :func:`select_orders`.

    Attributes
    ----------
    candidates : tuple of OrderCandidate
        In the order tried.
    best : OrderCandidate
        The parsimonious choice (module docstring, :func:`_parsimonious`).
    rel_tol : float
    criterion : str
        Stage-2 criterion used for every candidate.
    skip : int
        Leading held-out samples not scored.
    """

    __repr__ = result_repr

    candidates: tuple
    best: OrderCandidate
    rel_tol: float
    criterion: str
    skip: int

    def table(self) -> str:
        """The candidates, best first within equal scores: orders, parameters, error % on
        held-out and estimation data, time, status."""
        head = (f"{'orders (mu,na,nb,r,p,q)':>24} {'params':>7} {'held-out %':>11} "
                f"{'estim. %':>9} {'time s':>7}  status")
        lines = [head]
        for c in sorted(self.candidates, key=lambda c: (c.score, c.n_params)):
            mark = " *" if c is self.best else ""
            est = (np.sqrt(np.mean(c.error_percent_estimation ** 2))
                   if c.error_percent_estimation is not None else float("nan"))
            lines.append(f"{str(c.orders.as_tuple()):>24} {c.n_params:7d} {c.score:11.4f} "
                         f"{est:9.4f} {c.wall_time:7.2f}  {c.status}{mark}")
        lines.append(f"* chosen: fewest parameters within {100 * self.rel_tol:g}% of the best "
                     "held-out error")
        return "\n".join(lines)


def order_grid(grid: Mapping[str, Iterable[int]] | Iterable | None = None,
               base=(3, 1, 1, 1, 2, 2)) -> list[HWLOrders]:
    """Expand a grid of orders.

    Parameters
    ----------
    grid : mapping or sequence, optional
        ``{"na": [1, 2, 3], "q": [1, 3], ...}`` (cartesian product; orders not named are
        those of ``base``) or an explicit sequence of ``(mu, na, nb, r, p, q)``.
        Default: ``DEFAULT_GRID`` around ``base``.
    base : orders

    Raises
    ------
    ConfigError
        Unknown names, empty value lists, more than ``MAX_CANDIDATES`` candidates.
    OrderError
        A candidate out of range.
    """
    base = HWLOrders.from_tuple(base)
    if grid is None:
        grid = DEFAULT_GRID
    if isinstance(grid, Mapping):
        unknown = sorted(set(map(str, grid)) - set(_NAMES))
        if unknown:
            raise ConfigError(f"order grid has unknown name(s) {unknown}: use {_NAMES}")
        axes = []
        for name, default in zip(_NAMES, base.as_tuple()):
            vals = grid.get(name, (default,))
            vals = (vals,) if isinstance(vals, (int, np.integer)) else tuple(vals)
            if not vals:
                raise ConfigError(f"order grid {name}: empty list of values")
            axes.append(vals)
        n = int(np.prod([len(a) for a in axes]))
        if n > MAX_CANDIDATES:
            raise ConfigError(f"order grid has {n} candidates (more than {MAX_CANDIDATES}); "
                              "narrow it")
        combos = list(itertools.product(*axes))
    else:
        combos = list(grid)
        if not combos:
            raise ConfigError("order grid is empty: give at least one (mu, na, nb, r, p, q)")
        if len(combos) > MAX_CANDIDATES:
            raise ConfigError(f"order grid has {len(combos)} candidates (more than "
                              f"{MAX_CANDIDATES}); narrow it")
    out, seen = [], set()
    for c in combos:
        o = HWLOrders.from_tuple(c)
        if o not in seen:
            seen.add(o)
            out.append(o)
    return out


def parse_grid(text: str) -> dict[str, tuple[int, ...]]:
    """``"na=1:4 p=1,2 q=1:3"`` (spaces or ``;`` between items, ``a:b`` inclusive ranges)
    as a grid mapping for :func:`order_grid`."""
    grid: dict[str, tuple[int, ...]] = {}
    for item in text.replace(";", " ").split():
        if "=" not in item:
            raise ConfigError(f"order grid item {item!r}: write NAME=VALUES, e.g. na=1:4 or "
                              "q=1,3")
        name, vals = item.split("=", 1)
        values: list[int] = []
        try:
            for part in vals.split(","):
                if ":" in part:
                    a, b = part.split(":", 1)
                    values += list(range(int(a), int(b) + 1))
                elif part:
                    values.append(int(part))
        except ValueError:
            raise ConfigError(f"order grid item {item!r}: values must be integers, ranges "
                              "a:b or lists a,b,c") from None
        grid[name.strip()] = tuple(values)
    if not grid:
        raise ConfigError(f"order grid {text!r} is empty: e.g. 'na=1:4 p=1,2 q=1:3'")
    return grid


def _parsimonious(ok: list[OrderCandidate], rel_tol: float) -> OrderCandidate:
    """Among the candidates (in grid order) whose score is within ``rel_tol`` of the best,
    the one with the fewest parameters; of those, the lowest score, where a later candidate
    replaces an earlier one only when it is lower by more than ``SCORE_TIE_RTOL``."""
    s_min = min(c.score for c in ok)
    near = [c for c in ok if c.score <= s_min * (1 + rel_tol)]
    fewest = min(c.n_params for c in near)
    best = None
    for c in near:
        if c.n_params == fewest and (best is None
                                     or c.score < best.score * (1 - SCORE_TIE_RTOL)):
            best = c
    return best


def select_orders(data: IOData, grid=None, *, base=(3, 1, 1, 1, 2, 2),
                  validation: float | IOData = 0.3, rel_tol: float = 0.02,
                  keep_models: bool = False, **settings: Any) -> OrderSelection:
    """Identify every candidate orders on the estimation data and compare them by free-run
    error on held-out data (module docstring).

    Parameters
    ----------
    data : IOData
        Records; the last ``validation`` fraction of each is held out (or all of ``data`` is
        used for estimation when ``validation`` is an IOData).
    grid : mapping or sequence, optional
        See :func:`order_grid` (includes ``p != q`` candidates by default).
    base : orders
        Orders not varied by a mapping grid.
    validation : float or IOData
        Held-out fraction in (0, 1), or separate validation records.
    rel_tol : float
        Parsimony tolerance on the held-out score (0.02: within 2 % of the best).
    keep_models : bool
        Keep every candidate's model (else only the best's).
    **settings
        Fields of :class:`IdentificationSettings` for every candidate; the default
        criterion here is ``"simulation"``.

    Returns
    -------
    OrderSelection

    Raises
    ------
    ConfigError, DataError, OrderError
        Invalid grid, settings or split (before any identification).
    DataError
        No candidate could be identified (every message is listed).
    """
    if not isinstance(data, IOData):
        raise DataError(f"data must be an IOData, got {type(data).__name__}")
    if not (isinstance(rel_tol, (int, float)) and np.isfinite(rel_tol) and rel_tol >= 0):
        raise ConfigError(f"rel_tol={rel_tol!r} must be a finite number >= 0")
    settings.setdefault("criterion", "simulation")
    cfg = IdentificationSettings.build(None, **settings)
    candidates = order_grid(grid, base)
    if isinstance(validation, IOData):
        est, val = data, validation
    else:
        if not (isinstance(validation, (int, float)) and 0 < validation < 1):
            raise ConfigError(f"validation={validation!r}: give a held-out fraction in (0, 1) "
                              "or an IOData")
        est, val = data.split(1 - validation)
    skip = max(o.max_lag for o in candidates)
    out = []
    for o in candidates:
        t0 = time.perf_counter()
        n_params = HWLStructure(o, data.n_modes, data.has_u, data.has_v, cfg.offset).n_params
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res: IdentificationResult = identify(est, o, settings=cfg)
                score_val = fit_report(res.model, val, "simulation", skip=skip)
            ev = score_val.error_percent
            score = float(np.sqrt(np.mean(ev ** 2)))
            if not np.isfinite(score):
                score = float("inf")
            out.append(OrderCandidate(o, n_params, score, ev, res.fit.error_percent,
                                      res.return_status if np.isfinite(score)
                                      else "Unstable_Free_Run", "",
                                      time.perf_counter() - t0, res.model))
        except CasflutterError as exc:
            result = getattr(exc, "result", None)
            status = getattr(result, "return_status", type(exc).__name__)
            out.append(OrderCandidate(o, n_params, float("inf"), None, None, status, str(exc),
                                      time.perf_counter() - t0, None))
    ok = [c for c in out if c.ok]
    if not ok:
        msgs = "; ".join(f"{c.orders.as_tuple()}: {c.message or c.status}" for c in out[:5])
        raise DataError(f"no candidate orders could be identified ({msgs})")
    best = _parsimonious(ok, rel_tol)
    if not keep_models:
        out = [c if c is best else replace(c, model=None) for c in out]
        best = next(c for c in out if c.orders == best.orders)
    return OrderSelection(tuple(out), best, float(rel_tol), cfg.criterion, skip)
