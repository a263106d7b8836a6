"""``casflutter sensitivity CONFIG.toml``: ranked normalised flutter-speed sensitivities.

CONFIG::

    [sensitivity]
    problem = "typical_section"
    parameters = ["a", "e", "mu", "r2", "sigma", "zeta"]   # default: all
    V_min = 0.02
    V_max = 4.0
    n_grid = 81
    rel_step = 1e-6
    method = "eigen"      # or "nlp": parametric sensitivity of the Hopf-point NLP
    check = true          # also finite differences of Vf itself

    [params]              # nominal point (changes from the published case)
    zeta = 0.01

With a ``[gamma]`` table instead of ``[sensitivity]``, the optimal γ of fixed-order H∞
synthesis is differentiated (:func:`casflutter.study.gamma_sensitivity`)::

    [gamma]
    plant = "package.module:function"   # params -> generalised plant StateSpace(s)
    nmeas = 1
    ncon = 1
    order = 0             # controller order
    starts = 2
    seed = 0

    [params]              # every parameter of the plant function (all differentiated)
    a = -1.0
"""

from __future__ import annotations

import json

__all__ = ["register", "run"]


def register(subparsers) -> None:
    """Add the ``sensitivity`` sub-command."""
    p = subparsers.add_parser(
        "sensitivity", help="ranked flutter-speed (or optimal gamma) sensitivities",
        description="Derivatives of the flutter speed and frequency with respect to the "
                    "problem parameters, by eigenvalue perturbation at the crossing, printed "
                    "as a table ranked by normalised sensitivity (p/Vf) dVf/dp; with a "
                    "[gamma] table, derivatives of the optimal gamma of fixed-order "
                    "synthesis.")
    p.add_argument("config", nargs="?", help="TOML file with [sensitivity] and [params]")
    p.add_argument("--problem", default=None, help="problem name (instead of / overriding CONFIG)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="nominal parameter change (repeatable)")
    p.add_argument("--parameters", default=None, help="comma-separated parameters")
    p.add_argument("--method", choices=("eigen", "nlp"), default=None,
                   help="eigen: eigenvalue perturbation (default); nlp: parametric "
                        "sensitivity of the Hopf-point NLP (CasADi)")
    p.add_argument("--check", action="store_true",
                   help="compare with finite differences of the flutter speed")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def _number(table: str, key: str, value, *, low=None, high=None, integer=False,
            positive=False) -> float | int:
    """A numeric entry of the config file, checked (type, finite, range) with a message that
    names the table and key."""
    import math  # noqa: PLC0415

    from ...errors import ConfigError  # noqa: PLC0415

    ok = not isinstance(value, bool) and isinstance(value, (int, float))
    if ok and integer:
        ok = float(value).is_integer()
    if ok:
        v = float(value)
        ok = math.isfinite(v) and (low is None or v >= low) and (high is None or v <= high) \
            and (not positive or v > 0)
    if not ok:
        kind = "an integer" if integer else "a finite number"
        rng = "".join([" > 0" if positive else "", f" >= {low}" if low is not None else "",
                       f" <= {high}" if high is not None else ""])
        raise ConfigError(f"[{table}] {key} = {value!r}: give {kind}{rng}")
    return int(value) if integer else float(value)


def _check_sensitivity(sec: dict, params: dict) -> None:
    """Types and ranges of the ``[sensitivity]`` and ``[params]`` entries."""
    from ...errors import ConfigError  # noqa: PLC0415

    if "problem" in sec and not isinstance(sec["problem"], str):
        raise ConfigError(f"[sensitivity] problem = {sec['problem']!r}: give a problem name")
    v_min = _number("sensitivity", "V_min", sec.get("V_min", 0.02), low=0.0)
    v_max = _number("sensitivity", "V_max", sec.get("V_max", 4.0), low=0.0)
    if not v_min < v_max:
        raise ConfigError(f"[sensitivity] V_min = {v_min} must be below V_max = {v_max}")
    _number("sensitivity", "n_grid", sec.get("n_grid", 81), low=3, integer=True)
    _number("sensitivity", "rel_step", sec.get("rel_step", 1e-6), positive=True, high=0.1)
    if not isinstance(sec.get("check", False), bool):
        raise ConfigError(f"[sensitivity] check = {sec['check']!r}: give true or false")
    names = sec.get("parameters")
    if names is not None and (not isinstance(names, list)
                              or not all(isinstance(n, str) for n in names)):
        raise ConfigError(f"[sensitivity] parameters = {names!r}: give a list of parameter "
                          'names, e.g. ["mu", "zeta"]')
    for k, v in params.items():
        _number("params", k, v)


def _config(args) -> tuple[dict, dict]:
    from ..._resources import read_toml
    from ..._settings import reject_unknown
    from ...errors import ConfigError

    cfg: dict = {}
    if args.config:
        cfg = read_toml(args.config, "config file")
        reject_unknown(cfg, {"sensitivity", "params", "gamma"}, "unknown table(s)",
                       allowed_text="[sensitivity] or [gamma], and [params]")
    sec = dict(cfg.get("sensitivity", {}))
    allowed = {"problem", "parameters", "V_min", "V_max", "n_grid", "rel_step", "check",
               "method"}
    reject_unknown(sec, allowed, where=" in [sensitivity]")
    params = dict(cfg.get("params", {}))
    for item in args.sets:
        name, sep, value = item.partition("=")
        if not sep:
            raise ConfigError(f"--set {item!r} is not NAME=VALUE")
        try:
            params[name.strip()] = float(value)
        except ValueError:
            raise ConfigError(f"--set {item!r}: value must be a number") from None
    if args.problem:
        sec["problem"] = args.problem
    if args.parameters:
        sec["parameters"] = [s.strip() for s in args.parameters.split(",") if s.strip()]
    if args.check:
        sec["check"] = True
    if args.method:
        sec["method"] = args.method
    if sec.get("method", "eigen") not in ("eigen", "nlp"):
        raise ConfigError(f"method must be 'eigen' or 'nlp', got {sec['method']!r}")
    _check_sensitivity(sec, params)
    return sec, params


def _gamma(cfg: dict, args) -> int:
    """The ``[gamma]`` form: synthesize, then dγ*/dp at the solution."""
    import importlib  # noqa: PLC0415

    from ...design import synthesize  # noqa: PLC0415
    from ...errors import ConfigError  # noqa: PLC0415
    from ...study import gamma_sensitivity  # noqa: PLC0415

    g = dict(cfg["gamma"])
    allowed = {"plant", "nmeas", "ncon", "order", "starts", "seed", "rel_step", "tol"}
    bad = set(g) - allowed
    if bad or not {"plant", "nmeas", "ncon"} <= set(g):
        raise ConfigError(f"[gamma] needs plant, nmeas, ncon (optional order, starts, seed, "
                          f"rel_step, tol); unknown: {sorted(bad)}")
    params = {k: _number("params", k, v) for k, v in cfg.get("params", {}).items()}
    nmeas = _number("gamma", "nmeas", g["nmeas"], low=1, integer=True)
    ncon = _number("gamma", "ncon", g["ncon"], low=1, integer=True)
    order = _number("gamma", "order", g.get("order", 0), low=0, integer=True)
    starts = _number("gamma", "starts", g.get("starts", 2), low=1, integer=True)
    seed = _number("gamma", "seed", g.get("seed", 0), low=0, integer=True)
    tol = _number("gamma", "tol", g.get("tol", 1e-6), positive=True)
    rel_step = _number("gamma", "rel_step", g.get("rel_step", 1e-6), positive=True, high=0.1)
    mod, _, attr = str(g["plant"]).partition(":")
    try:
        plant_fn = getattr(importlib.import_module(mod), attr)
    except (ImportError, AttributeError, ValueError) as exc:
        raise ConfigError(f"[gamma] plant {g['plant']!r} cannot be imported ({exc}); give "
                          "'package.module:function'") from None
    res = synthesize(plant_fn(params), nmeas, ncon, order, starts=starts, seed=seed,
                     options={"tol": tol})
    gs = gamma_sensitivity(plant_fn, params, nmeas, ncon, res, rel_step=rel_step)
    rows = [{"name": n, "value": params[n], "dgamma_dp": d, "normalized": z}
            for n, d, z in gs.ranked()]
    if args.json:
        print(json.dumps({"gamma": gs.gamma, "synthesis_gamma": gs.synthesis_gamma,
                          "order": res.order, "peaks": gs.peaks,
                          "multipliers": gs.multipliers, "kkt_residual": gs.kkt_residual,
                          "method": gs.method, "sensitivities": rows}, indent=2))
        return 0
    print(f"gamma* = {gs.gamma:.6g} (order {res.order}, {len(gs.peaks)} active peak(s), "
          f"stationarity residual {gs.kkt_residual:.1e}; {gs.method})")
    print(f"{'rank':>4}  {'parameter':<12} {'value':>11} {'dgamma/dp':>13} {'normalised':>11}")
    for i, r in enumerate(rows, 1):
        print(f"{i:>4}  {r['name']:<12} {r['value']:>11.5g} {r['dgamma_dp']:>+13.6g} "
              f"{r['normalized']:>+11.5f}")
    return 0


def run(args) -> int:
    """Handler: print the ranked table (and the finite-difference check)."""
    from ..._resources import read_toml
    from ...study import flutter_sensitivity, flutter_sensitivity_nlp, flutter_speed_fd

    if args.config:
        raw = read_toml(args.config, "config file")
        if "gamma" in raw:
            _config(args)  # validates the tables
            return _gamma(raw, args)
    sec, params = _config(args)
    problem = str(sec.get("problem", "typical_section"))
    V_range = (float(sec.get("V_min", 0.02)), float(sec.get("V_max", 4.0)))
    n_grid = int(sec.get("n_grid", 81))
    if sec.get("method", "eigen") == "nlp":
        res = flutter_sensitivity_nlp(problem, sec.get("parameters"), params=params,
                                      V_range=V_range, rel_step=float(sec.get("rel_step", 1e-6)))
    else:
        res = flutter_sensitivity(problem, sec.get("parameters"), params=params,
                                  V_range=V_range, n_grid=n_grid,
                                  rel_step=float(sec.get("rel_step", 1e-6)))
    data = res.as_dict()
    if sec.get("check"):
        for row in data["sensitivities"]:
            fd = flutter_speed_fd(problem, row["name"], params=params, V_range=V_range,
                                  n_grid=n_grid)
            row["dVf_dp_fd"] = fd
            row["fd_difference"] = abs(row["dVf_dp"] - fd)
    if args.json:
        print(json.dumps(data, indent=2))
        return 0
    print(res.table())
    if sec.get("check"):
        print("\nfinite-difference check (central differences of the refined Vf):")
        print(f"  {'parameter':<12} {'derivative':>14} {'finite diff.':>14} {'|diff|':>10}")
        for row in data["sensitivities"]:
            print(f"  {row['name']:<12} {row['dVf_dp']:>+14.6g} {row['dVf_dp_fd']:>+14.6g} "
                  f"{row['fd_difference']:>10.2e}")
    return 0
