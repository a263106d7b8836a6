"""Hopf and Neimark--Sacker points and their first Lyapunov coefficients.

For a flow ``x' = f(x, V)`` with ``f(0, V) = 0`` (the undeflected equilibrium), write
``f(x, V_H) = A x + B(x, x)/2 + C(x, x, x)/6 + ...`` with the symmetric multilinear forms
``B`` and ``C`` (second and third derivatives at zero, taken by CasADi's forward
differentiation).  At a Hopf point ``A q = i omega q``, ``A^T p = -i omega p``,
``<q, q> = <p, q> = 1`` (``<a, b> = conj(a)^T b``), and the first Lyapunov coefficient is
(Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed., eq. 3.20)

    l1 = Re( <p, C(q, q, conj q)> - 2 <p, B(q, A^{-1} B(q, conj q))>
             + <p, B(conj q, (2 i omega I - A)^{-1} B(q, q))> ) / (2 omega).

``l1 < 0``: supercritical (a stable LCO grows on the unstable side of the equilibrium),
``l1 > 0``: subcritical.  On the centre manifold ``x ~ 2 Re(z q)`` with
``r' = mu r + omega l1 r^3`` (``mu = Re lambda``), so the cycle of radius ``r`` sits at
``V - V_H = -omega l1 r^2 / (d mu / dV)`` and its component ``i`` has amplitude
``2 r |q_i|``: the check against the computed branch.

For a map ``x -> F(x, V)`` with a pair ``e^{+-i theta}`` on the unit circle (Neimark--Sacker,
Kuznetsov §4.7 and §5.4), ``A q = e^{i theta} q``, ``A^T p = e^{-i theta} p``, and

    d = Re( e^{-i theta} [ <p, C(q, q, conj q)> + 2 <p, B(q, (I - A)^{-1} B(q, conj q))>
                           + <p, B(conj q, (e^{2 i theta} I - A)^{-1} B(q, q))> ] ) / 2,

with the radial normal form ``r -> r (1 + beta + d r^2)`` (``beta = |mu| - 1``): ``d < 0`` is
supercritical and the invariant circle of radius ``r`` sits at
``V - V_NS = -d r^2 / (d |mu| / dV)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import casadi as ca
import numpy as np
from scipy.optimize import brentq

from .._format import result_repr
from ..errors import ConfigError

__all__ = ["MultilinearForms", "CriticalPair", "find_hopf", "find_neimark_sacker",
           "lyapunov_flow", "lyapunov_map"]


class MultilinearForms:
    """``A(V)``, ``B`` and ``C`` of ``f(., V)`` at the origin, by CasADi differentiation."""

    def __init__(self, f: ca.Function):
        n = int(f.size1_in(0))
        x = ca.SX.sym("x", n)
        V = ca.SX.sym("V")
        a, b, c = (ca.SX.sym(s, n) for s in "abc")
        fx = f(x, V)
        Jf = ca.jacobian(fx, x)
        Ja = ca.jtimes(fx, x, a)
        Bab = ca.jtimes(Ja, x, b)
        Cabc = ca.jtimes(Bab, x, c)
        z = ca.DM.zeros(n)
        self.n = n
        self._A = ca.Function("A", [x, V], [Jf])
        self._dA = ca.Function("dA", [x, V], [ca.jacobian(ca.vec(Jf), V)])
        self._B = ca.Function("B", [x, V, a, b], [Bab])
        self._C = ca.Function("C", [x, V, a, b, c], [Cabc])
        self._zero = z

    def A(self, V: float) -> np.ndarray:
        """Jacobian at the origin."""
        return np.asarray(self._A(self._zero, V))

    def dA(self, V: float) -> np.ndarray:
        """``dA/dV`` at the origin."""
        return np.asarray(self._dA(self._zero, V)).reshape(self.n, self.n, order="F")

    def _complex(self, fun, V, args):
        out = np.zeros(self.n, complex)
        for choice in product((0, 1), repeat=len(args)):
            parts = [np.real(a) if c == 0 else np.imag(a) for a, c in zip(args, choice)]
            val = np.asarray(fun(self._zero, V, *parts)).ravel()
            out = out + (1j ** sum(choice)) * val
        return out

    def B(self, V: float, u, v) -> np.ndarray:
        """``B(u, v)`` for complex vectors (bilinear extension)."""
        return self._complex(self._B, V, (u, v))

    def C(self, V: float, u, v, w) -> np.ndarray:
        """``C(u, v, w)`` for complex vectors (trilinear extension)."""
        return self._complex(self._C, V, (u, v, w))


@dataclass(frozen=True)
class CriticalPair:
    """The critical eigenvalue pair at a Hopf / Neimark--Sacker point.

    ``V``; ``eigenvalue`` (``i omega`` or ``e^{i theta}``); ``q``, ``p`` normalised
    eigenvectors (``<q, q> = <p, q> = 1``); ``crossing_rate`` (``d Re lambda/dV`` or
    ``d|mu|/dV``); ``A`` the Jacobian there.
    """

    __repr__ = result_repr

    V: float
    eigenvalue: complex
    q: np.ndarray
    p: np.ndarray
    crossing_rate: float
    A: np.ndarray


def _critical_vectors(A: np.ndarray, target: complex):
    lam, R = np.linalg.eig(A)
    k = int(np.argmin(np.abs(lam - target)))
    q = R[:, k] / np.linalg.norm(R[:, k])
    lamL, L = np.linalg.eig(A.T)
    j = int(np.argmin(np.abs(lamL - np.conj(lam[k]))))
    p = L[:, j]
    p = p / np.conj(np.vdot(p, q))          # <p, q> = conj(p)^T q = 1
    return lam[k], q, p


def _scan(measure, vrange, n_grid, what, speed_scale=1.0, speed_unit="", *, real=None,
          real_what=""):
    """The first speed of ``vrange`` where ``measure`` (of the oscillatory eigenvalues)
    crosses zero; ``real`` (of the real eigenvalues) names a static loss of stability when
    there is no such crossing, so that a diverging equilibrium is never called stable."""
    lo, hi = map(float, vrange)
    grid = np.linspace(lo, hi, n_grid)
    vals = np.array([measure(v) for v in grid])
    u = f" {speed_unit}" if speed_unit else ""
    if real is not None and not np.any(vals >= 0):
        static = np.array([real(v) for v in grid])
        for k in range(1, n_grid):
            if static[k - 1] < 0 <= static[k]:
                Vd = brentq(real, grid[k - 1], grid[k], xtol=1e-13 * max(1.0, hi), rtol=1e-14)
                raise ConfigError(
                    f"no flutter (Hopf) point in the speed range [{lo * speed_scale:g}, "
                    f"{hi * speed_scale:g}]{u}, but the equilibrium diverges statically at "
                    f"V = {Vd * speed_scale:.6g}{u} ({real_what}): no limit cycle starts "
                    "there; the oscillatory eigenvalues stay stable ("
                    f"{what} {vals.max():.3g} at most)")
    if vals[0] >= 0:
        raise ConfigError(f"the equilibrium is already unstable at the start of the speed range "
                          f"{lo * speed_scale:g}{u} ({what} {vals[0]:.3g} >= 0): lower the "
                          "range's start (--vrange)")
    for k in range(1, n_grid):
        if vals[k - 1] < 0 <= vals[k]:
            return brentq(measure, grid[k - 1], grid[k], xtol=1e-13 * max(1.0, hi), rtol=1e-14)
    raise ConfigError(f"no flutter (Hopf) point in the speed range [{lo * speed_scale:g}, "
                      f"{hi * speed_scale:g}]{u}: the equilibrium stays stable ({what} "
                      f"{vals.max():.3g} at most); widen the range (--vrange)")


def find_hopf(forms: MultilinearForms, vrange, n_grid: int = 121, *, speed_scale: float = 1.0,
              speed_unit: str = "") -> CriticalPair:
    """First Hopf point of the flow in ``vrange``: the abscissa of the oscillatory
    eigenvalues crossing zero (a real eigenvalue through zero is not a Hopf point).

    Raises
    ------
    ConfigError
        Unstable at the range start, or no oscillatory eigenvalue crosses the imaginary
        axis in the range.
    """
    def split(V):
        lam = np.linalg.eigvals(forms.A(V))
        osc = np.abs(lam.imag) > 1e-9 * max(1.0, np.max(np.abs(lam)))
        return lam[osc], lam[~osc].real

    def abscissa(V):
        osc = split(V)[0]
        return float(np.max(osc.real)) if osc.size else -np.inf

    def real_abscissa(V):
        real = split(V)[1]
        return float(np.max(real)) if real.size else -np.inf

    Vh = _scan(abscissa, vrange, n_grid, "spectral abscissa of the oscillatory eigenvalues",
               speed_scale, speed_unit, real=real_abscissa,
               real_what="a real eigenvalue crosses zero")
    A = forms.A(Vh)
    lam = np.linalg.eigvals(A)
    osc = lam[np.abs(lam.imag) > 0]
    target = osc[np.argmax(osc.real)]
    target = complex(target.real, abs(target.imag))
    ev, q, p = _critical_vectors(A, target)
    rate = float(np.real(np.vdot(p, forms.dA(Vh) @ q)))
    return CriticalPair(float(Vh), complex(ev), q, p, rate, A)


def find_neimark_sacker(forms: MultilinearForms, vrange, n_grid: int = 121, *,
                        speed_scale: float = 1.0, speed_unit: str = "") -> CriticalPair:
    """First Neimark--Sacker point of the map in ``vrange``: the spectral radius of the
    complex eigenvalues crossing one.

    Raises
    ------
    ConfigError
        Unstable at the range start, or no complex eigenvalue leaves the unit circle in the
        range.
    """
    def split(V):
        lam = np.linalg.eigvals(forms.A(V))
        osc = np.abs(lam.imag) > 1e-9
        return lam[osc], lam[~osc].real

    def radius(V):
        osc = split(V)[0]
        return float(np.max(np.abs(osc))) - 1.0 if osc.size else -np.inf

    def real_radius(V):
        real = split(V)[1]
        return float(np.max(np.abs(real))) - 1.0 if real.size else -np.inf

    Vns = _scan(radius, vrange, n_grid, "spectral radius - 1 of the complex eigenvalues",
                speed_scale, speed_unit, real=real_radius,
                real_what="a real eigenvalue of the map leaves the unit circle")
    A = forms.A(Vns)
    lam = np.linalg.eigvals(A)
    osc = lam[np.abs(lam.imag) > 1e-9]
    target = osc[np.argmax(np.abs(osc))]
    target = complex(target.real, abs(target.imag))
    ev, q, p = _critical_vectors(A, target)
    dmu = np.vdot(p, forms.dA(Vns) @ q)                 # d mu / dV
    rate = float(np.real(np.conj(ev) * dmu) / abs(ev))   # d|mu|/dV
    return CriticalPair(float(Vns), complex(ev), q, p, rate, A)


def lyapunov_flow(forms: MultilinearForms, cp: CriticalPair) -> float:
    """First Lyapunov coefficient ``l1`` of a Hopf point (module docstring)."""
    V, A, q, p = cp.V, cp.A, cp.q, cp.p
    w = cp.eigenvalue.imag
    n = A.shape[0]
    qb = np.conj(q)
    h11 = np.linalg.solve(A, forms.B(V, q, qb))
    h20 = np.linalg.solve(2j * w * np.eye(n) - A, forms.B(V, q, q))
    val = (np.vdot(p, forms.C(V, q, q, qb)) - 2.0 * np.vdot(p, forms.B(V, q, h11))
           + np.vdot(p, forms.B(V, qb, h20)))
    return float(np.real(val) / (2.0 * w))


def lyapunov_map(forms: MultilinearForms, cp: CriticalPair) -> float:
    """Critical coefficient ``d`` of a Neimark--Sacker point (module docstring)."""
    V, A, q, p = cp.V, cp.A, cp.q, cp.p
    mu = cp.eigenvalue / abs(cp.eigenvalue)
    n = A.shape[0]
    qb = np.conj(q)
    h11 = np.linalg.solve(np.eye(n) - A, forms.B(V, q, qb))
    h20 = np.linalg.solve(mu * mu * np.eye(n) - A, forms.B(V, q, q))
    val = (np.vdot(p, forms.C(V, q, q, qb)) + 2.0 * np.vdot(p, forms.B(V, q, h11))
           + np.vdot(p, forms.B(V, qb, h20)))
    return float(0.5 * np.real(np.conj(mu) * val))
