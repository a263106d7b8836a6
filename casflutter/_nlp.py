"""The one helper through which every CasADi NLP in casflutter is built and solved.

``problem dict -> nlpsol -> checked stats -> frozen NLPResult``.  Identification,
synthesis and the parametric studies all go through :func:`make_solver` /
:func:`solve_nlp`; nobody else calls ``casadi.nlpsol``.  Dense convex QPs solved by an
active-set method (the multi-speed design's trust-region steps) go through
:func:`make_qp_solver` (``casadi.conic``, qpOASES).  Square nonlinear systems (the
collocation of periodic orbits in :mod:`casflutter.lco`, built as CasADi functions) go
through :func:`solve_newton`.
"""

from __future__ import annotations

import contextlib
import difflib
import functools
import io
import math
import re
import time
import types
from dataclasses import dataclass, field
from typing import Any, Mapping

import casadi as ca
import numpy as np
from scipy.linalg import lu_factor, lu_solve
from scipy.sparse.linalg import splu

from .errors import ConfigError, ConvergenceError

__all__ = ["NLPResult", "NLPSolver", "make_solver", "solve_nlp", "DEFAULT_IPOPT_OPTIONS",
           "RootResult", "solve_newton", "IpoptOption", "ipopt_option_list",
           "check_solver_options", "QPResult", "QPSolver", "make_qp_solver",
           "DEFAULT_QP_OPTIONS"]

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


# ---- dense convex QPs (casadi.conic) ----------------------------------------------------
#: Defaults of each QP plugin; every key may be overridden through ``options``.
DEFAULT_QP_OPTIONS: dict[str, dict[str, Any]] = {
    "qpoases": {"printLevel": "none", "sparse": False, "error_on_fail": False},
}


@dataclass(frozen=True)
class QPResult:
    """Outcome of one QP solve.

    Attributes
    ----------
    x : ndarray
        Solution (or the solver's last point when ``success`` is False).
    cost : float
        ``½ xᵀ H x + gᵀ x`` at ``x``.
    lam_a, lam_x : ndarray
        Multipliers of the linear constraints and of the simple bounds (positive where an
        upper bound is active, negative where a lower one is).
    success : bool
        Whether the solver reported an optimal solution.
    return_status : str
        The solver's status verbatim.
    wall_time : float
        Wall-clock seconds of the solve.
    """

    x: np.ndarray
    cost: float
    lam_a: np.ndarray
    lam_x: np.ndarray
    success: bool
    return_status: str
    wall_time: float


class QPSolver:
    """A reusable dense QP solver of one size::

        minimise ½ xᵀ H x + gᵀ x   subject to   lba <= A x <= uba,   lbx <= x <= ubx

    Build once with :func:`make_qp_solver`, call with new data.  qpOASES, the default, is a
    dense active-set method: on the small QPs of the synthesis (under a hundred variables,
    up to a thousand constraints) it is exact where an interior point relaxes the bounds,
    and an order of magnitude faster than Ipopt.
    """

    def __init__(self, nx: int, na: int, plugin: str = "qpoases",
                 options: Mapping[str, Any] | None = None, name: str = "qp"):
        opts = dict(DEFAULT_QP_OPTIONS.get(plugin, {"error_on_fail": False}))
        opts.update(options or {})
        self.name, self.plugin = name, plugin
        self.nx, self.na = int(nx), int(na)
        # qpOASES prints its copyright notice when built (CasADi sends it to sys.stdout):
        # it must not reach the results a command prints there (--json)
        with contextlib.redirect_stdout(io.StringIO()):
            self.function = ca.conic(name, plugin,
                                     {"h": ca.Sparsity.dense(self.nx, self.nx),
                                      "a": ca.Sparsity.dense(self.na, self.nx)}, opts)

    def __call__(self, H, g, A, lba, uba, lbx, ubx) -> QPResult:
        """Solve once; never raises on a failed solve (see ``success``).

        Returns
        -------
        QPResult
        """
        t0 = time.perf_counter()
        sol = self.function(h=H, g=g, a=A, lba=lba, uba=uba, lbx=lbx, ubx=ubx)
        wall = time.perf_counter() - t0
        stats = self.function.stats()
        return QPResult(x=np.asarray(sol["x"]).ravel(), cost=float(sol["cost"]),
                        lam_a=np.asarray(sol["lam_a"]).ravel(),
                        lam_x=np.asarray(sol["lam_x"]).ravel(),
                        success=bool(stats.get("success", False)),
                        return_status=str(stats.get("return_status", "unknown")),
                        wall_time=wall)


def make_qp_solver(nx: int, na: int, plugin: str = "qpoases",
                   options: Mapping[str, Any] | None = None, name: str = "qp") -> QPSolver:
    """Build a reusable dense :class:`QPSolver` with ``nx`` variables and ``na`` linear
    constraints (``plugin``: a ``casadi.conic`` plugin).

    Returns
    -------
    QPSolver
    """
    return QPSolver(nx, na, plugin, options, name)


# ---- the option list of the installed Ipopt ---------------------------------------------
@dataclass(frozen=True)
class IpoptOption:
    """One option of Ipopt, as its own documentation states it.

    Attributes
    ----------
    name : str
        Ipopt's name (without the ``ipopt.`` prefix of CasADi).
    kind : str
        ``"real"``, ``"integer"`` or ``"string"``.
    low, high : float or None
        Bounds of a number (None: unbounded on that side).
    low_strict, high_strict : bool
        Whether the bound itself is excluded.
    values : tuple of str
        The settings of a string option (empty: any string).
    """

    name: str
    kind: str
    low: float | None = None
    high: float | None = None
    low_strict: bool = False
    high_strict: bool = False
    values: tuple = ()

    def allowed(self) -> str:
        """What the option accepts, in words (``"a real number with 0 < tol"``).

        Returns
        -------
        str
        """
        if self.kind == "string":
            if not self.values:
                return "a string"
            return "one of " + ", ".join(f'"{v}"' for v in self.values)
        what = "an integer" if self.kind == "integer" else "a real number"
        parts = []
        if self.low is not None:
            parts.append(f"{self.low:g} {'<' if self.low_strict else '<='} ")
        parts.append(self.name)
        if self.high is not None:
            parts.append(f" {'<' if self.high_strict else '<='} {self.high:g}")
        return what if len(parts) == 1 else f"{what} with {''.join(parts)}"

    def accepts(self, value) -> bool:
        """Whether ``value`` (a TOML/Python value) is a valid setting.

        Returns
        -------
        bool
        """
        if self.kind == "string":
            return isinstance(value, str) and (not self.values or value in self.values)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        if self.kind == "integer" and not isinstance(value, int):
            return False
        if not math.isfinite(value):
            return False
        if self.low is not None and (value < self.low or (self.low_strict and value == self.low)):
            return False
        return not (self.high is not None
                    and (value > self.high or (self.high_strict and value == self.high)))


_NUMBER = r"([-+]?[0-9.]+(?:e[-+]?[0-9]+)?|[-+]?10<sup>[-+]?[0-9]+</sup>)"


def _doc_number(text: str) -> float:
    power = re.fullmatch(r"([-+]?)10<sup>([-+]?[0-9]+)</sup>", text)
    if power:
        return float(f"{power.group(1)}1e{power.group(2)}")
    return float(text)


def _parse_ipopt_doc(doc: str) -> dict[str, IpoptOption]:
    """Ipopt's ``print_options_documentation`` output (doxygen mode) -> its options."""
    table = {}
    for block in re.split(r"\\anchor OPT_", doc)[1:]:
        name = re.match(r"\w+", block).group(0)
        kind = re.search(r"this (real|integer|string) option", block)
        if kind is None:
            continue
        kind = kind.group(1)
        if kind == "string":
            values = tuple(v for v in re.findall(r"(?m)^ - ([^:\s]+):", block) if v != "*")
            star = re.search(r"(?m)^ - \*:", block) is not None
            table[name] = IpoptOption(name, kind, values=() if star else values)
            continue
        low = high = None
        low_strict = high_strict = False
        rng = re.search(rf"(?:{_NUMBER} (<|&le;) )?{re.escape(name)}(?: (<|&le;) {_NUMBER})? and "
                        "its default", block)
        if rng:
            if rng.group(1) is not None:
                low, low_strict = _doc_number(rng.group(1)), rng.group(2) == "<"
            if rng.group(4) is not None:
                high, high_strict = _doc_number(rng.group(4)), rng.group(3) == "<"
        table[name] = IpoptOption(name, kind, low, high, low_strict, high_strict)
    return table


def _tiny_solver(options: Mapping[str, Any]) -> str:
    """Build (never solve) a one-variable Ipopt NLP with ``options``; Ipopt's console output
    (CasADi routes it through ``sys.stdout``) is returned instead of printed."""
    x = ca.SX.sym("x")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        ca.nlpsol("option_check", "ipopt", {"x": x, "f": x * x},
                  {"print_time": False, "ipopt.sb": "yes", **options})
    return out.getvalue()


@functools.lru_cache(maxsize=1)
def ipopt_option_list() -> Mapping[str, IpoptOption]:
    """The options of the installed Ipopt, from its own documentation.

    Ipopt prints the documentation of every option (type, valid range, settings, advanced
    ones included) when a solver is built with ``print_options_documentation``; the list is
    read once per process (a fraction of a second, no solve).

    Returns
    -------
    mapping of str to IpoptOption
    """
    doc = _tiny_solver({"ipopt.print_options_documentation": "yes",
                        "ipopt.print_advanced_options": "yes",
                        "ipopt.print_options_mode": "doxygen"})
    return types.MappingProxyType(_parse_ipopt_doc(doc))


def _flat(options: Mapping[str, Any]) -> dict[str, Any]:
    flat = {}
    for key, value in options.items():
        if key == "ipopt" and isinstance(value, Mapping):  # CasADi's nested form
            flat.update({f"ipopt.{k}": v for k, v in value.items()})
        else:
            flat[str(key)] = value
    return flat


def check_solver_options(options: Mapping[str, Any] | None, key: str = "options") -> dict:
    """Check NLP options against the installed solver before any work.

    ``ipopt.NAME`` keys are checked against Ipopt's own option list
    (:func:`ipopt_option_list`: name, type, range, settings); the other keys are CasADi's
    ``nlpsol`` options, checked by building (never solving) a one-variable NLP with them.
    Options Ipopt accepts but leaves out of its documentation (``ipopt.sb``) are accepted the
    same way.

    Parameters
    ----------
    options : mapping
        Flat options (``{"ipopt.tol": 1e-8, "print_time": False}``), or CasADi's nested
        ``{"ipopt": {...}}``.
    key : str
        Name of the setting that holds them, for the messages (``"solver.ipopt"``).

    Returns
    -------
    dict
        The flat options.

    Raises
    ------
    ConfigError
        An unknown option (with the closest known names), or a value of the wrong type or
        outside the option's range (with what is allowed).
    """
    flat = _flat(options or {})
    listed = ipopt_option_list() if any(k.startswith("ipopt.") for k in flat) else {}
    other = {}
    for name, value in flat.items():
        if not name.startswith("ipopt."):
            other[name] = value
            continue
        opt = listed.get(name[6:])
        if opt is None:
            try:
                _tiny_solver({name: value})
            except RuntimeError:
                near = difflib.get_close_matches(name[6:], list(listed), n=3)
                hint = (f"; did you mean {', '.join('ipopt.' + n for n in near)}?" if near
                        else "; see Ipopt's option list (print_options_documentation)")
                raise ConfigError(f"{key}: unknown Ipopt option {name!r} = {value!r}{hint}"
                                  ) from None
            continue
        if not opt.accepts(value):
            raise ConfigError(f"{key}: Ipopt option {name!r} = {value!r} is not allowed: "
                              f"give {opt.allowed()}")
    if other:
        try:
            _tiny_solver(other)
        except RuntimeError as exc:
            msg = str(exc)
            unknown = re.search(r"Unknown option: (\S+)", msg)
            if unknown:
                near = re.findall(r'> "(\w+)"', msg)[:3]
                hint = f"; did you mean {', '.join(near)}?" if near else ""
                raise ConfigError(f"{key}: unknown solver option {unknown.group(1)!r} (neither "
                                  f"CasADi's nlpsol nor Ipopt's, which take the prefix "
                                  f"'ipopt.'){hint}") from None
            detail = msg.strip().splitlines()[-1] if msg.strip() else msg
            raise ConfigError(f"{key}: solver options {other!r} are not accepted by CasADi's "
                              f"nlpsol ({detail})") from None
    return flat


# ---- square nonlinear systems (collocation of periodic orbits, invariant circles) --------
@dataclass(frozen=True)
class RootResult:
    """Outcome of one Newton solve of ``g(x) = 0``.

    Attributes
    ----------
    x : ndarray
        Solution (or last iterate when ``success`` is False).
    residual : float
        ``max |g(x)|`` at ``x``.
    success : bool
        True when the residual is finite and at most the tolerance.
    return_status : str
        ``"success"``, ``"max_iter"``, ``"singular_jacobian"``, ``"non_finite"`` or
        ``"no_descent"`` (the damped step could not reduce the residual).
    iterations : int
        Newton iterations.
    wall_time : float
        Wall-clock seconds of the solve.
    factor : scipy.sparse.linalg.SuperLU or None
        LU factors of the last Jacobian factorised (at the last iterate but one), for
        callers that solve further systems with it (continuation tangents).
    """

    x: np.ndarray
    residual: float
    success: bool
    return_status: str
    iterations: int
    wall_time: float
    factor: Any = field(default=None, repr=False, compare=False)


class _DenseLU:
    """LU factors of a dense matrix with the ``solve`` method of ``SuperLU``."""

    def __init__(self, A: np.ndarray):
        self._lu = lu_factor(A, check_finite=True)
        if np.any(np.diag(self._lu[0]) == 0):
            raise np.linalg.LinAlgError("singular matrix")

    def solve(self, b: np.ndarray) -> np.ndarray:
        return lu_solve(self._lu, b)


def solve_newton(residual, jacobian, x0, *, tol: float = 1e-10, max_iter: int = 20,
                 name: str = "root") -> RootResult:
    """Damped Newton iteration for a square sparse system ``g(x) = 0``.

    Used for the bordered collocation systems of :mod:`casflutter.lco`, whose residual and
    sparse Jacobian are CasADi functions (``casadi.rootfinder`` would rebuild the Jacobian
    of the dense phase and arclength rows symbolically, which costs seconds per problem,
    and its ``newton`` plugin reports success on non-finite iterates).  Each step solves
    with a sparse LU factorisation; the step is halved (at most five times) until the
    residual norm decreases.

    Parameters
    ----------
    residual : callable
        ``x -> g(x)`` (1-D array).
    jacobian : callable
        ``x -> dg/dx`` (``scipy.sparse`` matrix, or a dense ``numpy`` array).
    x0 : array_like
        Initial guess.
    tol : float
        Convergence: ``max |g| <= tol``.
    max_iter : int
        Newton iterations.
    name : str
        Name used in log messages.

    Returns
    -------
    RootResult
        Never raises on non-convergence: read ``success``.
    """
    t0 = time.perf_counter()
    x = np.asarray(x0, dtype=float).ravel().copy()
    g = np.asarray(residual(x), float).ravel()
    nrm = float(np.max(np.abs(g), initial=0.0))
    status, it, lu = "max_iter", 0, None
    while it < max_iter:
        if not np.isfinite(nrm):
            status = "non_finite"
            break
        if nrm <= tol:
            status = "success"
            break
        try:
            J = jacobian(x)
            lu = _DenseLU(J) if isinstance(J, np.ndarray) else splu(J.tocsc())
            dx = lu.solve(-g)
        except (RuntimeError, np.linalg.LinAlgError, ValueError):
            status = "singular_jacobian"
            break
        if not np.all(np.isfinite(dx)):
            status = "singular_jacobian"
            break
        it += 1
        lam, accepted = 1.0, False
        for _ in range(6):
            xt = x + lam * dx
            gt = np.asarray(residual(xt), float).ravel()
            nt = float(np.max(np.abs(gt), initial=0.0))
            if np.isfinite(nt) and nt < nrm * (1.0 - 1e-4 * lam):
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            # accept a full step that stalls at round-off level, otherwise give up
            if np.isfinite(nt) and nt <= 10.0 * tol:
                x, g, nrm = xt, gt, nt
                continue
            status = "no_descent"
            break
        x, g, nrm = xt, gt, nt
    else:
        if np.isfinite(nrm) and nrm <= tol:
            status = "success"
    ok = status == "success"
    return RootResult(x=x, residual=nrm, success=ok, return_status=status, iterations=it,
                      wall_time=time.perf_counter() - t0, factor=lu)
