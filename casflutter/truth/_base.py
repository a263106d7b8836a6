"""The common machinery of the full-order truth simulators.

A truth is a structure with ``n`` physical (or assumed-mode) coordinates ``x``,

    Mhat x'' + Chat x' + Khat x + f_nl(x) = fhat,

(mass-scaled so that ``Mhat`` is dimensionless), loaded by linear unsteady aerodynamics in
the Jones/Wagner state-space form (see :mod:`._aero`)

    fhat = Kx x + Cx x' + Mx x'' + Fv v + Fv1 v' + Fv2 v'' + W g_eff,
    g    = Gx x + Gx1 x' + Gv v + Gv1 v',
    g_eff = (1 - A1 - A2) g + A1 lam1 z1 + A2 lam2 z2,   z_j' = -lam_j z_j + g,

with flap angle ``v``.  The in-vacuo modes ``x = Phi u`` (``Phi^T Mhat Phi = I``,
``Phi^T Khat Phi = diag(omega^2)``) turn the structure into the paper's eq. (6),

    u_i'' + 2 zeta_i omega_i u_i' + omega_i^2 u_i = alpha V^2 y_i,   y = Phi^T fhat / (alpha V^2),

and ``y`` is what :meth:`AeroelasticTruth.aero_forces` returns for prescribed ``u`` and ``v``.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import casadi as ca
import control
import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import make_interp_spline
from scipy.linalg import eigh

from .._format import result_repr
from ..errors import ConfigError, DataError, DimensionError
from ..structure import ModalLayout, ModalStates, ModalStructure, SpeedConvention
from ._aero import JONES_A, check_timepts, integrate_lags, sample_derivatives

__all__ = ["AeroMatrices", "SimulationResult", "AeroelasticTruth"]


@dataclass(frozen=True)
class AeroMatrices:
    """Linear aerodynamic operator at one speed (see the module docstring for the form).

    Shapes: ``Kx, Cx, Mx`` ``(n, n)``; ``Fv, Fv1, Fv2`` ``(n,)``; ``W`` ``(n, ng)``;
    ``Gx, Gx1`` ``(ng, n)``; ``Gv, Gv1`` ``(ng,)``; ``lams`` the Jones lag rates [1/time].
    """

    Kx: np.ndarray
    Cx: np.ndarray
    Mx: np.ndarray
    Fv: np.ndarray
    Fv1: np.ndarray
    Fv2: np.ndarray
    W: np.ndarray
    Gx: np.ndarray
    Gx1: np.ndarray
    Gv: np.ndarray
    Gv1: np.ndarray
    lams: tuple[float, float]


@dataclass(frozen=True)
class SimulationResult:
    """A time simulation of the full truth (structure + Jones aerodynamics).

    Attributes
    ----------
    timepts : numpy.ndarray
        ``(K,)`` sample times.
    states : numpy.ndarray
        ``(K, 2N + 2 ng)``: ``[u, u', z1, z2]`` (modal displacements, velocities, lag states).
    u, udot, uddot : numpy.ndarray
        ``(K, N)`` modal displacements, velocities, accelerations.
    y : numpy.ndarray
        ``(K, N)`` generalised aerodynamic forces (normalised as in eq. (6)).
    v : numpy.ndarray
        ``(K,)`` flap angle used.
    V : float
        Speed index.
    success : bool
        Integrator status (``scipy.integrate.solve_ivp``).
    message : str
        Integrator message.
    nfev : int
        Right-hand-side evaluations.
    """

    __repr__ = result_repr

    timepts: np.ndarray
    states: np.ndarray
    u: np.ndarray
    udot: np.ndarray
    uddot: np.ndarray
    y: np.ndarray
    v: np.ndarray
    V: float
    success: bool
    message: str
    nfev: int


def _as_2d(name: str, arr, K: int, N: int) -> np.ndarray:
    a = np.asarray(arr, dtype=float)
    if a.ndim == 1 and N == 1:
        a = a[:, None]
    if a.shape != (K, N):
        raise DimensionError(f"{name} must have shape (K, N) = ({K}, {N}) (samples x modes), "
                             f"got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise DataError(f"{name} contains NaN or inf")
    return a


def _as_1d(name: str, arr, K: int) -> np.ndarray:
    a = np.asarray(arr, dtype=float).reshape(-1)
    if a.shape != (K,):
        raise DimensionError(f"{name} must have K = {K} samples, got shape {np.shape(arr)}")
    if not np.all(np.isfinite(a)):
        raise DataError(f"{name} contains NaN or inf")
    return a


class AeroelasticTruth(ModalStates, abc.ABC):
    """Base class of the truth simulators (typical section, Goland wing).

    Subclasses provide the structural matrices, the aerodynamic operator at a speed index
    and the conventions; everything else (modes, forces for prescribed motion, the coupled
    linear system, nonlinear simulation) is shared.
    """

    #: parameter dataclass of the problem
    params: object

    def __init__(self, params) -> None:
        self.params = params
        Mh, Kh = self._structure_matrices()
        w2, Phi = eigh(Kh, Mh)
        if np.any(w2 <= 0):
            raise ConfigError("structural stiffness is not positive definite; check the "
                              "stiffness parameters")
        # sign convention: the largest component of each mode shape is positive
        idx = np.argmax(np.abs(Phi), axis=0)
        Phi = Phi * np.sign(Phi[idx, np.arange(Phi.shape[1])])
        self._Mhat, self._Khat, self._Phi = Mh, Kh, Phi
        self._omega = np.sqrt(w2)

    # ---- to be provided by a problem -------------------------------------------------
    @abc.abstractmethod
    def _structure_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``(Mhat, Khat)`` in the physical/assumed-mode coordinates."""

    @abc.abstractmethod
    def aero_matrices(self, V: float) -> AeroMatrices:
        """The linear aerodynamic operator at speed index ``V`` (module docstring).

        Parameters
        ----------
        V : float
            Speed index.

        Returns
        -------
        AeroMatrices
            The state-space operator from modal motion (and flap) to generalised forces.
        """

    @property
    @abc.abstractmethod
    def alpha(self) -> float:
        """Flow constant ``alpha`` of eq. (6)."""

    @abc.abstractmethod
    def _names(self) -> dict:
        """Mode names, coordinate names, sensor rows/names (and units, kind)."""

    @property
    @abc.abstractmethod
    def speed(self) -> SpeedConvention:
        """What the speed index ``V`` is, the unit of time, the airspeed and dynamic pressure
        (:class:`~casflutter.structure.SpeedConvention`)."""

    def _nonlinear_force(self, x: np.ndarray) -> np.ndarray | None:
        """Extra structural restoring force ``f_nl(x)`` (``None`` if linear)."""
        return None

    def _zeta(self) -> np.ndarray:
        return np.full(self._omega.size, float(getattr(self.params, "zeta", 0.0)))

    def _modal_damping(self) -> np.ndarray:
        """Modal damping matrix ``D`` of ``u'' + D u' + ...`` (``diag(2 zeta omega)`` unless a
        problem has physical dampers that couple the modes)."""
        return np.diag(2.0 * self._zeta() * self._omega)

    # ---- public ----------------------------------------------------------------------
    def with_updates(self, **changes: float):
        """The same problem with some parameters changed (unknown names raise ConfigError)."""
        return type(self)(self.params.with_updates(**changes))

    @property
    def n_modes(self) -> int:
        """Number of structural modes ``N``."""
        return int(self._omega.size)

    def damping_coupling(self) -> float:
        """How strongly the structural damping couples the modes: the largest
        ``|D_ij| / sqrt(D_ii D_jj)`` (``i != j``) of the modal damping matrix ``D``; 0 for
        modal damping, which Σs (eq. 7, diagonal) holds exactly.

        Returns
        -------
        float
        """
        D = self._modal_damping()
        d = np.sqrt(np.abs(np.diag(D)))
        off = np.abs(D - np.diag(np.diag(D)))
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(off > 0, off / np.outer(d, d), 0.0)
        ratio = np.where(np.isfinite(ratio), ratio, np.inf)
        return float(np.max(ratio, initial=0.0))

    def modal_structure(self) -> ModalStructure:
        """Σs of the truth (eq. 6-7): frequencies, damping, flow constant, mode shapes, the
        problem's sensor rows (read as displacements unless the problem says otherwise) and
        the names of modes, coordinates and sensors.

        Returns
        -------
        casflutter.structure.ModalStructure
        """
        nm = self._names()
        return ModalStructure(omega=self._omega.copy(), zeta=self._zeta(), alpha=self.alpha,
                              Hs=np.asarray(nm["sensor_rows"], float),
                              sensor=nm.get("sensor", "displacement"),
                              mode_names=tuple(nm["mode_names"]),
                              sensor_names=tuple(nm["sensor_names"]), shapes=self._Phi.copy(),
                              coordinate_names=tuple(nm["coordinate_names"]), speed=self.speed)

    @property
    def layout(self) -> ModalLayout:
        """Where the truth's state ``[u, u', lags]`` keeps each mode."""
        return ModalLayout(self.n_modes, interleaved=False)

    @property
    def mode_states(self) -> list[np.ndarray]:
        """Indices ``[u_i, u'_i]`` of each mode in the truth's state ``[u, u', lags]`` (for the
        origin-mode attribution of :func:`casflutter.aeroelastic.find_flutter`)."""
        return self.layout.mode_states

    def sensor_units(self) -> tuple[str, ...]:
        """Units of the sensor rows' readings (``""`` where the problem gives none)."""
        nm = self._names()
        return tuple(nm.get("sensor_units", ("",) * len(nm["sensor_names"])))

    def _check_V(self, V: float) -> float:
        V = float(V)
        if not np.isfinite(V) or V <= 0:
            raise ConfigError(f"speed index V must be positive and finite, got {V}")
        return V

    def _prescribed_motion(self, timepts, u, v, udot, uddot, vdot, vddot):
        """Checked samples of a prescribed modal motion and flap with their first two
        derivatives (from a quintic spline of the samples where not given), shared by every
        truth's :meth:`aero_forces`."""
        dt = check_timepts(timepts)
        t = np.asarray(timepts, float)
        K, N = t.size, self.n_modes
        u = _as_2d("u", u, K, N)
        v = np.zeros(K) if v is None else _as_1d("v", v, K)
        if udot is None or uddot is None:
            d1, d2 = sample_derivatives(t, u, 2)
            udot = d1 if udot is None else udot
            uddot = d2 if uddot is None else uddot
        udot, uddot = _as_2d("udot", udot, K, N), _as_2d("uddot", uddot, K, N)
        if vdot is None or vddot is None:
            d1, d2 = sample_derivatives(t, v, 2)
            vdot = d1 if vdot is None else vdot
            vddot = d2 if vddot is None else vddot
        vdot, vddot = _as_1d("vdot", vdot, K), _as_1d("vddot", vddot, K)
        return t, dt, u, v, udot, uddot, vdot, vddot

    def aero_forces(self, timepts: np.ndarray, u: np.ndarray, v: np.ndarray | None,
                    V: float, *, udot: np.ndarray | None = None,
                    uddot: np.ndarray | None = None, vdot: np.ndarray | None = None,
                    vddot: np.ndarray | None = None) -> np.ndarray:
        """Generalised aerodynamic forces ``y`` for prescribed modal motion and flap.

        ``y`` is normalised so that the structure is exactly eq. (6),
        ``u'' + 2 zeta omega u' + omega^2 u = alpha V^2 y`` (see :meth:`modal_structure`).
        The flow is at rest before ``timepts[0]`` (Wagner lag states start at zero).

        Derivatives not passed are taken from a quintic interpolating spline of the samples
        (exact for the interpolant; ``O(dt^4)`` for ``u''`` away from the first and last
        few samples, where the spline's end conditions lose accuracy: pass exact derivatives
        or discard ~10 samples at each end); the Jones lag states are then integrated
        exactly for the cubic Hermite interpolant of their input.  Sample finely enough to
        resolve the highest modal frequency excited (``omega dt`` well below 1).

        Parameters
        ----------
        timepts : numpy.ndarray
            ``(K,)`` uniformly spaced sample times [time unit of the problem].
        u : numpy.ndarray
            ``(K, N)`` modal displacements.
        v : numpy.ndarray or None
            ``(K,)`` flap angle [rad]; ``None`` for no flap motion.
        V : float
            Speed index (see ``modal_structure().speed_index``).
        udot, uddot, vdot, vddot : numpy.ndarray, optional
            Exact derivatives, if the caller has them.

        Returns
        -------
        numpy.ndarray
            ``(K, N)`` generalised aerodynamic forces ``y``.
        """
        V = self._check_V(V)
        t, dt, u, v, udot, uddot, vdot, vddot = self._prescribed_motion(
            timepts, u, v, udot, uddot, vdot, vddot)
        Phi = self._Phi
        x, xd, xdd = u @ Phi.T, udot @ Phi.T, uddot @ Phi.T
        am = self.aero_matrices(V)
        geff = self._lagged_circulation(am, dt, x, xd, xdd, v, vdot, vddot)
        f = (x @ am.Kx.T + xd @ am.Cx.T + xdd @ am.Mx.T + np.outer(v, am.Fv)
             + np.outer(vdot, am.Fv1) + np.outer(vddot, am.Fv2) + geff @ am.W.T)
        return (f @ Phi) / (self.alpha * V * V)

    @staticmethod
    def _lagged_circulation(am: AeroMatrices, dt: float, x, xd, xdd, v, vdot,
                            vddot) -> np.ndarray:
        """Effective circulatory downwash per strip with Jones's two-lag Wagner function:
        the quasi-steady ``g`` (from the strip motion ``x, x', x''`` and the flap) filtered
        by the lag states ``z`` integrated exactly along the prescribed motion."""
        g = x @ am.Gx.T + xd @ am.Gx1.T + np.outer(v, am.Gv) + np.outer(vdot, am.Gv1)
        gd = xd @ am.Gx.T + xdd @ am.Gx1.T + np.outer(vdot, am.Gv) + np.outer(vddot, am.Gv1)
        zs = integrate_lags(g, gd, dt, am.lams)
        geff = (1.0 - sum(JONES_A)) * g
        for A, lam, z in zip(JONES_A, am.lams, zs):
            geff = geff + A * lam * z
        return geff

    # ---- coupled linear system -------------------------------------------------------
    def _coupled(self, V: float) -> dict:
        """Blocks of the coupled modal equations at ``V`` (see :meth:`state_matrix`)."""
        V = self._check_V(V)
        am = self.aero_matrices(V)
        Phi, P = self._Phi, self._Phi.T
        N, ng = self.n_modes, am.W.shape[1]
        a0 = 1.0 - sum(JONES_A)
        Mm = np.eye(N) - P @ am.Mx @ Phi
        Minv = np.linalg.inv(Mm)
        Ku = -np.diag(self._omega ** 2) + P @ (am.Kx + a0 * am.W @ am.Gx) @ Phi
        Cu = -self._modal_damping() + P @ (am.Cx + a0 * am.W @ am.Gx1) @ Phi
        Z = [A * lam * P @ am.W for A, lam in zip(JONES_A, am.lams)]
        Bv = [P @ (am.Fv + a0 * am.W @ am.Gv), P @ (am.Fv1 + a0 * am.W @ am.Gv1), P @ am.Fv2]
        nx = 2 * N + 2 * ng
        A = np.zeros((nx, nx))
        A[:N, N:2 * N] = np.eye(N)
        A[N:2 * N, :N] = Minv @ Ku
        A[N:2 * N, N:2 * N] = Minv @ Cu
        Bflap = np.zeros((nx, 3))  # columns: v, v', v''
        for j, lam in enumerate(am.lams):
            rows = slice(2 * N + j * ng, 2 * N + (j + 1) * ng)
            A[N:2 * N, rows] = Minv @ Z[j]
            A[rows, :N] = am.Gx @ Phi
            A[rows, N:2 * N] = am.Gx1 @ Phi
            A[rows, rows] = -lam * np.eye(ng)
            Bflap[rows, 0] = am.Gv
            Bflap[rows, 1] = am.Gv1
        for k in range(3):
            Bflap[N:2 * N, k] = Minv @ Bv[k]
        Bw = np.zeros((nx, N))
        Bw[N:2 * N] = Minv * self.alpha
        return {"A": A, "Bflap": Bflap, "Bw": Bw, "Minv": Minv, "am": am, "N": N, "ng": ng}

    def state_matrix(self, V: float) -> np.ndarray:
        """State matrix of the coupled full-order aeroelastic system at speed index ``V``.

        States ``[u, u', z1, z2]`` (modal displacements, velocities, Jones lag states),
        flap held at zero.  Its eigenvalues give the true flutter speed.
        """
        return self._coupled(V)["A"]

    def statespace(self, V: float, actuator_omega: float | None = None,
                   actuator_zeta: float = 0.7) -> control.StateSpace:
        """The linear aeroelastic system with flap input and modal disturbances.

        Parameters
        ----------
        V : float
            Speed index.
        actuator_omega : float, optional
            If given, the flap follows a second-order actuator
            ``v'' = actuator_omega^2 (v_c - v) - 2 actuator_zeta actuator_omega v'`` and the
            first input is the command ``v_c``; otherwise the flap states ``v, v'`` are a
            double integrator of the first input ``v''`` (flap acceleration).
        actuator_zeta : float
            Actuator damping ratio.

        Returns
        -------
        control.StateSpace
            States ``[u, u', z1, z2, v, v']``; inputs ``[flap, w_1..w_N]`` where ``w`` enters
            as in eq. (7) (``u'' += alpha w`` through the apparent-mass coupling); outputs
            ``[u_1..u_N, sensors...]``.
        """
        c = self._coupled(V)
        A0, Bf, Bw, N = c["A"], c["Bflap"], c["Bw"], c["N"]
        nx = A0.shape[0]
        A = np.zeros((nx + 2, nx + 2))
        A[:nx, :nx] = A0
        A[:nx, nx] = Bf[:, 0]
        A[:nx, nx + 1] = Bf[:, 1]
        A[nx, nx + 1] = 1.0
        B = np.zeros((nx + 2, 1 + N))
        B[:nx, 1:] = Bw
        if actuator_omega is None:
            B[:nx, 0] = Bf[:, 2]
            B[nx + 1, 0] = 1.0
        else:
            wa, za = float(actuator_omega), float(actuator_zeta)
            if wa <= 0 or za < 0:
                raise ConfigError("actuator_omega must be > 0 and actuator_zeta >= 0")
            # v'' = wa^2 (vc - v) - 2 za wa v'
            A[:nx, nx] += Bf[:, 2] * (-wa * wa)
            A[:nx, nx + 1] += Bf[:, 2] * (-2 * za * wa)
            A[nx + 1, nx] = -wa * wa
            A[nx + 1, nx + 1] = -2 * za * wa
            B[:nx, 0] = Bf[:, 2] * wa * wa
            B[nx + 1, 0] = wa * wa
        nm = self._names()
        H = np.asarray(nm["sensor_rows"], float)
        C = np.zeros((N + H.shape[0], nx + 2))
        C[:N, :N] = np.eye(N)
        C[N:, :N] = H
        D = np.zeros((C.shape[0], 1 + N))
        ng = c["ng"]
        states = ([f"u{i + 1}" for i in range(N)] + [f"u{i + 1}_dot" for i in range(N)]
                  + [f"z{j + 1}_{k + 1}" for j in range(2) for k in range(ng)] + ["v", "v_dot"])
        inputs = ["v_ddot" if actuator_omega is None else "v_c"] + [f"w{i + 1}" for i in range(N)]
        outputs = [f"u{i + 1}" for i in range(N)] + list(nm["sensor_names"])
        return control.ss(A, B, C, D, states=states, inputs=inputs, outputs=outputs,
                          name=f"{type(self).__name__}_V{V:g}".replace(".", "p"))

    # ---- CasADi vector field (periodic orbits, casflutter.lco) -----------------------
    #: speeds at which the V-polynomial coefficients of the coupled matrices are sampled
    _V_NODES: tuple[float, float, float] = (0.5, 1.0, 2.0)

    def _quadratic_in_V(self, fun) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact coefficients ``(c0, c1, c2)`` of ``fun(V) = c0 + c1 V + c2 V^2``.

        Theodorsen's strip coefficients and the Jones lag rates are linear or quadratic in
        the airspeed, so every block of the coupled operator is a quadratic polynomial in
        ``V``: the coefficients follow from three speeds (:attr:`_V_NODES`), and a fourth
        speed checks that the polynomial is exact.

        Raises
        ------
        ConfigError
            If ``fun`` is not quadratic in ``V`` (a truth whose operator is not).
        """
        v = np.asarray(self._V_NODES, float)
        F = [np.asarray(fun(float(vk)), float) for vk in v]
        Vd = np.vander(v, 3, increasing=True)
        coef = np.linalg.solve(Vd, np.array([f.ravel() for f in F]))
        c = [coef[k].reshape(F[0].shape) for k in range(3)]
        vt = 1.7 * v[-1]
        ref = np.asarray(fun(vt), float)
        err = np.max(np.abs(c[0] + vt * c[1] + vt * vt * c[2] - ref), initial=0.0)
        if err > 1e-9 * max(np.max(np.abs(ref), initial=0.0), 1e-300):
            raise ConfigError(f"{type(self).__name__}: the coupled operator is not quadratic in "
                              f"the speed (mismatch {err:.3g}); its CasADi vector field needs "
                              "its own implementation")
        return c[0], c[1], c[2]

    def vector_field(self) -> ca.Function:
        """The nonlinear truth without flap as a CasADi function ``f(x, V) -> dx/dt``.

        The state is that of :meth:`simulate`, ``x = [u, u', z1, z2]``; ``f`` is the linear
        coupled operator of :meth:`state_matrix` (written exactly as a quadratic polynomial
        in ``V``, see :meth:`_quadratic_in_V`) plus the nonlinear structural force
        ``f_nl`` of the problem, the same right-hand side as :meth:`flap_dynamics` with the
        flap at rest.  Periodic orbits (LCO) are solved and continued on it
        (:mod:`casflutter.lco`).

        Returns
        -------
        casadi.Function
            ``f(x, V)``: ``x`` of length ``2N + 2 ng``, ``V`` the speed index; output
            ``dx/dt``.
        """
        A0, A1, A2 = self._quadratic_in_V(lambda V: self._coupled(V)["A"])
        Minv = self._coupled(self._V_NODES[0])["Minv"]
        if not np.allclose(Minv, self._coupled(self._V_NODES[-1])["Minv"], rtol=1e-12,
                           atol=0.0):
            raise ConfigError(f"{type(self).__name__}: the apparent mass depends on the speed; "
                              "its CasADi vector field needs its own implementation")
        N, nx = self.n_modes, A0.shape[0]
        x = ca.SX.sym("x", nx)
        V = ca.SX.sym("V")
        dx = ca.mtimes(ca.DM(A0) + V * ca.DM(A1) + V * V * ca.DM(A2), x)
        Phi = self._Phi
        if self._nonlinear_force(np.zeros(Phi.shape[0])) is not None:
            xp = ca.mtimes(ca.DM(Phi), x[:N])
            fnl = self._nonlinear_force(xp)
            fnl = ca.vertcat(*[fnl[i] for i in range(Phi.shape[0])])
            corr = ca.mtimes(ca.DM(Minv @ Phi.T), fnl)
            dx = ca.vertcat(dx[:N], dx[N:2 * N] - corr, dx[2 * N:])
        return ca.Function("truth_vector_field", [x, V], [dx], ["x", "V"], ["xdot"])

    # ---- nonlinear simulation --------------------------------------------------------
    def flap_dynamics(self, V: float, linear: bool = False):
        """The truth as ``f(s, v, v', v'') -> (ds/dt, u'')`` for a flap driven from outside
        (a controller and actuator); ``s = [u, u', z1, z2]`` as in :meth:`simulate`, with the
        same (optional) nonlinear structural stiffness unless ``linear``.

        Parameters
        ----------
        V : float
            Speed index.
        linear : bool
            The linearised dynamics instead.

        Returns
        -------
        callable
            ``f(s, v, vdot, vddot) -> (ds/dt, u'')``.
        """
        c = self._coupled(V)
        A, Bf, Minv, N = c["A"], c["Bflap"], c["Minv"], c["N"]
        Phi = self._Phi
        has_nl = (not linear) and self._nonlinear_force(np.zeros(Phi.shape[0])) is not None

        def f(s, vv, vdv, vddv):
            ds = A @ s + Bf @ np.array([vv, vdv, vddv])
            if has_nl:
                ds[N:2 * N] -= Minv @ (Phi.T @ self._nonlinear_force(Phi @ s[:N]))
            return ds, ds[N:2 * N]

        return f

    def _simulation_inputs(self, timepts, x0, v, nx: int):
        """Checked inputs of a simulation: the times, the full initial state (a structural
        state is completed with the lag states at rest), the flap samples and their quintic
        spline (``None`` without flap motion)."""
        t = np.asarray(timepts, float)
        if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0):
            raise DataError("timepts must be a 1-D increasing array of at least 2 samples")
        x0 = self.layout.initial(x0, nx)
        if v is None:
            return t, x0, np.zeros(t.size), None
        vs = _as_1d("v", v, t.size)
        if t.size < 6:
            raise DataError("a flap history needs at least 6 samples")
        return t, x0, vs, make_interp_spline(t, vs, k=5)

    def simulate(self, timepts: np.ndarray, x0: np.ndarray, V: float,
                 v: np.ndarray | None = None, *, rtol: float = 1e-9,
                 atol: float = 1e-12) -> SimulationResult:
        """Time simulation of the full truth, including any nonlinear structural stiffness.

        Parameters
        ----------
        timepts : numpy.ndarray
            ``(K,)`` increasing output times (any spacing).
        x0 : ModalState or numpy.ndarray
            Initial state: a :class:`~casflutter.structure.ModalState` (e.g.
            :meth:`displaced_state`) or ``[u, u']`` (length ``2N``), the lag states at zero
            (the flow at rest), or the full state ``[u, u', z1, z2]``.
        V : float
            Speed index.
        v : numpy.ndarray, optional
            ``(K,)`` flap angle at ``timepts`` (interpolated by a quintic spline, whose
            derivatives give ``v'`` and ``v''``); zero if omitted.
        rtol, atol : float
            ``solve_ivp`` (DOP853) tolerances.

        Returns
        -------
        SimulationResult
        """
        c = self._coupled(V)
        A, Bf, Minv, N = c["A"], c["Bflap"], c["Minv"], c["N"]
        nx = A.shape[0]
        t, x0, vs, vfun = self._simulation_inputs(timepts, x0, v, nx)
        if vfun is not None:
            vd1, vd2 = vfun.derivative(1), vfun.derivative(2)
        Phi = self._Phi
        has_nl = self._nonlinear_force(np.zeros(Phi.shape[0])) is not None

        def rhs(tt, s):
            ds = A @ s
            if vfun is not None:
                ds = ds + Bf @ np.array([vfun(tt), vd1(tt), vd2(tt)])
            if has_nl:
                fnl = self._nonlinear_force(Phi @ s[:N])
                ds[N:2 * N] -= Minv @ (Phi.T @ fnl)
            return ds

        sol = solve_ivp(rhs, (t[0], t[-1]), x0, method="DOP853", t_eval=t, rtol=rtol,
                        atol=atol)
        S = sol.y.T
        if S.shape[0] != t.size:  # integration stopped early: pad with NaN, report failure
            S = np.vstack([S, np.full((t.size - S.shape[0], nx), np.nan)])
        acc = np.array([rhs(tt, s)[N:2 * N] if np.all(np.isfinite(s)) else np.full(N, np.nan)
                        for tt, s in zip(t, S)])
        u, ud = S[:, :N], S[:, N:2 * N]
        # eq. (6): alpha V^2 y = u'' + 2 zeta omega u' + omega^2 u + Phi^T f_nl
        aV2y = acc + ud @ self._modal_damping().T + u * self._omega ** 2
        if has_nl:
            aV2y = aV2y + np.array([Phi.T @ self._nonlinear_force(Phi @ ui) for ui in u])
        V = self._check_V(V)
        return SimulationResult(timepts=t, states=S, u=u, udot=ud, uddot=acc,
                                y=aV2y / (self.alpha * V * V), v=vs, V=V,
                                success=bool(sol.success), message=str(sol.message),
                                nfev=int(sol.nfev))
