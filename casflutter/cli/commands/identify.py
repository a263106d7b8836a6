"""``casflutter identify``: identify an HWL ROM from a data file and print the fit table."""

from __future__ import annotations

import json
from pathlib import Path

from ...errors import ConfigError


def _orders(text: str):
    try:
        vals = tuple(int(x) for x in text.replace(" ", "").split(","))
    except ValueError:
        raise ConfigError(f"--orders {text!r}: give six integers mu,na,nb,r,p,q") from None
    return vals


def _load(args):
    from ...data import IOData

    path = Path(args.data)
    if not path.exists():
        raise ConfigError(f"data file {path} does not exist")
    suffix = path.suffix.lower()
    split = lambda s: [c for c in s.split(",") if c] if s else None  # noqa: E731
    if suffix == ".npz":
        return IOData.from_npz(path, dt=args.dt)
    if suffix == ".csv":
        if not args.y:
            raise ConfigError("a CSV needs --y COL1,COL2,... (and --u/--v)")
        return IOData.from_csv(path, y=split(args.y), u=split(args.u), v=args.v,
                               time=args.time, dt=args.dt)
    if suffix == ".mat":
        if not args.y:
            raise ConfigError("a .mat file needs --y VARIABLE (and --u/--v VARIABLE)")
        return IOData.from_mat(path, y=args.y, u=args.u, v=args.v, dt=args.dt, fs=args.fs)
    raise ConfigError(f"unknown data format {suffix!r}: use .npz, .csv or .mat")


def _main(args) -> int:
    from ...ident import identify
    from ...realize import realize

    data = _load(args)
    res = identify(data, _orders(args.orders), criterion=args.criterion,
                   regularization=args.regularization)
    real = realize(res.model, args.nf if args.nf else "auto")
    if args.out:
        res.model.save(args.out)
    if args.json:
        print(json.dumps({
            "orders": list(res.model.orders.as_tuple()), "n_params": res.n_params,
            "fit_error_percent": res.fit.error_percent.tolist(),
            "nrmse": res.fit.nrmse.tolist(), "status": res.return_status,
            "iterations": res.iterations, "wall_time_s": res.wall_time, "nf": real.order,
            "hankel_singular_values": real.hankel_singular_values[:3 * real.order].tolist(),
        }, indent=2))
    else:
        print(res.summary())
        print(f"linear part realised by ERA + Tustin: nf = {real.order} "
              f"(exact-order bound {real.exact_order_bound})")
        if args.out:
            print(f"model written to {args.out}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("identify", help="identify an HWL ROM from input-output data",
                              description=__doc__)
    p.add_argument("data", help="records: .npz (arrays y,u,v,dt), .csv or .mat")
    p.add_argument("--orders", default="3,1,1,1,2,2", help="mu,na,nb,r,p,q (default: paper)")
    p.add_argument("--criterion", default="prediction", choices=["prediction", "simulation"])
    p.add_argument("--regularization", type=float, default=0.0)
    p.add_argument("--y", help="output columns/variable"), p.add_argument("--u"), p.add_argument("--v")
    p.add_argument("--time", default="t", help="CSV time column")
    p.add_argument("--dt", type=float, help="sampling time [s]")
    p.add_argument("--fs", help=".mat variable holding the sampling frequency")
    p.add_argument("--nf", type=int, help="order of Σf (default: from the Hankel singular values)")
    p.add_argument("--out", help="write the model (.npz)")
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.set_defaults(func=_main)
