"""Helpers for the verification tests (imported by the test modules): seeded random
systems, an independent dense frequency sweep (python-control's own frequency evaluation
with scipy local refinement) and a toy wing LFT written from eq. (8)-(14)."""

from __future__ import annotations

import control
import numpy as np
from scipy.optimize import minimize_scalar


def random_stable_ss(rng: np.random.Generator, n: int, m: int, p: int, *,
                     with_d: bool = True, min_damping: float = 0.05) -> control.StateSpace:
    """Random stable system in real modal form with damping ratios >= min_damping."""
    blocks = []
    k = 0
    while k < n:
        if n - k >= 2 and rng.random() < 0.7:
            wn = 10 ** rng.uniform(-1, 1.5)
            z = rng.uniform(min_damping, 0.9)
            blocks.append(np.array([[-z * wn, wn * np.sqrt(1 - z**2)],
                                    [-wn * np.sqrt(1 - z**2), -z * wn]]))
            k += 2
        else:
            blocks.append(np.array([[-(10 ** rng.uniform(-1, 1.5))]]))
            k += 1
    Am = np.zeros((n, n))
    i = 0
    for b in blocks:
        Am[i:i + b.shape[0], i:i + b.shape[0]] = b
        i += b.shape[0]
    T = rng.standard_normal((n, n)) + 3 * np.eye(n)   # similarity keeps the spectrum
    A = T @ Am @ np.linalg.inv(T)
    B = rng.standard_normal((n, m))
    C = rng.standard_normal((p, n))
    D = rng.standard_normal((p, m)) if with_d else np.zeros((p, m))
    return control.ss(A, B, C, D)


def sigma_max_control(sys: control.StateSpace, omega: np.ndarray) -> np.ndarray:
    """σ_max(G(jω)) from python-control's own evaluation of the transfer function."""
    G = sys(1j * np.atleast_1d(omega), squeeze=False)       # (p, m, nw)
    return np.array([np.linalg.svd(G[:, :, k], compute_uv=False)[0]
                     for k in range(G.shape[2])])


def dense_peak(sys: control.StateSpace, npts: int = 4000) -> tuple[float, float]:
    """Peak of σ_max over a dense log grid (plus pole frequencies), refined locally
    around the best grid points with bounded scalar optimisation."""
    poles = np.linalg.eigvals(sys.A)
    wmax = max(1.0, float(np.max(np.abs(poles))))
    wmin = min(1.0, float(np.min(np.abs(poles))))
    grid = np.unique(np.concatenate([np.logspace(np.log10(wmin) - 3, np.log10(wmax) + 3, npts),
                                     np.abs(poles.imag), np.abs(poles)]))
    sig = sigma_max_control(sys, grid)
    best_g, best_w = float(sig.max()), float(grid[np.argmax(sig)])
    dinf = np.linalg.svd(np.atleast_2d(sys.D), compute_uv=False)[0]
    if dinf > best_g:
        best_g, best_w = float(dinf), np.inf
    s0 = float(sigma_max_control(sys, np.array([0.0]))[0])
    if s0 > best_g:
        best_g, best_w = s0, 0.0
    for k in np.argsort(sig)[::-1][:6]:
        lo = grid[max(k - 1, 0)]
        hi = grid[min(k + 1, grid.size - 1)]
        r = minimize_scalar(lambda w: -sigma_max_control(sys, np.array([w]))[0],
                            bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-12 * hi, "maxiter": 500})
        if -r.fun > best_g:
            best_g, best_w = float(-r.fun), float(r.x)
    return best_g, best_w


# --- a two-mode wing with quasi-steady aerodynamics, written from eq. (8)-(14) -----------
# ẍ = -K q - C q̇ + V² (Ka q + Ca q̇ + df v): bending-torsion coalescence flutter near V ≈ 1.

def wing(sensor: str = "state") -> dict:
    """Matrices of the toy wing; ``sensor`` "state" (zm = q, D21 = 0 as in eq. 14) or
    "accel" (zm = q̈, which gives D21 = [-I 0] and D22 = Vf² Nv)."""
    N = 2
    K, Cd = np.diag([1.0, 4.0]), np.diag([0.04, 0.08])
    As = np.block([[np.zeros((N, N)), np.eye(N)], [-K, -Cd]])
    Bs = np.vstack([np.zeros((N, N)), np.eye(N)])
    Nx = np.hstack([np.array([[0.0, 1.0], [-1.0, 1.0]]),
                    np.array([[-0.15, 0.05], [0.02, -0.05]])])
    Nv = np.array([[0.3], [-0.5]])
    if sensor == "state":
        Hx, Hf = np.hstack([np.eye(N), np.zeros((N, N))]), np.zeros((N, N))
    else:
        Hx, Hf = np.hstack([-K, -Cd]), np.eye(N)
    return dict(N=N, As=As, Bs=Bs, Nx=Nx, Nv=Nv, Hx=Hx, Hf=Hf)


def wing_plant_at(w: dict, V: float) -> control.StateSpace:
    """ΣAE at speed index V directly (no LFT): input v, outputs zm."""
    return control.ss(w["As"] + V**2 * w["Bs"] @ w["Nx"], V**2 * w["Bs"] @ w["Nv"],
                      w["Hx"] + V**2 * w["Hf"] @ w["Nx"], V**2 * w["Hf"] @ w["Nv"])


def wing_lft(w: dict, Vf: float) -> control.StateSpace:
    """The LFT of eq. (14): inputs [wf, w, v], outputs [zf, zm]; Mx = -Bs, Nx, Nv."""
    N, Bs, Nx, Nv, Hf = w["N"], w["Bs"], w["Nx"], w["Nv"], w["Hf"]
    A = w["As"] + Vf**2 * Bs @ Nx
    B = np.hstack([-Bs, Bs, Vf**2 * Bs @ Nv])
    C = np.vstack([Nx, w["Hx"] + Vf**2 * Hf @ Nx])
    D = np.block([[np.zeros((N, 2 * N)), Nv], [-Hf, np.zeros((N, N)), Vf**2 * Hf @ Nv]])
    return control.ss(A, B, C, D)


def lqg_controller(P: control.StateSpace, Dk: np.ndarray) -> control.StateSpace:
    """Observer-based controller u = -Kc x̂ + Dk y (positive-feedback convention u = K y)."""
    A, B, C, D = (np.asarray(M, float) for M in (P.A, P.B, P.C, P.D))
    n = A.shape[0]
    Kc, _, _ = control.lqr(A, B, np.eye(n), np.eye(B.shape[1]))
    L, _, _ = control.lqe(A, np.eye(n), C, np.eye(n), 0.1 * np.eye(C.shape[0]))
    Ak = A - L @ C - (B - L @ D) @ Kc
    Bk = L + (B - L @ D) @ Dk
    return control.ss(Ak, Bk, -Kc, Dk)
