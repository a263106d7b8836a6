"""Sensitivity of the optimal γ of fixed-order H∞ synthesis to plant parameters.

The synthesis (paper §III.C) solves the minimax NLP ``min_{K,t} t`` s.t.
``σ̄(T_zw(K, p, jω)) ≤ t`` at the frequencies of the closed-loop peaks.  At its solution
``K*`` the value function ``γ*(p)`` has the derivative of the Lagrangian (envelope theorem
of parametric NLP sensitivity)::

    dγ*/dp = Σ_i μ_i ∂φ_i/∂p,   φ_i(K, p) = Re(u_iᴴ T_zw(K, p, jω_i) v_i)

with ``(u_i, v_i)`` the top singular vectors at each active peak ``ω_i`` (where
``φ_i = σ̄`` and ``∂σ̄ = ∂φ_i`` for a simple singular value) and the multipliers ``μ_i ≥ 0``,
``Σ μ_i = 1`` of the stationarity condition ``Σ μ_i ∇_K φ_i = 0``.  The closed loop, its
frequency response in real arithmetic and all derivatives with respect to the controller
and the plant matrices are CasADi expressions (algorithmic differentiation); only
``∂(plant matrices)/∂p`` is a central difference of the user's plant function.
:func:`casflutter.design.synthesize` does not expose its NLP, so the multipliers are
recovered from the stationarity condition at the returned controller; the residual of that
condition (``kkt_residual``) says how close the controller is to a stationary point.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import casadi as ca
import numpy as np
from scipy.optimize import minimize_scalar, nnls

from .._format import result_repr
from ..design import partition
from ..errors import ConfigError, DimensionError

__all__ = ["GammaSensitivity", "gamma_sensitivity"]


@dataclass(frozen=True)
class GammaSensitivity:
    """Outcome of :func:`gamma_sensitivity`.

    Attributes
    ----------
    gamma : float
        Worst-case γ of the closed loop(s) at the nominal parameters (frequency sweep and
        refinement of the peaks; compare ``synthesis_gamma``).
    synthesis_gamma : float
        The verified γ reported by the synthesis.
    peaks : tuple of (int, float, float)
        Active peaks ``(plant index, ω_i, σ̄_i)`` within ``peak_rtol`` of ``gamma``.
    multipliers : tuple of float
        ``μ_i`` of the active peaks.
    kkt_residual : float
        ``‖Σ μ_i ∇_K φ_i‖ · max(‖K‖, 1) / γ``: relative change of γ per relative change of
        the controller (0 at an exact stationary point; the derivatives are first-order
        accurate in it).
    dgamma_dp : dict
        ``name -> dγ*/dp``.
    normalized : dict
        ``name -> (p/γ) dγ*/dp`` (``dγ*/dp / γ`` when ``p == 0``).
    params : dict
        Nominal parameter values.
    method : str
        Description of the method.
    """

    __repr__ = result_repr

    gamma: float
    synthesis_gamma: float
    peaks: tuple
    multipliers: tuple
    kkt_residual: float
    dgamma_dp: Mapping[str, float]
    normalized: Mapping[str, float]
    params: Mapping[str, float]
    method: str = "envelope theorem of the minimax NLP (CasADi AD)"

    def ranked(self) -> list[tuple[str, float, float]]:
        """``(name, dγ/dp, normalised)`` by decreasing ``|normalised|``."""
        return sorted(((n, self.dgamma_dp[n], self.normalized[n]) for n in self.dgamma_dp),
                      key=lambda r: -abs(r[2]))


def _blocks(P, nmeas: int, ncon: int, order: int) -> list[np.ndarray]:
    a = partition(P, nmeas, ncon).augmented(order)
    return [np.atleast_2d(np.asarray(M, float)) for M in
            (a.A, a.B1, a.B2, a.C1, a.C2, a.D11, a.D12, a.D21)]


def _phi_function(shapes, kshape) -> ca.Function:
    """``φ(Kbar, blocks..., ω, ur, ui, vr, vi) = Re(uᴴ T(jω) v)`` in real arithmetic."""
    syms = [ca.SX.sym(n, *s) for n, s in zip(("A", "B1", "B2", "C1", "C2", "D11", "D12", "D21"),
                                             shapes)]
    A, B1, B2, C1, C2, D11, D12, D21 = syms
    K = ca.SX.sym("K", *kshape)
    om = ca.SX.sym("omega")
    nz, nw = shapes[5]
    ur, ui = ca.SX.sym("ur", nz), ca.SX.sym("ui", nz)
    vr, vi = ca.SX.sym("vr", nw), ca.SX.sym("vi", nw)
    Acl = A + B2 @ K @ C2
    Bcl = B1 + B2 @ K @ D21
    Ccl = C1 + D12 @ K @ C2
    Dcl = D11 + D12 @ K @ D21
    n = shapes[0][0]
    I = ca.SX.eye(n)
    M = ca.blockcat([[-Acl, -om * I], [om * I, -Acl]])
    X = ca.solve(M, ca.vertcat(Bcl, ca.SX.zeros(n, nw)))
    Tr, Ti = Ccl @ X[:n, :] + Dcl, Ccl @ X[n:, :]
    phi = ca.dot(ur, Tr @ vr - Ti @ vi) + ca.dot(ui, Ti @ vr + Tr @ vi)
    return ca.Function("phi", [K, *syms, om, ur, ui, vr, vi],
                       [phi, ca.gradient(phi, K), *[ca.gradient(phi, s) for s in syms]])


def _freqresp(blocks, K, om):
    A, B1, B2, C1, C2, D11, D12, D21 = blocks
    Acl, Bcl = A + B2 @ K @ C2, B1 + B2 @ K @ D21
    Ccl, Dcl = C1 + D12 @ K @ C2, D11 + D12 @ K @ D21
    return Ccl @ np.linalg.solve(1j * om * np.eye(Acl.shape[0]) - Acl, Bcl) + Dcl


def _peaks(blocks, K, extra=(), n_grid: int = 400):
    """Local maxima of σ̄(T(jω)): a log grid with ω = 0, every lightly damped closed-loop
    pole frequency and the given ``extra`` frequencies as candidates, each refined by a
    bounded scalar search; duplicates merged."""
    A = blocks[0] + blocks[2] @ K @ blocks[4]
    lam = np.linalg.eigvals(A)
    if np.max(lam.real) >= 0:
        raise ConfigError("the closed loop is unstable at the nominal parameters: no γ")
    scale = max(np.max(np.abs(lam)), 1e-3)
    w = np.concatenate([[0.0], np.geomspace(1e-4 * scale, 1e3 * scale, n_grid)])

    def sig(om):
        return float(np.linalg.svd(_freqresp(blocks, K, om), compute_uv=False)[0])

    def refine(lo, hi, om0):
        r = minimize_scalar(lambda x: -sig(x), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-13 * max(hi, 1.0)})
        return (float(r.x), sig(r.x)) if sig(r.x) >= sig(om0) else (float(om0), sig(om0))

    s = np.array([sig(om) for om in w])
    cands = [(0.0, s[0])] if s[0] >= s[1] else []
    for i in range(1, len(w) - 1):
        if s[i] >= s[i - 1] and s[i] >= s[i + 1]:
            cands.append(refine(w[i - 1], w[i + 1], w[i]))
    for lm in lam[lam.imag > 0]:
        om0, width = abs(lm.imag), 3 * abs(lm.real)
        cands.append(refine(max(om0 - width, 0.0), om0 + width, om0))
    for om0 in extra:
        if np.isfinite(om0) and om0 >= 0:
            cands.append(refine(max(om0 * (1 - 1e-3), 0.0), om0 * (1 + 1e-3) + 1e-12, om0))
    cands.sort()
    out = []
    for om, v in cands:
        if out and abs(om - out[-1][0]) <= 1e-6 * max(om, 1e-4 * scale):
            if v > out[-1][1]:
                out[-1] = (om, v)
            continue
        out.append((om, v))
    return out


def gamma_sensitivity(plant_fn: Callable[[Mapping[str, float]], Any], params: Mapping[str, float],
                      nmeas: int, ncon: int, controller, *, names: Sequence[str] | None = None,
                      synthesis_gamma: float | None = None, rel_step: float = 1e-6,
                      peak_rtol: float = 1e-3) -> GammaSensitivity:
    """dγ*/dp of fixed-order H∞ synthesis at its solution (module docstring).

    Parameters
    ----------
    plant_fn : callable
        ``params -> StateSpace`` (or a list of them: worst case over plants), the generalised
        plant(s) in ``hinfsyn`` form, e.g. the LFT of eq. (14) for given problem parameters.
    params : mapping
        Nominal parameter values.
    nmeas, ncon : int
        Measurements and controls.
    controller : control.StateSpace or SynthesisResult
        The optimal controller (``SynthesisResult.controller``; its ``gamma`` is used as
        ``synthesis_gamma``).
    names : sequence of str, optional
        Parameters to differentiate (default: all of ``params``).
    rel_step : float
        Relative step of the central differences of the plant matrices.
    peak_rtol : float
        Peaks within this relative distance of the largest are active.

    Returns
    -------
    GammaSensitivity
    """
    extra = ()
    if hasattr(controller, "controller"):
        synthesis_gamma = controller.gamma if synthesis_gamma is None else synthesis_gamma
        extra = tuple(controller.omega_peaks)
        controller = controller.controller
    params = {k: float(v) for k, v in params.items()}
    names = list(names) if names is not None else list(params)
    bad = [n for n in names if n not in params]
    if bad:
        raise ConfigError(f"parameter(s) {bad} are not in params ({', '.join(params)})")
    k = int(controller.nstates)
    Dk, Ck = np.atleast_2d(controller.D), np.asarray(controller.C).reshape(ncon, k)
    Bk, Ak = np.asarray(controller.B).reshape(k, nmeas), np.asarray(controller.A).reshape(k, k)
    Kbar = np.block([[Dk, Ck], [Bk, Ak]]) if k else Dk

    def plants(p):
        P = plant_fn(p)
        return list(P) if isinstance(P, (list, tuple)) else [P]

    nominal = [_blocks(P, nmeas, ncon, k) for P in plants(params)]
    if any(b[2].shape[1] != Kbar.shape[0] or b[4].shape[0] != Kbar.shape[1] for b in nominal):
        raise DimensionError("controller sizes do not fit the plant's nmeas/ncon")
    peaks = []
    for j, blocks in enumerate(nominal):
        peaks += [(j, om, s) for om, s in _peaks(blocks, Kbar, extra)]
    gamma = max(s for _, _, s in peaks)
    active = [pk for pk in peaks if pk[2] >= gamma * (1 - peak_rtol)]
    funcs = {j: _phi_function([b.shape for b in nominal[j]], Kbar.shape)
             for j in {pk[0] for pk in active}}
    evals = []
    for j, om, _ in active:
        U, _, Vh = np.linalg.svd(_freqresp(nominal[j], Kbar, om))
        u, v = U[:, 0], Vh[0].conj()
        out = funcs[j](Kbar, *nominal[j], om, u.real, u.imag, v.real, v.imag)
        evals.append((j, [np.asarray(o, float) for o in out]))
    G = np.column_stack([e[1][1].ravel() for e in evals])
    if G.shape[1] == 1:
        mu = np.ones(1)
    else:
        wgt = 1e3 * max(np.linalg.norm(G), 1.0)
        mu, _ = nnls(np.vstack([G, wgt * np.ones((1, G.shape[1]))]),
                     np.concatenate([np.zeros(G.shape[0]), [wgt]]))
        mu = mu / mu.sum()
    kkt = float(np.linalg.norm(G @ mu) * max(np.linalg.norm(Kbar), 1.0) / gamma)
    dgamma, normalized = {}, {}
    for name in names:
        p0 = params[name]
        h = rel_step * max(abs(p0), 1.0)
        plus = [_blocks(P, nmeas, ncon, k) for P in plants({**params, name: p0 + h})]
        minus = [_blocks(P, nmeas, ncon, k) for P in plants({**params, name: p0 - h})]
        d = 0.0
        for m, (j, out) in zip(mu, evals):
            grads = out[2:]
            d += m * sum(float(np.sum(g * (bp - bm) / (2 * h)))
                         for g, bp, bm in zip(grads, plus[j], minus[j]))
        dgamma[name] = d
        normalized[name] = p0 / gamma * d if p0 != 0 else d / gamma
    return GammaSensitivity(gamma=float(gamma),
                            synthesis_gamma=float(np.nan if synthesis_gamma is None
                                                  else synthesis_gamma),
                            peaks=tuple((j, float(om), float(s)) for j, om, s in active),
                            multipliers=tuple(float(m) for m in mu), kkt_residual=kkt,
                            dgamma_dp=dgamma, normalized=normalized, params=dict(params))
