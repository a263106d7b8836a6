"""``casflutter bench identify``: identification benchmarks (JSON).

Two cases:

``paper``
    N = 5 synthetic HWL truth with the paper's orders (3, 1, 1, 1, 2, 2), 4000 samples,
    band-limited chirps, white output noise.
``duffing``
    One input, one output, 65,000 samples of a Duffing-type oscillator (cubic stiffness in
    the feedback) sampled at 10x its resonance with 1 % output noise
    (:func:`casflutter.ident.duffing_data`), fitted with the 14-parameter HWL model of orders
    (1, 5, 5, 0, 1, 3).

Each run reports casflutter's times (median over ``--repeat``), its cost, and the same stage-2
problem solved by ``scipy.optimize.least_squares`` from the same start: for the prediction
criterion on the full-record residual and on casflutter's QR-reduced residual, for the
simulation criterion on casflutter's free-run residual (same decision vector, initial outputs
included) with a finite-difference Jacobian and with casflutter's exact Jacobian.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import sys
import time
import tracemalloc

import numpy as np

from ..._outputs import atomic_file, check_output_path
from ...errors import ConfigError

PAPER_ORDERS = (3, 1, 1, 1, 2, 2)
DUFFING_ORDERS = (1, 5, 5, 0, 1, 3)
CASES = ("paper", "duffing")


def _timed_least_squares(residual, x0, cost, jac="2-point"):
    """``scipy.optimize.least_squares`` (trf): seconds, our cost at its solution, residual
    evaluations, success."""
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    sol = least_squares(residual, x0, jac=jac, method="trf", xtol=1e-10, ftol=1e-10,
                        gtol=1e-10)
    return time.perf_counter() - t0, cost(sol.x), int(sol.nfev), bool(sol.success)


def _scipy_prediction(structure, data, theta0, cost):
    """The prediction-error problem over the whole record (numpy residuals, 2-point
    Jacobian)."""
    from ...ident import HWLModel

    L = structure.max_lag
    n_rows = sum(r.n_samples - L for r in data.records)
    scale = np.sqrt(1.0 / (n_rows * structure.n_modes))

    def residual(theta):
        m = HWLModel(structure, theta, data.dt)
        return np.concatenate([((m.predict(r.y, r.u, r.v) - r.y)[L:] * scale).ravel()
                               for r in data.records])

    return _timed_least_squares(residual, theta0, cost)


def _scipy_prediction_reduced(structure, data, theta0, cost):
    """The prediction-error problem in casflutter's QR-reduced form (``Q'Y - R w(theta)``)."""
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


def _scipy_simulation(problem, x0, exact_jacobian: bool):
    """The free-run problem: casflutter's residual (a diverging free run returns a large
    residual, which trf rejects), 2-point or exact Jacobian."""
    big = np.full(problem.n_rows * problem.N, 1e10)

    def residual(x):
        r = problem.residual(x)[0]
        return big if r is None else r

    def jac(x):
        r, cache, _ = problem.residual(x)
        if r is None:
            return np.zeros((big.size, problem.n_x))
        return problem.jacobian(cache)

    return _timed_least_squares(residual, x0, problem.cost,
                                jac=jac if exact_jacobian else "2-point")


def _record(runs, method: str) -> dict:
    cost = float(runs[0][1])
    return {"t_s": statistics.median(r[0] for r in runs),
            "cost": cost if np.isfinite(cost) else None,
            "nfev": runs[0][2], "success": runs[0][3], "method": method}


def _finite(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _case(case: str, n_samples: int | None, noise: float | None, seed: int):
    from ...ident import duffing_data, random_hwl_model, synthetic_data

    if case == "paper":
        n = 4000 if n_samples is None else n_samples
        nz = 0.05 if noise is None else noise
        truth = random_hwl_model(5, PAPER_ORDERS, seed=seed)
        data = synthetic_data(truth, n, seed=seed + 1, noise=nz)
        text = (f"N=5 synthetic HWL truth, orders {PAPER_ORDERS}, {n} samples, band-limited "
                f"chirps, {100 * nz:g}% white output noise, seed {seed}")
        return data, PAPER_ORDERS, text
    n = 65000 if n_samples is None else n_samples
    nz = 0.01 if noise is None else noise
    data = duffing_data(n, noise=nz, seed=seed)
    text = (f"SISO Duffing-type oscillator (cubic stiffness), sampled at 10x resonance, {n} "
            f"samples, {100 * nz:g}% white output noise, seed {seed}; HWL orders "
            f"{DUFFING_ORDERS}")
    return data, DUFFING_ORDERS, text


def run(n_samples: int | None = None, noise: float | None = None, seed: int = 1,
        repeat: int = 3, scipy_repeat: int = 1, criterion: str = "prediction",
        case: str = "paper") -> dict:
    """Run the benchmark; times are medians over ``repeat`` runs."""
    from ...ident import HWLOrders, HWLStructure, identify, stage1
    from ...ident._refine import prediction_problem
    from ...ident._simfit import FreeRunProblem

    if case not in CASES:
        raise ConfigError(f"bench case {case!r} is not known: use one of {CASES}")
    data, orders, text = _case(case, n_samples, noise, seed)
    runs = [identify(data, orders, criterion=criterion) for _ in range(repeat)]
    res = runs[-1]
    tracemalloc.start()
    identify(data, orders, criterion=criterion)
    peak_traced = tracemalloc.get_traced_memory()[1] / 2 ** 20
    tracemalloc.stop()
    # process high-water mark after casflutter's runs, before the scipy references
    peak_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    # the scaled problem stage 2 solved, for the references
    structure = HWLStructure(HWLOrders.from_tuple(orders), data.n_modes, data.has_u, data.has_v)
    sy, su, sv = data.scales()
    work = data.scaled(sy, su, sv)
    theta0 = stage1(structure, work).model.theta
    if criterion == "prediction":
        _, cost = prediction_problem(structure, work)
        sc = [_scipy_prediction(structure, work, theta0, cost) for _ in range(scipy_repeat)]
        sr = [_scipy_prediction_reduced(structure, work, theta0, cost) for _ in range(repeat)]
        m1 = "least_squares(trf), full-record numpy residuals, 2-point Jacobian"
        m2 = "least_squares(trf) on casflutter's QR-reduced residual, 2-point Jacobian"
    else:
        problem = FreeRunProblem(structure, work, 0.0, theta0)
        x0 = problem.x0(theta0)
        sc = [_scipy_simulation(problem, x0, False) for _ in range(scipy_repeat)]
        sr = [_scipy_simulation(problem, x0, True) for _ in range(scipy_repeat)]
        m1 = ("least_squares(trf) on casflutter's free-run residual (same decision vector, "
              "initial outputs included), 2-point Jacobian")
        m2 = "least_squares(trf) on casflutter's free-run residual with its exact Jacobian"
    t1 = statistics.median(r.t_stage1 for r in runs)
    t2 = statistics.median(r.t_stage2 for r in runs)
    threads = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                              "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
    return {
        "problem": text,
        "case": case,
        "criterion": res.settings.criterion,
        "solver": res.solver,
        "orders": list(orders),
        "n_params": res.n_params,
        "n_samples": data.n_samples,
        "fit_error_percent": [_finite(x) for x in res.fit.error_percent],
        "t_stage1_s": t1,
        "t_stage2_s": t2,
        "t_total_s": statistics.median(r.wall_time for r in runs),
        "cost": _finite(res.cost),
        "cost_initial": _finite(res.cost_initial),
        "ipopt_status": res.return_status,
        "ipopt_iterations": res.iterations,
        "repeats": repeat,
        "peak_traced_memory_mb": peak_traced,
        "peak_rss_mb": peak_rss,
        "threads": threads,
        "scipy_reference": _record(sc, m1),
        "scipy_reduced_reference": _record(sr, m2),
        "speedup_stage2_vs_scipy": statistics.median(s[0] for s in sc) / t2,
    }


def _main(args) -> int:
    if args.out:
        check_output_path(args.out, what="--out", suffixes=(".json",))
    out = run(args.samples, args.noise, args.seed, args.repeat, criterion=args.criterion,
              case=args.case)
    text = json.dumps(out, indent=2, allow_nan=False)
    if args.out:
        with atomic_file(args.out, what="--out") as tmp:
            tmp.write_text(text + "\n")
    print(text if not args.out else f"wrote {args.out}", file=sys.stdout)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("identify", help="identification benchmarks (paper case, "
                              "65k-sample Duffing case)", description=__doc__)
    p.add_argument("--out", help="JSON file to write (default: print)")
    p.add_argument("--case", default="paper", choices=CASES,
                   help="paper: N = 5, 4000 samples; duffing: SISO, 65,000 samples")
    p.add_argument("--criterion", default="prediction", choices=["prediction", "simulation"],
                   help="stage-2 criterion: prediction error (default) or free-run "
                        "simulation error")
    p.add_argument("--samples", type=int, default=None,
                   help="record length (default: 4000 paper, 65000 duffing)")
    p.add_argument("--noise", type=float, default=None,
                   help="relative output noise (default: 0.05 paper, 0.01 duffing)")
    p.add_argument("--seed", type=int, default=1, help="seed of the synthetic case (default 1)")
    p.add_argument("--repeat", type=int, default=3, help="runs of casflutter (median)")
    p.set_defaults(func=_main)
