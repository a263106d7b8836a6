"""``casflutter bench identify``: the N = 5 paper-order identification benchmark (JSON)."""

from __future__ import annotations

import json
import statistics
import sys
import time

import numpy as np

PAPER_ORDERS = (3, 1, 1, 1, 2, 2)


def _timed_least_squares(residual, theta0, cost):
    """``scipy.optimize.least_squares`` (trf, 2-point Jacobian): seconds, our cost at its
    solution, residual evaluations, success."""
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    sol = least_squares(residual, theta0, method="trf", xtol=1e-10, ftol=1e-10, gtol=1e-10)
    return time.perf_counter() - t0, cost(sol.x), int(sol.nfev), bool(sol.success)


def _scipy_reference(structure, data, theta0, cost):
    """The same stage-2 problem (prediction error over the whole record) with
    ``scipy.optimize.least_squares`` from the same start: numpy residuals of the full
    record, finite-difference Jacobian (scipy's default), trust-region reflective."""
    from ...ident import HWLModel

    L = structure.max_lag
    n_rows = sum(r.n_samples - L for r in data.records)
    scale = np.sqrt(1.0 / (n_rows * structure.n_modes))

    def residual(theta):
        m = HWLModel(structure, theta, data.dt)
        return np.concatenate([((m.predict(r.y, r.u, r.v) - r.y)[L:] * scale).ravel()
                               for r in data.records])

    return _timed_least_squares(residual, theta0, cost)


def _scipy_reduced(structure, data, theta0, cost):
    """The same problem in casflutter's QR-reduced form (``Q'Y - R w(theta)``), handed to
    ``least_squares`` with a finite-difference Jacobian: isolates the solver from the
    formulation."""
    from ...ident._regression import regressor_matrix, weights_matrix

    Phi, Y = regressor_matrix(structure, data)
    col = np.linalg.norm(Phi, axis=0)
    Q, R = np.linalg.qr(Phi / col)
    C, RD = Q.T @ Y, R * col
    scale = np.sqrt(1.0 / (Y.shape[0] * structure.n_modes))

    def residual(theta):
        Wm = np.vstack(weights_matrix(structure, structure.weights(theta)))
        return ((C - RD @ Wm) * scale).ravel()

    return _timed_least_squares(residual, theta0, cost)


def _record(runs, method: str) -> dict:
    return {"t_s": statistics.median(r[0] for r in runs), "cost": float(runs[0][1]),
            "nfev": runs[0][2], "success": runs[0][3], "method": method}


def run(n_samples: int = 4000, noise: float = 0.05, seed: int = 1, repeat: int = 3,
        scipy_repeat: int = 1) -> dict:
    """Run the benchmark; times are medians over ``repeat`` runs."""
    from ...ident import identify, random_hwl_model, synthetic_data
    from ...ident._refine import prediction_problem

    truth = random_hwl_model(5, PAPER_ORDERS, seed=seed)
    data = synthetic_data(truth, n_samples, seed=seed + 1, noise=noise)
    runs = [identify(data, PAPER_ORDERS) for _ in range(repeat)]
    res = runs[-1]
    # the scaled problem stage 2 solved, for the reference
    sy, su, sv = data.scales()
    work = data.scaled(sy, su, sv)
    from ...ident import stage1
    theta0 = stage1(truth.structure, work).model.theta
    _, cost = prediction_problem(truth.structure, work)
    sc = [_scipy_reference(truth.structure, work, theta0, cost) for _ in range(scipy_repeat)]
    sr = [_scipy_reduced(truth.structure, work, theta0, cost) for _ in range(repeat)]
    t1 = statistics.median(r.t_stage1 for r in runs)
    t2 = statistics.median(r.t_stage2 for r in runs)
    return {
        "problem": f"N=5 synthetic HWL truth, orders {PAPER_ORDERS}, {n_samples} samples, "
                   f"band-limited chirps, {100 * noise:g}% white output noise, seed {seed}",
        "criterion": res.settings.criterion,
        "n_params": res.n_params,
        "fit_error_percent": [float(x) for x in res.fit.error_percent],
        "t_stage1_s": t1,
        "t_stage2_s": t2,
        "t_total_s": statistics.median(r.wall_time for r in runs),
        "cost": float(res.cost),
        "cost_initial": float(res.cost_initial),
        "ipopt_status": res.return_status,
        "ipopt_iterations": res.iterations,
        "repeats": repeat,
        "scipy_reference": _record(
            sc, "least_squares(trf), full-record numpy residuals, 2-point Jacobian"),
        "scipy_reduced_reference": _record(
            sr, "least_squares(trf) on casflutter's QR-reduced residual, 2-point Jacobian"),
        "speedup_stage2_vs_scipy": statistics.median(s[0] for s in sc) / t2,
    }


def _main(args) -> int:
    out = run(args.samples, args.noise, args.seed, args.repeat)
    text = json.dumps(out, indent=2)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text + "\n")
    print(text if not args.out else f"wrote {args.out}", file=sys.stdout)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("identify", help="identification benchmark (N = 5, paper orders)",
                              description=__doc__)
    p.add_argument("--out", help="JSON file to write (default: print)")
    p.add_argument("--samples", type=int, default=4000)
    p.add_argument("--noise", type=float, default=0.05,
                   help="relative output noise, so that stage 2 has work to do (default 0.05)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--repeat", type=int, default=3, help="runs of casflutter (median)")
    p.set_defaults(func=_main)
