"""LCO branches of the sampled-data ROM loop: invariant circles of a discrete map.

The nonlinear loop of :func:`casflutter.aeroelastic.simulate_loop` -- the HWL ROM of
eq. (3) (one sample per step ``h``) in feedback with Σs of eq. (7), coupled by a zero-order
hold and propagated exactly -- is the map ``s_{k+1} = F(s_k, V)`` of the state

    s_k = [x_s(t_k), u_{k-1}, ..., u_{k-L}, y_{k-1}, ..., y_{k-Ly}]

(``L`` the ROM's largest lag, ``Ly = max(L, 1)``, or ``max(L, 2)`` with the first-order hold;
flap at rest):

    u_k = Cs x_s(t_k),   y_k = HWL(y_{k-L..k-1}, u_{k-L..k}),
    x_s(t_{k+1}) = Ad x_s(t_k) + B0 V^2 y_k [+ B1 V^2 (y_k - y_{k-1})],

the force held over the step ``h`` by a zero-order hold or, with the bracket, a predictive
first-order hold (:func:`casflutter.aeroelastic.simulate_loop` explains both;
``Ad, B0, B1`` from :func:`casflutter.aeroelastic.structure_step`).

The step is the ROM's sample time ``h = dt`` at every speed (eq. 8 as the paper writes it),
or, with ``convective_V0 = V0``, ``h = dt V0 / V``: the aerodynamic recursion advances one
sample per the same reduced time at every speed, so its time scale follows the reduced
frequency (:func:`casflutter.aeroelastic.loop_sample_time`); ``Ad, Bd`` then depend on V
(:func:`casflutter.aeroelastic.structure_step`, in closed form, so ``F`` is differentiable
in V).

Its flutter is a Neimark--Sacker bifurcation of the fixed point ``s = 0`` and its LCO is an
invariant circle, not a periodic orbit: the LCO period is not a whole number of samples.
The circle is solved as a closed curve ``s(theta)``, a truncated Fourier series with
``harmonics`` harmonics, with

    F(s(theta_j), V) = s(theta_j + 2 pi rho),   theta_j = 2 pi j / (2 harmonics + 1),

the rotation number ``rho`` (samples per LCO period ``1 / rho``) unknown, closed by the
integral phase condition against the previous circle and the continuation's linear
condition.  The LCO frequency is ``rho / h``.

Stability: a perturbation of the circle is carried by the linearised cocycle
``DF(s(theta))`` over the rotation ``theta -> theta + 2 pi rho``; its exponents (the radii of
the circles that form the spectrum of the transfer operator) are measured from the
product of ``DF`` along ``q`` iterates, ``p / q`` a continued-fraction convergent of ``rho``
with ``q rho >= 1`` turns and the smallest closing error ``|q rho - p|`` available.  One of
the product's eigenvalues belongs to the tangent direction ``s'(theta)`` (modulus 1 up to the
closing error); the largest of the others, taken to the power ``1 / (q rho)``, is the
circle's normal multiplier over one LCO period (below 1: stable).
"""

from __future__ import annotations

import math
import time

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.optimize import brentq

from .._nlp import RootResult, solve_newton
from ..aeroelastic import check_convective_V0, check_hold, loop_sample_time, structure_step
from ..errors import ConfigError, ConvergenceError, DimensionError
from ..ident import HWLModel, hwl_predict_function
from ..structure import ModalStructure
from ._branch import BranchStart, run_from_hopf
from ._normal_form import MultilinearForms, find_neimark_sacker, lyapunov_map
from ._results import LCOBranch, LCOPoint, LCOSettings

__all__ = ["rom_loop_map", "rom_loop_flutter", "InvariantCircle", "rom_lco_branch"]

def _history(rom: HWLModel, hold: str) -> tuple[int, int]:
    """``(L, Ly)``: the input and output history lengths of the map's state."""
    L = int(rom.max_lag)
    return L, max(L, 2 if hold == "foh" else 1)


def rom_loop_map(rom: HWLModel, structure: ModalStructure, *,
                 convective_V0: float | None = None, hold: str = "zoh") -> ca.Function:
    """The sampled-data ROM loop as a CasADi map ``F(s, V) -> s_next`` (module docstring).

    Parameters
    ----------
    rom : HWLModel
        Discrete HWL ROM (eq. 3); its flap input, if any, is held at zero.
    structure : ModalStructure
        Σs (eq. 7) with as many modes as the ROM.
    convective_V0 : float, optional
        The ROM's identification speed index: the loop is stepped at ``rom.dt · V0 / V``
        (module docstring); default ``rom.dt`` at every speed (eq. 8).
    hold : {"zoh", "foh"}
        The force's hold between samples (module docstring).

    Returns
    -------
    casadi.Function
        ``F(s, V)`` with ``s`` of length ``2N + (L + Ly) N``.
    """
    N, dt = rom.n_modes, float(rom.dt)
    if structure.n_modes != N:
        raise DimensionError(f"the ROM has {N} modes but Σs has {structure.n_modes}")
    check_convective_V0(convective_V0)
    check_hold(hold)
    L, Ly = _history(rom, hold)
    nx = 2 * N
    pred = hwl_predict_function(rom.structure, L + 1)
    s = ca.SX.sym("s", nx + (L + Ly) * N)
    V = ca.SX.sym("V")
    Ad, B0, B1 = structure_step(structure)(loop_sample_time(dt, V, convective_V0))
    xs = s[:nx]
    uh = [s[nx + d * N:nx + (d + 1) * N] for d in range(L)]           # u_{k-1-d}
    yh = [s[nx + L * N + d * N:nx + L * N + (d + 1) * N] for d in range(Ly)]
    uk = ca.mtimes(ca.DM(structure.Cs), xs)
    U = ca.vertcat(*[uh[d].T for d in reversed(range(L))], uk.T)      # rows k-L .. k
    Y = ca.vertcat(*[yh[d].T for d in reversed(range(L))], ca.DM.zeros(1, N))
    args = [ca.DM(rom.theta), Y]
    if rom.has_u:
        args.append(U)
    if rom.has_v:
        args.append(ca.DM.zeros(L + 1, 1))
    yk = pred(*args).T
    xs_next = ca.mtimes(Ad, xs) + ca.mtimes(B0, V * V * yk)
    if hold == "foh":
        xs_next += ca.mtimes(B1, V * V * (yk - yh[0]))
    nxt = ca.vertcat(xs_next, uk, *uh[:L - 1], yk, *yh[:Ly - 1])
    return ca.Function("rom_loop_map", [s, V], [nxt], ["s", "V"], ["s_next"])


def rom_loop_flutter(rom: HWLModel, structure: ModalStructure, vrange, *, n_grid: int = 111,
                     convective_V0: float | None = None, hold: str = "zoh") -> float | None:
    """The flutter speed of the sampled-data ROM loop: its first Neimark--Sacker point in
    ``vrange``, where the spectral radius of the map's linearisation at rest (its oscillatory
    multipliers) crosses one.

    Parameters
    ----------
    rom : HWLModel
        Discrete HWL ROM (eq. 3).
    structure : ModalStructure
        Σs (eq. 7).
    vrange : (float, float)
        Speed-index range, scanned on ``n_grid`` points, the crossing refined by Brent's
        method.
    n_grid : int
        Points of the scan (at least 3).
    convective_V0, hold :
        The loop (:func:`rom_loop_map`).

    Returns
    -------
    float or None
        ``None`` when the loop is unstable at the low end or does not flutter in the range.
    """
    F = rom_loop_map(rom, structure, convective_V0=convective_V0, hold=hold)
    n = int(F.size1_in(0))
    s, V = ca.SX.sym("s", n), ca.SX.sym("V")
    jac = ca.Function("loop_jacobian", [s, V], [ca.jacobian(F(s, V), s)])
    zero = np.zeros(n)

    def radius(v: float) -> float:
        lam = np.linalg.eigvals(np.asarray(jac(zero, v), float))
        osc = lam[np.abs(lam.imag) > 1e-9]
        return float(np.max(np.abs(osc))) - 1.0 if osc.size else -1.0

    grid = np.linspace(max(float(vrange[0]), 1e-3), float(vrange[1]), int(n_grid))
    r = np.array([radius(v) for v in grid])
    if r[0] >= 0:
        return None
    up = np.flatnonzero((r[:-1] < 0) & (r[1:] >= 0))
    if up.size == 0:
        return None
    k = int(up[0])
    return float(brentq(radius, grid[k], grid[k + 1], xtol=1e-10))


def _rom_outputs(rom, structure, sensor_kind, mode_names, sensor_names, hold):
    N = rom.n_modes
    L, Ly = _history(rom, hold)
    s = ca.SX.sym("s", 2 * N + (L + Ly) * N)
    V = ca.SX.sym("V")
    xs = s[:2 * N]
    u = ca.mtimes(ca.DM(structure.Cs), xs)
    H = ca.DM(np.asarray(structure.Hs, float))
    if structure.sensor == "state":
        raise ConfigError("the LCO outputs need modal sensor rows (sensor kind 'displacement', "
                          "'velocity' or 'acceleration'), not the paper's literal state rows")
    if sensor_kind == "acceleration":
        # left limit at t_k, as simulate_loop reads accelerometers: the held force V^2 y_{k-1},
        # or its first-order extrapolation V^2 (2 y_{k-1} - y_{k-2})
        y1 = s[2 * N + L * N:2 * N + L * N + N]
        y_left = 2 * y1 - s[2 * N + (L + 1) * N:2 * N + (L + 2) * N] if hold == "foh" else y1
        acc = ca.mtimes(ca.DM(structure.Cv @ structure.As), xs) + structure.alpha * V * V * y_left
        z = ca.mtimes(H, acc)
    else:
        z = ca.mtimes(H, u)
    mode_names = tuple(mode_names or (f"u{i + 1}" for i in range(N)))
    sensor_names = tuple(sensor_names or (f"z{j + 1}" for j in range(structure.n_sensors)))
    if len(mode_names) != N or len(sensor_names) != structure.n_sensors:
        raise DimensionError(f"give {N} mode names and {structure.n_sensors} sensor names")
    return (mode_names + sensor_names, ("",) * (N + structure.n_sensors),
            ca.Function("outputs", [s, V], [ca.vertcat(u, z)]))


def _basis(theta: np.ndarray, K: int) -> np.ndarray:
    """``[1, cos t, sin t, ..., cos Kt, sin Kt]`` at ``theta``: shape ``(len, 2K+1)``."""
    cols = [np.ones_like(theta)]
    for k in range(1, K + 1):
        cols += [np.cos(k * theta), np.sin(k * theta)]
    return np.stack(cols, axis=1)


def _dbasis_drho(theta: np.ndarray, K: int) -> np.ndarray:
    """d/dtheta of :func:`_basis`."""
    cols = [np.zeros_like(theta)]
    for k in range(1, K + 1):
        cols += [-k * np.sin(k * theta), k * np.cos(k * theta)]
    return np.stack(cols, axis=1)


class InvariantCircle:
    """Fourier discretisation of the invariant circles of ``F(s, V)`` (module docstring).

    Unknowns ``X = [C (n x M, column k the coefficient vector of basis k), rho, V]``.
    """

    def __init__(self, F: ca.Function, harmonics: int = 8, *, tol: float = 1e-9,
                 max_newton: int = 15):
        self.F = F
        n = int(F.size1_in(0))
        K = int(harmonics)
        M = 2 * K + 1
        self.n, self.K, self.M = n, K, M
        self.theta = 2.0 * np.pi * np.arange(M) / M
        self.E0 = _basis(self.theta, K)
        self.E0inv = np.linalg.inv(self.E0)
        self.nc = n * M
        self.nX = self.nc + 2
        self.irho, self.iV = self.nc, self.nc + 1
        s = ca.SX.sym("s", n)
        V = ca.SX.sym("V")
        Fs = F(s, V)
        self._Fm = F.map(M)
        self._J = ca.Function("DF", [s, V], [ca.jacobian(Fs, s), ca.jacobian(Fs, V)]).map(M)
        # DF along the circle, evaluated in chunks into numpy buffers (nonzeros only)
        Jsp = ca.jacobian(Fs, s)
        self._df_rows, self._df_cols = (np.asarray(v) for v in Jsp.sparsity().get_triplet())
        self._chunk = 512
        fb, ev = ca.Function("DFnz", [s, V], [Jsp]).map(self._chunk).buffer()
        self._df_in = np.zeros(n * self._chunk)
        self._df_V = np.zeros(self._chunk)
        self._df_out = np.zeros(Jsp.nnz() * self._chunk)
        fb.set_arg(0, memoryview(self._df_in))
        fb.set_arg(1, memoryview(self._df_V))
        fb.set_res(0, memoryview(self._df_out))
        self._df_buffer, self._df_eval = fb, ev
        self._tol, self._max_newton = tol, max_newton

    # ---- unknowns ---------------------------------------------------------------------
    def coefficients(self, X: np.ndarray) -> np.ndarray:
        """``C`` of shape ``(n, M)``."""
        return np.asarray(X[:self.nc]).reshape(self.M, self.n).T

    def pack(self, C: np.ndarray, rho: float, V: float) -> np.ndarray:
        return np.concatenate([np.asarray(C, float).ravel(order="F"), [rho, V]])

    def from_values(self, values: np.ndarray, rho: float, V: float) -> np.ndarray:
        """Unknowns from the circle's values at the ``M`` collocation angles."""
        return self.pack(np.asarray(values) @ self.E0inv.T, rho, V)

    def derivative(self, C: np.ndarray) -> np.ndarray:
        """Coefficients of ``ds/dtheta``."""
        out = np.zeros_like(C)
        for k in range(1, self.K + 1):
            a, b = C[:, 2 * k - 1], C[:, 2 * k]
            out[:, 2 * k - 1] = k * b
            out[:, 2 * k] = -k * a
        return out

    def values(self, X: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``s(theta)``, shape ``(n, len(theta))``."""
        return self.coefficients(X) @ _basis(np.asarray(theta, float), self.K).T

    # ---- system -----------------------------------------------------------------------
    def reference(self, X: np.ndarray) -> np.ndarray:
        """Phase reference: the coefficients of ``ds/dtheta`` (constant term zero)."""
        return self.derivative(self.coefficients(X)).ravel(order="F")

    def _shift(self, rho):
        th = self.theta + 2.0 * np.pi * rho
        return _basis(th, self.K), 2.0 * np.pi * _dbasis_drho(th, self.K)

    def _eval(self, X):
        C = self.coefficients(X)
        rho, V = X[self.irho], X[self.iV]
        S = C @ self.E0.T                                            # (n, M) at theta_j
        Es, dEs = self._shift(rho)
        Fv = np.asarray(self._Fm(S, np.full((1, self.M), V)))
        return C, S, Es, dEs, Fv, V

    def core(self, X: np.ndarray) -> np.ndarray:
        C, S, Es, dEs, Fv, V = self._eval(X)
        return (Fv - C @ Es.T).ravel(order="F")

    def core_jacobian(self, X: np.ndarray) -> np.ndarray:
        """Dense Jacobian of the invariance equations (rows point-major, state fastest)."""
        n, M = self.n, self.M
        C, S, Es, dEs, Fv, V = self._eval(X)
        Js, JV = self._J(S, np.full((1, M), V))
        Js = np.asarray(Js).reshape(n, M, n).transpose(1, 0, 2)     # (M, n, n): DF at theta_j
        JV = np.asarray(JV)                                          # (n, M)
        big = (np.einsum("jk,jab->jakb", self.E0, Js)
               - np.einsum("jk,ab->jakb", Es, np.eye(n))).reshape(M * n, M * n)
        drho = -(C @ dEs.T).ravel(order="F")
        return np.hstack([big, drho[:, None], JV.ravel(order="F")[:, None]])

    def phase_row(self, ref: np.ndarray) -> np.ndarray:
        row = np.zeros(self.nX)
        row[:self.nc] = ref
        return row

    def solve(self, X0, ref, c, s) -> RootResult:
        prow = self.phase_row(ref)

        def residual(X):
            return np.concatenate([self.core(X), [prow @ X, c @ X - s]])

        def jacobian(X):
            return np.vstack([self.core_jacobian(X), prow, c])

        return solve_newton(residual, jacobian, X0, tol=self._tol, max_iter=self._max_newton,
                            name="invariant_circle")

    def jacobian(self, X, ref):
        return np.vstack([self.core_jacobian(X), self.phase_row(ref)])

    # ---- stability ----------------------------------------------------------------------
    def _product(self, pts: np.ndarray, V: float) -> tuple[np.ndarray, float]:
        """``DF(s_{q-1}) ... DF(s_0)`` as ``(P, log_scale)`` with ``max|P| = 1``."""
        n, ch = self.n, self._chunk
        q = pts.shape[1]
        P = np.eye(n)
        log_scale = 0.0
        self._df_V[:] = V
        nnz = self._df_rows.size
        for a in range(0, q, ch):
            b = min(q, a + ch)
            blk = np.zeros((n, ch))
            blk[:, :b - a] = pts[:, a:b]
            self._df_in[:] = blk.ravel(order="F")
            self._df_eval()
            if self._df_buffer.ret() != 0:
                raise ConvergenceError("the Jacobian of the ROM loop map could not be evaluated "
                                       "along the invariant circle")
            nz = self._df_out.reshape(ch, nnz)
            Js = np.zeros((b - a, n, n))
            Js[:, self._df_rows, self._df_cols] = nz[:b - a]
            for k in range(b - a):
                P = Js[k] @ P
                if k % 8 == 7:
                    m = np.max(np.abs(P))
                    P /= m
                    log_scale += math.log(m)
        m = np.max(np.abs(P))
        return P / m, log_scale + math.log(m)

    def normal_multiplier(self, X: np.ndarray, closing_tol: float = 1e-3,
                          max_q: int = 20000) -> tuple[float, float, np.ndarray, float]:
        """``(normal multiplier per period, tangent error, multipliers, closing error)``.

        The product of ``DF`` along ``q`` iterates of the rotation (module docstring); the
        tangent error is ``| |mu_tangent| - 1 |`` per period, the accuracy of the estimate.
        """
        rho = float(X[self.irho]) % 1.0
        V = float(X[self.iV])
        q, closing = _convergent(rho, closing_tol, max_q)
        th = 2.0 * np.pi * rho * np.arange(q)
        pts = self.values(X, th)
        P, log_scale = self._product(pts, V)
        lam, vec = np.linalg.eig(P)
        d0 = (self.derivative(self.coefficients(X)) @ _basis(np.array([0.0]), self.K).T).ravel()
        d0 = d0 / max(np.linalg.norm(d0), 1e-300)
        align = np.abs(d0 @ vec) / np.linalg.norm(vec, axis=0)
        mods = np.abs(lam)
        big = mods >= 1e-12 * mods.max()
        k = int(np.argmax(np.where(big, align, -1.0)))
        # modulus per iterate -> per LCO period (1/rho iterates)
        logm = (np.log(np.maximum(mods, 1e-300)) + log_scale) / (q * rho)
        tang = float(abs(math.exp(logm[k]) - 1.0))
        others = np.delete(logm, k)
        normal = float(math.exp(np.max(others))) if others.size else 0.0
        return normal, tang, np.exp(logm), float(closing)


def _convergent(rho: float, tol: float, max_q: int) -> tuple[int, float]:
    """Denominator ``q`` of the first continued-fraction convergent ``p / q`` of ``rho`` with
    at least one turn (``q rho >= 1``) and closing error ``|q rho - p| < tol`` (else the best
    convergent with ``q <= max_q``), and that closing error."""
    h0, h1, k0, k1 = 0, 1, 1, 0          # convergents p/q: h/k
    x = rho
    best = None
    for _ in range(60):
        a = math.floor(x)
        h0, h1 = h1, a * h1 + h0
        k0, k1 = k1, a * k1 + k0
        if k1 > max_q:
            break
        err = abs(k1 * rho - h1)
        if k1 * rho >= 1.0 - 1e-12 or k1 * rho >= 0.5:
            if best is None or err < best[1]:
                best = (k1, err)
            if err < tol:
                break
        frac = x - a
        if frac < 1e-15:
            break
        x = 1.0 / frac
    if best is None:
        q = max(1, int(math.ceil(1.0 / max(rho, 1e-12))))
        return q, abs(q * rho - round(q * rho))
    return best


class _MapDisc:
    """Adaptor of :class:`InvariantCircle` for the continuation engine."""

    def __init__(self, circ: InvariantCircle, names, outputs: ca.Function, step,
                 n_fine: int = 256):
        self.circ = circ
        self.iV = circ.iV
        self.names = names
        self.step = step                   # V -> the loop's step h [s]
        self._theta = 2.0 * np.pi * np.arange(n_fine) / n_fine
        self._h = outputs.map(n_fine)
        self.w2 = np.ones((circ.n, 1))     # state weights of size(); set from the mode shape

    def solve(self, X0, ref, c, s):
        return self.circ.solve(X0, ref, c, s)

    def jacobian(self, X, ref):
        return sp.csc_matrix(self.circ.jacobian(X, ref))

    def reference(self, X):
        return self.circ.reference(X)

    def size(self, X) -> float:
        C = self.circ.coefficients(X)
        return float(np.sqrt(0.5 * np.sum(C[:, 1:] ** 2 * self.w2)))

    def evaluate(self, X) -> LCOPoint:
        circ = self.circ
        V, rho = float(X[circ.iV]), float(X[circ.irho])
        S = circ.values(X, self._theta)
        Y = np.asarray(self._h(S, np.full((1, S.shape[1]), V)))
        amp = 0.5 * (Y.max(axis=1) - Y.min(axis=1))
        mean = Y.mean(axis=1)
        normal, tang, mults, _ = circ.normal_multiplier(X)
        period = self.step(V) / abs(rho)
        return LCOPoint(V=V, period=period, freq_hz=1.0 / period,
                        amplitude={n: float(a) for n, a in zip(self.names, amp)},
                        mean={n: float(a) for n, a in zip(self.names, mean)},
                        multipliers=mults, max_multiplier=normal, stable=bool(normal < 1.0),
                        trivial_error=tang, state=S[:, 0].copy())


def rom_lco_branch(rom: HWLModel, structure: ModalStructure, vrange, settings: LCOSettings | None = None,
                   *, mode_names=None, sensor_names=None, problem: str = "rom",
                   speed_scale: float = 1.0, speed_unit: str = "speed index",
                   time_unit: str = "s", convective_V0: float | None = None,
                   hold: str = "zoh") -> LCOBranch:
    """LCO branch (invariant circles) of the sampled-data ROM loop from its flutter point.

    Parameters
    ----------
    rom : HWLModel
        The identified HWL ROM (``casflutter run`` writes it as ``rom.npz``;
        :meth:`HWLModel.load` reads it).
    structure : ModalStructure
        Σs (eq. 7) it is coupled with; its sensor rows ``Hs`` give the sensor outputs.
    vrange : (float, float)
        Speed-index range of the Neimark--Sacker search and of the branch.
    settings : LCOSettings, optional
        ``harmonics`` sets the Fourier truncation; ``sensor_kind`` reads the sensors as
        displacements (``Hs u``) or accelerations (``Hs u''`` at ``t_k``, as
        :func:`~casflutter.aeroelastic.simulate_loop`).
    mode_names, sensor_names : sequence of str, optional
        Output names (default ``u1..``, ``z1..``).
    problem, speed_scale, speed_unit, time_unit :
        Labels of the result.
    convective_V0 : float, optional
        The ROM's identification speed index: the loop is stepped at ``rom.dt · V0 / V``,
        its aerodynamic time scale following the reduced frequency (:func:`rom_loop_map`);
        default ``rom.dt`` at every speed (eq. 8).
    hold : {"zoh", "foh"}
        The force's hold between samples (:func:`rom_loop_map`).

    Returns
    -------
    LCOBranch
        ``system == "rom_loop"``; ``hopf.discrete`` is True and ``hopf.lyapunov`` is the
        Neimark--Sacker coefficient ``d``; ``freq_hz`` is ``rho / h``, ``h`` the loop's step
        at the point's speed.

    Raises
    ------
    ConfigError
        No Neimark--Sacker point in the range (or unstable at its start), or a degenerate one.
    ConvergenceError
        The first invariant circle did not converge.

    See Also
    --------
    lco_branch : the truth's branch, to compare with.
    simulate_loop : one long simulation of the ROM loop.

    Examples
    --------
    With ``model`` an identified HWL ROM and ``structure`` its Σs (as in :func:`simulate_loop`),
    over speed indices 0.8 to 1.6 (minutes for the seed wing; :func:`run` does it from a
    configuration's ``[lco]`` table):

    >>> branch = cf.rom_lco_branch(model, structure, (0.8, 1.6))    # doctest: +SKIP
    >>> branch.hopf.kind, [p.V for p in branch.points][:3]         # doctest: +SKIP
    """
    settings = LCOSettings() if settings is None else settings
    lo, hi = (float(v) for v in vrange)
    if not 0 < lo < hi:
        raise ConfigError(f"vrange = ({lo}, {hi}) must satisfy 0 < lo < hi")
    t0 = time.perf_counter()
    F = rom_loop_map(rom, structure, convective_V0=convective_V0, hold=hold)
    names, units, hfun = _rom_outputs(rom, structure, settings.sensor_kind, mode_names,
                                      sensor_names, hold)
    forms = MultilinearForms(F)
    cp = find_neimark_sacker(forms, (lo, hi), settings.n_grid, speed_scale=speed_scale,
                             speed_unit=speed_unit)
    d = lyapunov_map(forms, cp)
    t_hopf = time.perf_counter() - t0
    theta0 = abs(np.angle(cp.eigenvalue))
    if not math.isfinite(d) or abs(d) < 1e-14:
        raise ConfigError(f"the Neimark-Sacker point at {cp.V * speed_scale:.6g} {speed_unit} is "
                          f"degenerate (critical "
                          f"coefficient {d:.3g}): no LCO branch leaves it")
    N = rom.n_modes
    dom = int(np.argmax(np.abs(cp.q[:2 * N:2])) * 2)       # largest modal displacement
    qhat = cp.q * np.exp(-1j * np.angle(cp.q[dom])) / abs(cp.q[dom])
    circ = InvariantCircle(F, settings.harmonics, tol=settings.tol,
                           max_newton=settings.max_newton)
    def step(V: float) -> float:
        return float(loop_sample_time(float(rom.dt), float(V), convective_V0))

    disc = _MapDisc(circ, names, hfun, step)
    h0 = step(cp.V)
    rho0 = theta0 / (2.0 * np.pi)
    # the critical mode as a circle: s(theta) = Re(qhat e^{i theta})
    mode_vals = np.real(qhat[:, None] * np.exp(1j * circ.theta)[None, :])
    phi = circ.from_values(mode_vals, 0.0, 0.0)
    phi[circ.irho] = phi[circ.iV] = 0.0
    start = BranchStart(
        cp=cp, lyapunov=d, radial=d, omega=theta0 / h0,
        freq_hz=rho0 / h0, discrete=True, qhat=qhat, dominant=dom,
        guess=lambda eps, V: circ.from_values(eps * mode_vals, rho0, V), phi=phi,
        ref=circ.reference(phi), n_points=circ.M, period0=rho0, hint="try more harmonics")
    t1b = time.perf_counter()
    hopf, run = run_from_hopf(disc, start, settings, (lo, hi), speed_scale=speed_scale,
                              speed_unit=speed_unit)
    t_branch = time.perf_counter() - t1b
    return LCOBranch(problem=problem, system="rom_loop", hopf=hopf, points=tuple(run.points),
                     folds=tuple(run.folds), outputs=names, output_units=units,
                     speed_unit=speed_unit, speed_scale=speed_scale, time_unit=time_unit,
                     completed=run.completed, stop_reason=run.stop_reason, vrange=(lo, hi),
                     timings={"hopf": t_hopf, "branch": t_branch,
                              "total": time.perf_counter() - t0})
