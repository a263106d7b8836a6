"""``casflutter demo``: identification of the paper-sized synthetic case (N = 5, orders
(3,1,1,1,2,2), chirp inputs), its fit table, and the realisation of Σf."""

from __future__ import annotations

import math

import numpy as np

from ...errors import ConfigError


def _main(args) -> int:
    from ...ident import identify, paper_parameter_count, random_hwl_model, synthetic_data
    from ...realize import realize

    if args.seed < 0:
        raise ConfigError(f"--seed {args.seed}: give an integer >= 0")
    if not (math.isfinite(args.noise) and 0 <= args.noise < 1):
        raise ConfigError(f"--noise {args.noise}: give the relative output noise as a number "
                          "in [0, 1), e.g. 0.02")
    orders = (3, 1, 1, 1, 2, 2)
    truth = random_hwl_model(5, orders, seed=args.seed)
    data = synthetic_data(truth, 4000, seed=args.seed + 1, noise=args.noise)
    print(f"data: {len(data.records)} record, {data.n_samples} samples, dt = {data.dt} s, "
          f"{100 * args.noise:g}% output noise")
    res = identify(data, orders)
    print(res.summary())
    print(f"parameters: {res.n_params} free ({res.model.structure.n_coefficients} in eq. 3 "
          f"before normalisation; the paper's formula gives {paper_parameter_count(5, res.model.orders)})")
    val = synthetic_data(truth, 2000, seed=args.seed + 7).records[0]
    ysim = res.model.simulate(val.u, val.v, y0=val.y[:truth.max_lag])
    err = 100 * np.linalg.norm(ysim - val.y, axis=0) / np.linalg.norm(val.y, axis=0)
    print("free-run error against the noise-free truth on a fresh chirp record [%]: "
          + ", ".join(f"{e:.3f}" for e in err))
    for nf in ("auto", 15):
        real = realize(res.model, nf)
        S = real.hankel_singular_values
        print(f"Σf by ERA + Tustin, order {nf}: nf = {real.order}; Hankel singular values "
              f"σ15/σ1 = {S[14] / S[0]:.2e}, σ25/σ1 = {S[24] / S[0]:.2e}, σ26/σ1 = {S[25] / S[0]:.2e}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("demo", help="identify the paper-sized synthetic case",
                              description=__doc__)
    p.add_argument("--seed", type=int, default=1,
                   help="seed of the random truth model (its records use seed + 1; default 1)")
    p.add_argument("--noise", type=float, default=0.02,
                   help="relative output noise of the records, in [0, 1) (default 0.02)")
    p.set_defaults(func=_main)
