"""The one helper through which every CasADi NLP in casflutter is built and solved.

``problem dict -> nlpsol -> checked stats -> frozen NLPResult``.  Identification,
synthesis and the parametric studies all go through :func:`make_solver` /
:func:`solve_nlp`; nobody else calls ``casadi.nlpsol``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import casadi as ca
import numpy as np

from .errors import ConvergenceError

__all__ = ["NLPResult", "NLPSolver", "make_solver", "solve_nlp", "DEFAULT_IPOPT_OPTIONS"]

#: Quiet Ipopt defaults; every key may be overridden through ``options``.
DEFAULT_IPOPT_OPTIONS: dict[str, Any] = {
    "ipopt.print_level": 0,
    "print_time": False,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-8,
    "ipopt.max_iter": 500,
}

#: Ipopt return statuses that count as converged.  ``Solved_To_Acceptable_Level``
#: is only accepted when the caller asks for it (``accept_acceptable=True``).
_SUCCESS = {"Solve_Succeeded"}
_ACCEPTABLE = {"Solved_To_Acceptable_Level"}


@dataclass(frozen=True)
class NLPResult:
    """Outcome of one Ipopt solve.

    Attributes
    ----------
    x : ndarray
        Primal solution (or last iterate when ``success`` is False).
    f : float
        Objective value at ``x``.
    g : ndarray
        Constraint values at ``x``.
    lam_g, lam_x : ndarray
        Multipliers of the constraints and of the simple bounds.
    success : bool
        True when Ipopt reported ``Solve_Succeeded`` (or, if allowed,
        ``Solved_To_Acceptable_Level``).
    return_status : str
        Ipopt's status verbatim.
    iterations : int
        Ipopt iterations.
    wall_time : float
        Wall-clock seconds of the solve (excluding solver construction).
    stats : dict
        The complete ``solver.stats()`` dictionary.
    """

    x: np.ndarray
    f: float
    g: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray
    success: bool
    return_status: str
    iterations: int
    wall_time: float
    stats: Mapping[str, Any] = field(repr=False, default_factory=dict)

    @property
    def acceptable(self) -> bool:
        """True when Ipopt stopped at its *acceptable* (looser) tolerance."""
        return self.return_status in _ACCEPTABLE


class NLPSolver:
    """A reusable Ipopt solver for a fixed problem structure (parametric in ``p``).

    Build once with :func:`make_solver`, call many times with new data: this is
    what sweeps use to avoid rebuilding the expression graph.
    """

    def __init__(self, nlp: Mapping[str, ca.SX | ca.MX], options: Mapping[str, Any] | None = None,
                 name: str = "nlp"):
        opts = dict(DEFAULT_IPOPT_OPTIONS)
        opts.update(options or {})
        self.name = name
        self.options = opts
        self.nx = int(nlp["x"].numel())
        self.ng = int(nlp["g"].numel()) if "g" in nlp else 0
        self.np = int(nlp["p"].numel()) if "p" in nlp else 0
        self.function = ca.nlpsol(name, "ipopt", dict(nlp), opts)

    def __call__(self, x0, *, lbx=-np.inf, ubx=np.inf, lbg=0.0, ubg=0.0, p=None,
                 lam_x0=None, lam_g0=None, accept_acceptable: bool = False,
                 raise_on_failure: bool = False) -> NLPResult:
        """Solve from ``x0``; returns an :class:`NLPResult` (never raises on
        non-convergence unless ``raise_on_failure``)."""
        args: dict[str, Any] = {"x0": np.asarray(x0, dtype=float).ravel(),
                                "lbx": lbx, "ubx": ubx}
        if self.ng:
            args.update(lbg=lbg, ubg=ubg)
        if self.np:
            if p is None:
                raise ValueError(f"NLP '{self.name}' has {self.np} parameters: pass p=")
            args["p"] = np.asarray(p, dtype=float).ravel()
        if lam_x0 is not None:
            args["lam_x0"] = lam_x0
        if lam_g0 is not None:
            args["lam_g0"] = lam_g0
        t0 = time.perf_counter()
        sol = self.function(**args)
        wall = time.perf_counter() - t0
        stats = dict(self.function.stats())
        status = str(stats.get("return_status", "unknown"))
        ok = status in _SUCCESS or (accept_acceptable and status in _ACCEPTABLE)
        res = NLPResult(
            x=np.asarray(sol["x"]).ravel(),
            f=float(sol["f"]),
            g=np.asarray(sol["g"]).ravel(),
            lam_g=np.asarray(sol["lam_g"]).ravel(),
            lam_x=np.asarray(sol["lam_x"]).ravel(),
            success=bool(ok),
            return_status=status,
            iterations=int(stats.get("iter_count", -1)),
            wall_time=wall,
            stats=stats,
        )
        if raise_on_failure and not ok:
            raise ConvergenceError(
                f"Ipopt did not converge on '{self.name}': return_status={status!r} after "
                f"{res.iterations} iterations (raise ipopt.max_iter or check scaling)", res)
        return res


def make_solver(nlp: Mapping[str, Any], options: Mapping[str, Any] | None = None,
                name: str = "nlp") -> NLPSolver:
    """Build a reusable :class:`NLPSolver` from an ``{'x','p','f','g'}`` dict."""
    return NLPSolver(nlp, options, name)


def solve_nlp(nlp: Mapping[str, Any], x0, *, options: Mapping[str, Any] | None = None,
              name: str = "nlp", **kwargs) -> NLPResult:
    """Build and solve once. Keyword arguments are those of :meth:`NLPSolver.__call__`."""
    return make_solver(nlp, options, name)(x0, **kwargs)
