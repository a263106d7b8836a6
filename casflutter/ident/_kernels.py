"""Compiled inner loops of the free-run recursion (eq. 3) and of its forward sensitivities.

The free run of eq. 3 is a recursion in time: ``y(k)`` needs the model's own outputs at the
autoregressive lags ``mu, ..., mu + na - 1``.  Written with the autoregressive weights
``W[m, l-1] = A^(m) ∘ alpha^[l]`` (Hadamard product, eq. 2) and the input part ``x(k)`` of
eq. 3 (every term that does not involve y)::

    y(k) = x(k) - sum_m sum_l W[m, l-1] @ y(k - lag_m)^l

Differentiating with respect to any parameter ``theta_p`` gives the *same* recursion for the
sensitivity ``S(k) = dy(k)/dtheta`` (linear and time-varying)::

    S(k) = D(k) - sum_m J_m(k) @ S(k - lag_m),   J_m(k)[i, j] = sum_l l W[m, l-1][i, j] y_j(k - lag_m)^(l-1)

where ``D(k)`` is the direct derivative of eq. 3 with the past outputs held fixed.  Both loops
are compiled with numba (cached on disk); each step costs ``O(na N^2)`` for the outputs and
``O(na N^2 n_p)`` for the sensitivities, so a record of K samples costs ``O(K)`` time and memory.

*Segments.*  With ``seg > 0`` the record is cut into segments of ``seg`` samples and every
segment after the first starts from the *measured* past outputs (a ``seg``-step-ahead
simulation error); the measured values carry no sensitivity.  This is the horizon continuation
that keeps an unstable starting model from blowing up (see :mod:`._simfit`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["free_run", "sensitivities", "duffing_rk4"]


@njit(cache=True)
def free_run(xin, W, lags, ic, ymeas, seg, bound):  # pragma: no cover - compiled
    """Free run of eq. 3 over one record.

    Parameters
    ----------
    xin : (M, N) input part of eq. 3 at the simulated samples (constant term included).
    W : (na, q, N, N) autoregressive weights ``A^(m) ∘ alpha^[l]``.
    lags : (na,) int64, the autoregressive lags (all >= 1).
    ic : (H, N) initial outputs ``y(L-H), ..., y(L-1)`` (chronological), ``H = max(lags)``.
    ymeas : (H + M, N) measured outputs on the same time axis (used only when ``seg > 0``).
    seg : int, segment length (0: one free run over the whole record).
    bound : float, ``|y|`` above which the run is declared divergent and stopped.

    Returns
    -------
    ybuf : (H + M, N) with ``ybuf[:H] = ic`` and the simulated outputs after it.
    yused : (M, na, N) the past output used at each lag (simulated, initial or measured).
    diverged : int, first simulated sample that was non-finite or above ``bound`` (-1: none);
        the remaining rows are NaN.
    """
    M, N = xin.shape
    na, q = W.shape[0], W.shape[1]
    H = ic.shape[0]
    ybuf = np.empty((H + M, N))
    ybuf[:H] = ic
    yused = np.zeros((M, na, N))
    diverged = -1
    for t in range(M):
        s0 = (t // seg) * seg if seg > 0 else 0
        for i in range(N):
            ybuf[H + t, i] = xin[t, i]
        for m in range(na):
            tt = t - lags[m]
            if seg > 0 and tt >= 0 and tt < s0:
                for j in range(N):
                    yused[t, m, j] = ymeas[H + tt, j]
            else:
                for j in range(N):
                    yused[t, m, j] = ybuf[H + tt, j]
            for j in range(N):
                yv = yused[t, m, j]
                pw = yv
                for l in range(q):
                    for i in range(N):
                        ybuf[H + t, i] -= W[m, l, i, j] * pw
                    pw *= yv
        bad = False
        for i in range(N):
            val = ybuf[H + t, i]
            if not (abs(val) < bound):
                bad = True
        if bad:
            diverged = t
            for tt in range(t, M):
                for i in range(N):
                    ybuf[H + tt, i] = np.nan
            break
    return ybuf, yused, diverged


@njit(cache=True)
def sensitivities(D, W, lags, yused, seg, H):  # pragma: no cover - compiled
    """Forward sensitivities of the free run (module docstring).

    Parameters
    ----------
    D : (M, N, P) direct derivatives of eq. 3 with respect to the P model parameters.
    W, lags, seg : as in :func:`free_run`.
    yused : (M, na, N) from :func:`free_run`.
    H : int, number of initial output samples (their ``H * N`` values are extra parameters,
        ordered sample-major after the P model parameters).

    Returns
    -------
    S : (M, N, P + H N) with ``S[t, i, p] = d y_i(L + t) / d param_p``.
    """
    M, N, P = D.shape
    na, q = W.shape[0], W.shape[1]
    n = P + H * N
    S = np.zeros((H + M, N, n))
    for b in range(H):
        for j in range(N):
            S[b, j, P + b * N + j] = 1.0
    for t in range(M):
        s0 = (t // seg) * seg if seg > 0 else 0
        for i in range(N):
            for p in range(P):
                S[H + t, i, p] = D[t, i, p]
        for m in range(na):
            tt = t - lags[m]
            if seg > 0 and tt >= 0 and tt < s0:
                continue  # measured past output: no sensitivity
            for j in range(N):
                yv = yused[t, m, j]
                for i in range(N):
                    c = 0.0
                    pw = 1.0
                    for l in range(q):
                        c += (l + 1) * W[m, l, i, j] * pw
                        pw *= yv
                    if c != 0.0:
                        for p in range(n):
                            S[H + t, i, p] -= c * S[H + tt, j, p]
    return S[H:]


@njit(cache=True)
def duffing_rk4(u, dt, omega, zeta, k3, substeps):  # pragma: no cover - compiled
    """Duffing oscillator ``y'' + 2 zeta omega y' + omega^2 y + k3 y^3 = u(t)`` integrated by
    classical Runge--Kutta with ``substeps`` steps per sample and the input held between
    samples (zero-order hold).  Returns ``y`` at the sample instants."""
    K = u.shape[0]
    y = np.zeros(K)
    x0, x1 = 0.0, 0.0
    h = dt / substeps
    for k in range(K):
        y[k] = x0
        f = u[k]
        for _ in range(substeps):
            a0, a1 = x1, f - 2 * zeta * omega * x1 - omega ** 2 * x0 - k3 * x0 ** 3
            b0x, b1x = x0 + 0.5 * h * a0, x1 + 0.5 * h * a1
            b0, b1 = b1x, f - 2 * zeta * omega * b1x - omega ** 2 * b0x - k3 * b0x ** 3
            c0x, c1x = x0 + 0.5 * h * b0, x1 + 0.5 * h * b1
            c0, c1 = c1x, f - 2 * zeta * omega * c1x - omega ** 2 * c0x - k3 * c0x ** 3
            d0x, d1x = x0 + h * c0, x1 + h * c1
            d0, d1 = d1x, f - 2 * zeta * omega * d1x - omega ** 2 * d0x - k3 * d0x ** 3
            x0 += h / 6 * (a0 + 2 * b0 + 2 * c0 + d0)
            x1 += h / 6 * (a1 + 2 * b1 + 2 * c1 + d1)
    return y
