"""``casflutter identify``: identify an HWL ROM from a data file and print the fit table.

With ``--search [GRID]`` the orders are first chosen by free-run error on the held-out last
part of the records (``--validation``, default 30 %): every candidate of the grid
(default ``na=1:4 p=1:3 q=1:3`` around ``--orders``) is identified and scored, the table of
candidates is printed, and the chosen orders are then identified on all the data.

Exit status: 0 for a converged fit (also one stopped at the acceptable level, with a warning
line), 1 for an error, a fit that did not converge or diverges in free run, or a fit stopped
by ``--max-time`` (its best iterate is still reported and written).
"""

from __future__ import annotations

import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np

from ..._outputs import atomic_file, check_output_path
from ...errors import ConfigError, DataWarning


def _orders(text: str):
    from ...ident import HWLOrders

    return HWLOrders.from_tuple(text)


def _finite(x):
    """JSON-safe number: None for NaN/inf (valid JSON, never a bare NaN)."""
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_finite(v) for v in np.asarray(x, dtype=float).ravel()]
    x = float(x)
    return x if math.isfinite(x) else None


def _regularization(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"--regularization {text!r}: give a finite number >= 0") from None
    if not (math.isfinite(value) and value >= 0):
        raise ConfigError(f"--regularization {text!r}: give a finite number >= 0 "
                          "(0: no regularisation)")
    return value


def _seconds_or_name(text: str) -> float | str:
    """The ``--dt`` word: a number of seconds, else the name of a variable holding it."""
    try:
        return float(text)
    except ValueError:
        return text


def _dt(value: float | str | None, suffix: str) -> float | str | None:
    """``--dt``: the sampling time [s], or (a .mat file) the variable holding it."""
    if isinstance(value, str) and suffix != ".mat":
        raise ConfigError(f"--dt {value!r}: give the sampling time in seconds (a variable "
                          "name holding it works for a .mat file only)")
    return value


def _nf(text: str | None) -> int | str:
    """``--nf``: the order of Σf, a positive integer or ``auto`` (the default)."""
    if text is None or text.strip().lower() == "auto":
        return "auto"
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or value < 1:
        raise ConfigError(f"--nf {text!r}: give a positive integer, or --nf auto (the default: "
                          "the order from the Hankel singular values)")
    return value


def _load(args):
    from ...data import IOData

    path = Path(args.data)
    if not path.exists():
        raise ConfigError(f"data file {path} does not exist")
    suffix = path.suffix.lower()
    dt = _dt(args.dt, suffix)
    split = lambda s: [c for c in s.split(",") if c] if s else None  # noqa: E731
    if suffix == ".npz":
        return IOData.from_npz(path, dt=dt)
    if suffix == ".csv":
        if not args.y:
            raise ConfigError("a CSV needs --y COL1,COL2,... (and --u/--v)")
        return IOData.from_csv(path, y=split(args.y), u=split(args.u), v=args.v,
                               time=args.time, dt=dt)
    if suffix == ".mat":
        if not args.y:
            raise ConfigError("a .mat file needs --y VARIABLE (and --u/--v VARIABLE)")
        return IOData.from_mat(path, y=args.y, u=args.u, v=args.v, dt=dt, fs=args.fs)
    raise ConfigError(f"unknown data format {suffix!r}: use .npz, .csv or .mat")


def _main(args) -> int:
    from ...ident import IdentificationWarning, identify, parse_grid, select_orders
    from ...realize import realize

    # every argument checked before any work
    orders = _orders(args.orders)
    reg = _regularization(args.regularization)
    nf = _nf(args.nf)
    _dt(args.dt, Path(args.data).suffix.lower())
    out_path = None
    if args.out:   # numpy's own rule for savez: the model file ends in .npz
        out_path = check_output_path(args.out, what="--out")
        if not out_path.name.endswith(".npz"):
            out_path = check_output_path(out_path.with_name(out_path.name + ".npz"),
                                         what="--out")
    if args.max_time is not None and not (math.isfinite(args.max_time) and args.max_time > 0):
        raise ConfigError(f"--max-time {args.max_time}: give a positive number of seconds")
    grid = None if args.search in (None, "default") else parse_grid(args.search)
    if not 0 < args.validation < 1:
        raise ConfigError(f"--validation {args.validation}: give a fraction in (0, 1)")
    settings = dict(criterion=args.criterion, regularization=reg, offset=args.offset,
                    max_time=args.max_time)
    with warnings.catch_warnings(record=True) as caught:   # said before the fit, not after
        warnings.simplefilter("always", DataWarning)
        data = _load(args)
    for w in caught:
        print(f"casflutter: warning: {w.message}", file=sys.stderr)
    selection = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", IdentificationWarning)
        if args.search is not None:
            selection = select_orders(data, grid, base=orders, validation=args.validation,
                                      **settings)
            orders = selection.best.orders
            if not args.json:
                print(selection.table())
                print(f"identifying {orders} on all the data")
        res = identify(data, orders, **settings)
    for w in caught:   # one line each on stderr
        print(f"casflutter: warning: {w.message}", file=sys.stderr)
    real = realize(res.model, nf)
    if out_path is not None:   # written under a temporary name and renamed
        with atomic_file(out_path, what="--out") as tmp, open(tmp, "wb") as fh:
            res.model.save(fh)
    if args.json:
        out = {
            "orders": list(res.model.orders.as_tuple()), "n_params": res.n_params,
            "criterion": res.settings.criterion, "solver": res.solver,
            "fit_error_percent": _finite(res.fit.error_percent),
            "nrmse": _finite(res.fit.nrmse), "status": res.return_status,
            "success": bool(res.success), "iterations": res.iterations,
            "cost": _finite(res.cost), "cost_initial": _finite(res.cost_initial),
            "wall_time_s": res.wall_time, "nf": real.order,
            "hankel_singular_values": _finite(real.hankel_singular_values[:3 * real.order]),
        }
        if selection is not None:
            out["search"] = [{"orders": list(c.orders.as_tuple()), "n_params": c.n_params,
                              "held_out_error_percent": _finite(c.score),
                              "time_s": c.wall_time, "status": c.status,
                              "chosen": c is selection.best} for c in selection.candidates]
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(res.summary())
        print(f"linear part realised by ERA + Tustin: nf = {real.order} "
              f"(exact-order bound {real.exact_order_bound})")
        if out_path is not None:
            print(f"model written to {out_path}")
    if res.return_status in ("Maximum_WallTime_Exceeded",):
        print(f"casflutter: identification stopped at --max-time ({res.return_status}); the "
              "best iterate is reported", file=sys.stderr)
        return 1
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("identify", help="identify an HWL ROM from input-output data",
                              description=__doc__)
    p.add_argument("data", help="records: .npz (arrays y,u,v,dt), .csv or .mat")
    p.add_argument("--orders", default="3,1,1,1,2,2", help="mu,na,nb,r,p,q (default: paper)")
    p.add_argument("--criterion", default="prediction", choices=["prediction", "simulation"],
                   help="stage-2 criterion: mu-step-ahead prediction error (default, the "
                        "paper's, fast) or free-run simulation error (slower, for a model "
                        "that must run free, e.g. in the loop)")
    p.add_argument("--regularization", default="0", help="finite number >= 0 (default 0)")
    p.add_argument("--offset", action="store_true",
                   help="fit a constant term (identify on centred data, exact back-transform)")
    p.add_argument("--max-time", type=float, default=None,
                   help="wall-time budget of stage 2 [s]: the best iterate is returned")
    p.add_argument("--search", nargs="?", const="default", default=None, metavar="GRID",
                   help="choose the orders by held-out free-run error over GRID, e.g. "
                        "'na=1:4 p=1,2 q=1:3' (default grid: na=1:4 p=1:3 q=1:3 around "
                        "--orders)")
    p.add_argument("--validation", type=float, default=0.3,
                   help="held-out fraction of each record for --search (default 0.3)")
    p.add_argument("--y", help="outputs y, the generalised forces: CSV columns COL1,COL2,... "
                               "or a .mat variable")
    p.add_argument("--u", help="modal-displacement inputs u, one per mode: CSV columns "
                               "COL1,COL2,... or a .mat variable")
    p.add_argument("--v", help="flap input v: a CSV column or a .mat variable (omit for a "
                               "record without a flap)")
    p.add_argument("--time", default="t", help="CSV time column")
    p.add_argument("--dt", type=_seconds_or_name,
                   help="sampling time [s] (overrides a CSV time column), or for a MATLAB "
                        ".mat file the variable holding it")
    p.add_argument("--fs", help=".mat variable holding the sampling frequency")
    p.add_argument("--nf", help="order of Σf: a positive integer, or auto (default: from the "
                                "Hankel singular values)")
    p.add_argument("--out", help="write the model (.npz; written under a temporary name "
                                 "beside it and renamed when complete)")
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.set_defaults(func=_main)
