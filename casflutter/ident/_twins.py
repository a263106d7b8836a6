"""CasADi twins of the HWL model (eq. 3): the mu-step prediction and the free run as
``casadi.Function`` objects built from the same formulas as the numpy model in
:mod:`._model`, for the Ipopt NLPs of stage 2 and for users who embed the ROM in their own
CasADi problems."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ._structure import HWLStructure, _ar_part, _input_part

__all__ = ["hwl_predict_function", "hwl_simulate_function", "ar_weights", "recursion_step"]


def ar_weights(structure: HWLStructure, W) -> "ca.MX | np.ndarray":
    """The autoregressive weights ``A^(m) ∘ alpha^[l]`` stacked in one column (the only
    parameters the free-run recursion needs)."""
    o = structure.orders
    mats = [W["ar"][m][l] for m in range(o.na) for l in range(o.q)]
    if mats and isinstance(mats[0], (ca.MX, ca.SX, ca.DM)):
        return ca.vertcat(*[ca.vec(w) for w in mats])
    return np.concatenate([np.ravel(w, order="F") for w in mats])


def recursion_step(structure: HWLStructure) -> ca.Function:
    """One step of the free-run recursion: ``(hist, xin_k, w_ar) -> hist_next``.

    ``hist = [y(k-1); ...; y(k-H)]`` (each block N long, ``H`` the largest output lag);
    ``xin_k`` the input part of eq. 3 at time k; ``w_ar`` from :func:`ar_weights`.  The first
    N entries of ``hist_next`` are ``y(k)``.  Built from SX so that ``mapaccum`` over long
    records runs at compiled-expression speed.
    """
    o, N = structure.orders, structure.n_modes
    lags = o.ar_lags()
    H = max(lags)
    hist = ca.SX.sym("hist", H * N)
    xk = ca.SX.sym("xin", N)
    w_ar = ca.SX.sym("w_ar", o.na * o.q * N * N)
    yk = xk
    pos = 0
    for lag in lags:
        past = hist[(lag - 1) * N:lag * N]
        for l in range(1, o.q + 1):
            w = ca.reshape(w_ar[pos:pos + N * N], N, N)
            pos += N * N
            yk = yk - ca.mtimes(w, past ** l)
    new = ca.vertcat(yk, hist[:(H - 1) * N]) if H > 1 else yk
    return ca.Function("hwl_step", [hist, xk, w_ar], [new])


def _sym_signals(structure: HWLStructure, n_samples: int):
    N = structure.n_modes
    theta = ca.MX.sym("theta", structure.n_params)
    u = ca.MX.sym("u", n_samples, N) if structure.has_u else None
    v = ca.MX.sym("v", n_samples, 1) if structure.has_v else None
    return theta, u, v


def hwl_predict_function(structure: HWLStructure, n_samples: int) -> ca.Function:
    """CasADi twin of :meth:`HWLModel.predict`.

    ``f(theta, y, [u], [v]) -> yhat`` with ``yhat`` of shape ``(K - max_lag, N)`` (the rows
    where a prediction exists).  Inputs u, v appear only when the structure has them.
    """
    theta, u, v = _sym_signals(structure, n_samples)
    y = ca.MX.sym("y", n_samples, structure.n_modes)
    W = structure.weights(theta)
    yhat = _input_part(structure, W, u, v, n_samples)
    if structure.orders.na:
        yhat = yhat - _ar_part(structure, W, y, n_samples)
    args = [theta, y] + [s for s in (u, v) if s is not None]
    names = ["theta", "y"] + [n for n, s in (("u", u), ("v", v)) if s is not None]
    return ca.Function("hwl_predict", args, [yhat], names, ["yhat"])


def hwl_simulate_function(structure: HWLStructure, n_samples: int) -> ca.Function:
    """CasADi twin of :meth:`HWLModel.simulate`, built with ``mapaccum``.

    ``f(theta, y0, [u], [v]) -> ysim`` with ``y0`` the first ``max_lag`` outputs
    (``max_lag x N``) and ``ysim`` of shape ``(K - max_lag, N)``.
    """
    o = structure.orders
    N, L = structure.n_modes, structure.max_lag
    theta, u, v = _sym_signals(structure, n_samples)
    y0 = ca.MX.sym("y0", L, N)
    W = structure.weights(theta)
    xin = _input_part(structure, W, u, v, n_samples)  # (K-L, N)
    n_steps = n_samples - L
    lags = o.ar_lags()
    if lags:
        H = max(lags)  # history length carried by the recursion
        step = recursion_step(structure)
        acc = step.mapaccum("hwl_recursion", n_steps)
        # initial history from y0: rows L-1, L-2, ..., L-H
        rows = [y0[L - 1 - d, :].T for d in range(H)]
        hist0 = ca.vertcat(*rows)
        traj = acc(hist0, xin.T, ca.repmat(ar_weights(structure, W), 1, n_steps))  # (H*N, n_steps)
        ysim = traj[:N, :].T
    else:
        ysim = xin
    args = [theta, y0] + [s for s in (u, v) if s is not None]
    names = ["theta", "y0"] + [n for n, s in (("u", u), ("v", v)) if s is not None]
    return ca.Function("hwl_simulate", args, [ysim], names, ["ysim"])
