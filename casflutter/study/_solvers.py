"""One parametric CasADi solver per worker process and problem structure.

A sweep whose points differ only in numbers (the NLP's ``p``) must not rebuild the
expression graph and Ipopt instance at every point (rockit ``repeated_solve.py``).
:func:`cached_solver` keeps the :class:`casflutter._nlp.NLPSolver` built for a structure key
in a per-process cache; each worker builds it once and reuses it for all its points.
"""

from __future__ import annotations

from typing import Any, Callable, Hashable

from .._nlp import NLPSolver

__all__ = ["cached_solver", "solver_builds", "clear_solver_cache"]

_CACHE: dict[Hashable, NLPSolver] = {}
_BUILDS: dict[Hashable, int] = {}


def cached_solver(key: Hashable, build: Callable[[], NLPSolver]) -> NLPSolver:
    """The solver cached under ``key`` in this process, built by ``build()`` the first time.

    Parameters
    ----------
    key : hashable
        Everything that fixes the NLP's structure (sizes, orders, options) -- never the
        numerical data, which travels in ``p``.
    build : callable
        Returns a new :class:`NLPSolver` (via :func:`casflutter._nlp.make_solver`).
    """
    solver = _CACHE.get(key)
    if solver is None:
        solver = build()
        _CACHE[key] = solver
        _BUILDS[key] = _BUILDS.get(key, 0) + 1
    return solver


def solver_builds(key: Hashable | None = None) -> Any:
    """How many times this process built the solver of ``key`` (all keys: a dict)."""
    return dict(_BUILDS) if key is None else _BUILDS.get(key, 0)


def clear_solver_cache() -> None:
    """Forget every cached solver of this process (build counts are kept)."""
    _CACHE.clear()
