"""The seed wing: the paper's wind-tunnel wing with tip store (§IV, Table I, Fig. 5-6).

The wing's CFD/FEA are not available, so this is a full-order *nonlinear* truth of our own,
built in the spirit of the textbook problems and calibrated to the paper's published
figures.  Everything below that is not a number printed in the paper is OUR choice and is
documented with its reason in :class:`SeedWingParams`.

Structure (paper eq. 6, FEA modal basis given directly)
-------------------------------------------------------
Five modes with EXACTLY the paper's frequencies (Fig. 6): 1st bending 2.19 Hz, 1st lateral
(in-plane) 10.07 Hz, 2nd bending 13.55 Hz, 1st torsion 16.48 Hz, 3rd bending 38.09 Hz.  The
modal coordinates ``u`` are mass-normalised (generalised mass ``modal_mass`` for every
mode), so the structure is ``u'' + 2 zeta omega u' + omega^2 u = Q / modal_mass``.  Each mode
has a spanwise shape in the three physical deflections of the elastic axis, vertical
bending ``h(y)`` (positive down), lateral (chordwise, positive aft) ``e(y)`` and twist
``theta(y)`` (nose up):

    h_i(y) = H_i phi_{r(i)}(y),   e_i(y) = E_i phi_1(y),   theta_i(y) = T_i sin(pi y / 2L),

with ``phi_r`` the clamped--free Euler--Bernoulli shapes normalised to 1 at the tip (the
paper's bending frequencies 2.19 : 13.55 : 38.09 = 1 : 6.19 : 17.4 are within 1.5 % of the
uniform clamped--free ratios 1 : 6.27 : 17.55, so these shapes are apt).  The tip amplitudes
are fixed by the paper's accelerometer rows (§IV), which are the tip-store values of the
shapes: Acc2 (lateral) reads ``e(L)``, so ``E_i = Hs[1, i]``; Acc1 (vertical, ``acc1_offset``
aft of the elastic axis) reads ``h(L) + acc1_offset theta(L) = Hs[0, i]``, so
``H_i = Hs[0, i] - acc1_offset T_i``.  The twists ``T_i`` are: ``T_4 = Hs[0, 3] /
acc1_offset`` (torsion is pure twist, ``H_4 = 0``), ``T_1 = T_3 = T_5 = 0`` (bending modes are
untwisted) and ``T_2 = lateral_twist``: the tip store hangs below the wing plane, so when
it swings sideways in the lateral mode its inertia twists the tip -- the store-induced
lateral--torsion coupling that gives the otherwise aerodynamically silent in-plane mode its
aerodynamic forces, and with them the flutter of the mode-2 branch (paper Fig. 10).

Aerodynamics (strip theory, Wagner lag states per strip, saturating lift)
------------------------------------------------------------------------
``n_strips`` equal spanwise strips of Theodorsen's thin-airfoil theory (plunge ``h``, pitch
``theta``, trailing-edge flap ``v`` on the strips inside the flap span) with the circulatory
part through R. T. Jones' two-lag Wagner function, one pair of lag states per strip.  The
lagged effective downwash ``Q_eff`` of each strip passes through a softening lift curve
that saturates,

    c_l = lift_slope * alpha_sat * tanh(alpha_eff / alpha_sat),   alpha_eff = Q_eff / U,

(the source of the LCO above flutter), and the same saturated circulation carries the
leading-edge suction (Garrick 1936), a chordwise force ``X = suction * rho U b
lift_slope * (alpha_sat tanh(alpha_eff / alpha_sat))^2 * U`` (forward, per span) that acts on
the lateral deflection ``e``.  The suction is quadratic in the angle, so it vanishes in the
linearisation (flutter) but it makes the lateral mode's generalised force visibly nonlinear
in the chirp responses (paper Fig. 7: "less than 1 % error in all except the 2nd mode").
The flap is massless and prescribed; the tip store is aerodynamically inert.

Calibration (the values it gives are recorded in ``problems/seed_wing/problem.toml``)
-------------------------------------------------------------------------------------
- ``ea_chord`` (static divergence): the elastic axis sits at the quarter-chord aerodynamic
  centre (a quarter-chord spar), so the lift of a twisted strip has no moment arm and there
  is no torsional divergence.  What is left is the lateral mode's store-induced twist lifting
  its own plunge (``H_2 = -acc1_offset T_2`` up to the small Acc1 entry), a static
  divergence at ``V = 2.95``, far above the controller's range (the paper held ``V < 2.4``).
  Divergence sits at ``omega = 0``, where the tip accelerometers see nothing, so no
  controller can move it; with the axis at 35 % chord the paper route diverged at 1.26.
- ``modal_mass`` (hence ``alpha``): the aerodynamic-to-structural scale; set so that the
  paper's route -- HWL ROM (3,1,1,1,2,2) identified at ``V0 = 0.69`` from chirp records
  whose forces lag the motion by one step (dt = 2 ms, staggered CFD coupling, the reason
  for ``r = 1``), ERA to ``nf = 15``, Tustin, ΣAE with the ``V^2`` scaling, Hopf -- finds
  ``Vf = 1.20`` on the mode-2 branch (9.15 Hz) and no other crossing below 3.0.  The ROM
  data do not depend on ``modal_mass``, so the ROM's ``Vf`` (and any static divergence)
  scales exactly with ``sqrt(modal_mass)``.  The full-order truth flutters at 1.085
  (9.4 Hz); an exact linear ROM without the delay (the truth's aerodynamics frozen at
  ``V0``, scaled by ``V^2``) at 1.005: the frozen time scale, the one-step delay and the
  truncation to ``nf = 15`` (+0.07 against the minimal ``nf = 25``) all move the ROM's
  flutter by several per cent.
- ``lateral_twist`` (store offset): the twist that the store puts into the lateral mode;
  it drives the mode-2 flutter branch and sets its frequency, and with ``acc1_offset`` the
  mode's plunge ``H_2`` through the Acc1 row.  The static divergence speed goes as
  ``1 / lateral_twist``: 0.6 rad keeps it at 2.95 (0.8 gave 2.42).
- ``zeta`` 2 %, ``zeta_lateral`` 0.5 %: typical of a wind-tunnel model; the in-plane mode is
  the lightly damped one (its damping lowers the flutter speed, not the divergence).
- ``alpha_sat`` (nonlinearity): the lift curve saturates near 11 deg (c_l,max 1.26), which
  bounds the LCO above flutter (9.3 Hz at ``V = 1.3``, paper 8.5 Hz) and keeps the chirp
  responses of modes 1, 3, 4, 5 within 1 % of linear; ``suction = 1`` (full leading-edge
  suction) makes the lateral mode's force about 13 % nonlinear in the same chirps.
- ``chord`` 4 cm (beam-like): short Wagner lags (``b / U = 1 ms`` at ``V0``), so the paper's
  HWL orders (3,1,1,1,2,2) fit the chirp forces within 1 % on modes 1, 3, 4, 5.

Conventions: time in seconds; speed index ``V = U / U_ref`` with ``U_ref = 28.9 m/s``
(Table I: ``V0 = 0.69`` at 20 m/s, ``Vf = 1.20`` at 34.7 m/s); flow constant ``alpha =
rho U_ref^2 b L / modal_mass`` so that ``alpha V^2 y = Q / modal_mass`` with ``y = Q /
(rho U^2 b L)`` the generalised-force coefficient returned by :meth:`SeedWing.aero_forces`.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ..structure import AirspeedMixin, SpeedConvention
from ._aero import JONES_A, JONES_B, strip_coefficients
from ._base import AeroelasticTruth, AeroMatrices, SimulationResult
from ._goland import _bending_shapes
from ._params import ChordGeometryMixin, ParamsMixin, require
from ._params import parameter as _p  # the parameter fields below

__all__ = ["SeedWingParams", "SeedWing", "SEED_FREQUENCIES_HZ", "SEED_SENSOR_ROWS",
           "SEED_MODE_NAMES", "SEED_U_REF"]

#: Paper Fig. 6: modal frequencies [Hz] of the five FEA modes.
SEED_FREQUENCIES_HZ = (2.19, 10.07, 13.55, 16.48, 38.09)
#: Paper Fig. 6: the modes, in order.
SEED_MODE_NAMES = ("bending 1", "lateral 1", "bending 2", "torsion 1", "bending 3")
#: Paper §IV: the accelerometer rows in modal coordinates (Acc1 bending/torsion, Acc2 lateral).
SEED_SENSOR_ROWS = ((0.1299, -0.0006, -0.2866, -0.1130, 0.0766),
                    (-0.0021, 0.1364, 0.0141, 0.0021, -0.0020))
#: Table I: airspeed per unit speed index [m/s] (20 m/s <-> 0.69, 34.7 m/s <-> 1.20).
SEED_U_REF = 28.9

_BENDING_ORDER = (1, 1, 2, 1, 3)  # clamped-free shape carrying each mode's vertical part


@dataclass(frozen=True)
class SeedWingParams(ChordGeometryMixin, ParamsMixin):
    """Seed-wing parameters.

    Geometry and air are plausible values for a low-speed wind-tunnel wing (the paper does
    not print them); the calibrated constants (``modal_mass``, ``zeta``, ``zeta_lateral``,
    ``lateral_twist``, ``alpha_sat``, ``suction``) were chosen so that the ROM pipeline
    lands on the paper's published figures (see ``problems/seed_wing/problem.toml`` for the
    calibration record).
    """

    semispan: float = _p(0.50, "m", "semispan L (our choice: a 1 m wing span model)")
    chord: float = _p(0.04, "m", "chord 2b (our choice: a beam-like wing, semispan 12.5 chords)")
    ea_chord: float = _p(0.25, "-", "elastic axis, fraction of chord from the leading edge "
                         "(our choice: at the quarter-chord aerodynamic centre, a quarter-chord "
                         "spar; no torsional divergence, see the module docstring)")
    rho: float = _p(1.225, "kg/m^3", "air density (sea level; Mach 0.06 tunnel)")
    lift_slope: float = _p(2 * np.pi, "1/rad", "linear lift-curve slope")
    U_ref: float = _p(SEED_U_REF, "m/s", "airspeed per unit speed index (Table I)")
    modal_mass: float = _p(0.0006974, "kg", "generalised mass of every mass-normalised mode "
                           "(CALIBRATED: sets alpha, the aerodynamic-to-structural scale)")
    zeta: float = _p(0.02, "-", "structural damping ratio of modes 1, 3, 4, 5 "
                     "(CALIBRATED: typical of a wind-tunnel model)")
    zeta_lateral: float = _p(0.005, "-", "structural damping ratio of the lateral mode 2 "
                             "(CALIBRATED)")
    lateral_twist: float = _p(0.6, "rad", "tip twist of the lateral mode per unit modal "
                              "coordinate: store-induced lateral--torsion coupling (CALIBRATED)")
    acc1_offset: float = _p(0.04, "m", "Acc1 position aft of the elastic axis on the store "
                            "(our choice: on the store just aft of the trailing edge; sets the torsion "
                            "mode's tip twist Hs[0, 3] / acc1_offset = -2.8 rad per unit u4)")
    alpha_sat: float = _p(0.20, "rad", "saturation angle of the lift curve "
                          "c_l = a alpha_sat tanh(alpha/alpha_sat) (CALIBRATED: LCO)")
    suction: float = _p(1.0, "-", "leading-edge suction efficiency (CALIBRATED: mode-2 "
                        "nonlinearity)")
    flap_chord: float = _p(0.25, "-", "flap chord fraction (hinge at 75 % chord)")
    flap_span_start: float = _p(0.5, "-", "flap inboard end, fraction of semispan")
    flap_span_end: float = _p(0.9, "-", "flap outboard end, fraction of semispan")
    n_strips: int = _p(10, "-", "number of aerodynamic strips")

    def _validate(self) -> None:
        for name in ("semispan", "chord", "rho", "lift_slope", "U_ref", "modal_mass",
                     "alpha_sat", "acc1_offset"):
            require(getattr(self, name) > 0, f"{name} = {getattr(self, name)} must be positive")
        require(0 < self.ea_chord < 1, f"ea_chord = {self.ea_chord} must lie in (0, 1)")
        require(self.zeta >= 0 and self.zeta_lateral >= 0,
                f"damping ratios zeta = {self.zeta}, zeta_lateral = {self.zeta_lateral} "
                "must be >= 0")
        require(self.suction >= 0, f"suction = {self.suction} must be >= 0")
        require(0 < self.flap_chord < 1, f"flap_chord = {self.flap_chord} must lie in (0, 1)")
        require(0 <= self.flap_span_start < self.flap_span_end <= 1,
                f"need 0 <= flap_span_start ({self.flap_span_start}) < flap_span_end "
                f"({self.flap_span_end}) <= 1")
        require(2 <= self.n_strips <= 100, f"n_strips = {self.n_strips} must be in 2..100")


class SeedWing(AirspeedMixin, AeroelasticTruth):
    """Full-order nonlinear truth of the paper's wind-tunnel wing (module docstring).

    Parameters
    ----------
    params : SeedWingParams, optional
        Defaults to the calibrated wing.

    Notes
    -----
    The modal coordinates are the physical coordinates of the base class (``Phi = I``).
    :meth:`state_matrix` / :meth:`statespace` are the linearisation about the undeflected
    wing (``tanh'(0) = 1``, suction vanishes); :meth:`aero_forces` and :meth:`simulate` keep
    the saturating lift and the suction.
    """

    Params = SeedWingParams
    name = "seed_wing"

    def __init__(self, params: SeedWingParams | None = None) -> None:
        p = SeedWingParams() if params is None else params
        L, ns = p.semispan, p.n_strips
        self._dy = L / ns
        ys = (np.arange(ns) + 0.5) * self._dy
        self._ys = ys
        phi, _ = _bending_shapes(np.concatenate([ys, [L]]), L, 3)
        phi = phi / phi[:, -1:]  # tip value 1
        tw = np.sin(0.5 * np.pi * ys / L)
        Hs = np.asarray(SEED_SENSOR_ROWS, float)
        T = np.array([0.0, p.lateral_twist, 0.0, Hs[0, 3] / p.acc1_offset, 0.0])
        H = Hs[0] - p.acc1_offset * T
        E = Hs[1].copy()
        #: (N, ns) strip values of each mode's plunge, twist, lateral deflection
        self._h = np.array([H[i] * phi[_BENDING_ORDER[i] - 1, :-1] for i in range(5)])
        self._th = np.outer(T, tw)
        self._e = np.outer(E, phi[0, :-1])
        self._tip = {"H": H, "T": T, "E": E}
        frac = ys / L
        self._flap = ((frac >= p.flap_span_start) & (frac <= p.flap_span_end)).astype(float)
        super().__init__(p)

    # conventions --------------------------------------------------------------------
    @property
    def speed(self) -> SpeedConvention:
        """Speed index ``V = U / U_ref`` (Table I: ``U_ref = 28.9 m/s``), time in seconds,
        dynamic pressure from ``rho``."""
        p = self.params
        return SpeedConvention(f"V = U / U_ref, U_ref = {p.U_ref:g} m/s (Table I)", "s",
                               U_ref=p.U_ref, rho=p.rho)

    @property
    def alpha(self) -> float:
        """Flow constant of eq. (6): ``rho U_ref^2 b L / modal_mass`` [1/s^2]."""
        p = self.params
        return p.rho * p.U_ref ** 2 * p.b * p.semispan / p.modal_mass

    def _zeta(self) -> np.ndarray:
        p = self.params
        z = np.full(5, p.zeta)
        z[1] = p.zeta_lateral
        return z

    def _structure_matrices(self):
        w = 2 * np.pi * np.asarray(SEED_FREQUENCIES_HZ)
        return np.eye(5), np.diag(w ** 2)

    def strip_shapes(self) -> dict[str, np.ndarray]:
        """Strip positions and the modes' plunge, twist and lateral deflections there.

        Returns
        -------
        dict
            ``"y"`` ``(ns,)`` strip mid-span positions [m]; ``"h"``, ``"theta"``, ``"e"``
            ``(N, ns)`` per unit modal coordinate [m, rad, m]; ``"flap"`` ``(ns,)`` 1 on
            flapped strips; ``"tip"`` the tip amplitudes ``H, T, E`` of the shapes.
        """
        return {"y": self._ys.copy(), "h": self._h.copy(), "theta": self._th.copy(),
                "e": self._e.copy(), "flap": self._flap.copy(),
                "tip": {k: v.copy() for k, v in self._tip.items()}}

    # aerodynamics ---------------------------------------------------------------------
    def _strips(self, V: float):
        p = self.params
        U = self.airspeed(V)
        sc = strip_coefficients(rho=p.rho, b=p.b, U=U, a=p.a, c=1.0 - 2.0 * p.flap_chord,
                                lift_slope=p.lift_slope)
        return U, sc

    def aero_matrices(self, V: float) -> AeroMatrices:
        """Linearised strip-theory Jones/Wagner operator at ``V`` (per unit modal mass).

        One downwash ``Q`` (and its two Jones lag states) per strip: ``ng = n_strips``.
        """
        p = self.params
        V = self._check_V(V)
        U, sc = self._strips(V)
        h, th, fl, dy = self._h, self._th, self._flap, self._dy
        m = p.modal_mass
        # generalised force Q_i = sum_s dy (-L_s h_i(s) + M_s theta_i(s))
        Cx = dy * (-h @ (sc.La1 * th.T) + th @ (sc.Ma1 * th.T))
        Mx = dy * (-h @ (sc.Lh2 * h.T + sc.La2 * th.T) + th @ (sc.Mh2 * h.T + sc.Ma2 * th.T))
        Fv = dy * (th @ fl) * sc.Mb0
        Fv1 = dy * (-(h @ fl) * sc.Lb1 + (th @ fl) * sc.Mb1)
        Fv2 = dy * (-(h @ fl) * sc.Lb2 + (th @ fl) * sc.Mb2)
        W = dy * (-sc.Lc * h + sc.Mc * th)
        Gx = sc.Qa0 * th.T
        Gx1 = sc.Qh1 * h.T + sc.Qa1 * th.T
        Gv = sc.Qb0 * fl
        Gv1 = sc.Qb1 * fl
        return AeroMatrices(Kx=np.zeros((5, 5)), Cx=Cx / m, Mx=Mx / m, Fv=Fv / m, Fv1=Fv1 / m,
                            Fv2=Fv2 / m, W=W / m, Gx=Gx, Gx1=Gx1, Gv=Gv, Gv1=Gv1,
                            lams=tuple(bj * U / p.b for bj in JONES_B))

    def _nonlinear_circulation(self, geff: np.ndarray, U: float) -> tuple[np.ndarray, np.ndarray]:
        """Saturated effective downwash and the suction force per strip (per unit modal mass).

        Parameters
        ----------
        geff : numpy.ndarray
            ``(..., ns)`` lagged effective downwash ``Q_eff`` [m/s].
        U : float
            Airspeed [m/s].

        Returns
        -------
        gsat : numpy.ndarray
            ``U alpha_sat tanh(Q_eff / (U alpha_sat))``: replaces ``Q_eff`` in the
            circulatory lift and moment.
        qx : numpy.ndarray
            ``(..., N)`` generalised forces of the leading-edge suction on the lateral
            deflection, per unit modal mass.
        """
        p = self.params
        s = U * p.alpha_sat
        gsat = s * np.tanh(geff / s)
        # X forward (towards -e): -X e_i; X = suction rho b lift_slope gsat^2 per span
        X = p.suction * p.rho * p.b * p.lift_slope * gsat ** 2
        qx = -(X @ self._e.T) * self._dy / p.modal_mass
        return gsat, qx

    def aero_forces(self, timepts: np.ndarray, u: np.ndarray, v: np.ndarray | None,
                    V: float, *, udot: np.ndarray | None = None,
                    uddot: np.ndarray | None = None, vdot: np.ndarray | None = None,
                    vddot: np.ndarray | None = None, linear: bool = False) -> np.ndarray:
        """Nonlinear generalised aerodynamic forces ``y`` for prescribed modal motion and flap.

        As :meth:`AeroelasticTruth.aero_forces` (same arguments, same derivative handling,
        flow at rest before ``timepts[0]``), with the saturating lift and the leading-edge
        suction of the module docstring; ``y`` is normalised so that eq. (6),
        ``u'' + 2 zeta omega u' + omega^2 u = alpha V^2 y``, holds exactly.

        Parameters
        ----------
        timepts : ndarray, shape (K,)
            Sample times.
        u : ndarray, shape (K, N)
            Modal displacements.
        v : ndarray, shape (K,) or None
            Flap angle [rad].
        V : float
            Speed index.
        udot, uddot, vdot, vddot : ndarray, optional
            Exact derivatives of the motion (default: finite differences).
        linear : bool
            Return the linearised forces instead (the operator of :meth:`aero_matrices`).

        Returns
        -------
        numpy.ndarray
            ``(K, 5)`` generalised-force coefficients ``y = Q / (rho U^2 b L)``.
        """
        if linear:
            return super().aero_forces(timepts, u, v, V, udot=udot, uddot=uddot, vdot=vdot,
                                       vddot=vddot)
        V = self._check_V(V)
        t, dt, u, v, udot, uddot, vdot, vddot = self._prescribed_motion(
            timepts, u, v, udot, uddot, vdot, vddot)
        am = self.aero_matrices(V)
        geff = self._lagged_circulation(am, dt, u, udot, uddot, v, vdot, vddot)
        gsat, qx = self._nonlinear_circulation(geff, self.airspeed(V))
        f = (udot @ am.Cx.T + uddot @ am.Mx.T + np.outer(v, am.Fv) + np.outer(vdot, am.Fv1)
             + np.outer(vddot, am.Fv2) + gsat @ am.W.T + qx)
        return f / (self.alpha * V * V)

    # nonlinear simulation --------------------------------------------------------------
    def simulate(self, timepts: np.ndarray, x0: np.ndarray, V: float,
                 v: np.ndarray | None = None, *, rtol: float = 1e-8,
                 atol: float = 1e-11, linear: bool = False) -> SimulationResult:
        """Time simulation of the full nonlinear truth (structure + strip aerodynamics).

        Parameters
        ----------
        timepts : numpy.ndarray
            ``(K,)`` increasing output times [s].
        x0 : numpy.ndarray
            ``[u, u']`` (length 10; flow at rest) or the full state ``[u, u', z1, z2]``
            (length ``10 + 2 n_strips``).
        V : float
            Speed index.
        v : numpy.ndarray, optional
            ``(K,)`` flap angle [rad] at ``timepts`` (quintic spline); zero if omitted.
        rtol, atol : float
            ``solve_ivp`` (DOP853) tolerances.
        linear : bool
            Integrate the linearised truth instead (:meth:`state_matrix`).

        Returns
        -------
        SimulationResult
            ``y`` are the (nonlinear) generalised-force coefficients of eq. (6).
        """
        V = self._check_V(V)
        c = self._coupled(V)
        N, ng = c["N"], c["ng"]
        nx = 2 * N + 2 * ng
        t, x0, vs, vfun = self._simulation_inputs(timepts, x0, v, nx)
        if vfun is not None:
            vd1, vd2 = vfun.derivative(1), vfun.derivative(2)
        forces_at = self._forces(V, linear)

        def forces(tt, s):
            if vfun is None:
                return forces_at(s, 0.0, 0.0, 0.0)
            return forces_at(s, float(vfun(tt)), float(vd1(tt)), float(vd2(tt)))

        dynamics = self.flap_dynamics(V, linear)

        def rhs(tt, s):
            if vfun is None:
                return dynamics(s, 0.0, 0.0, 0.0)[0]
            return dynamics(s, float(vfun(tt)), float(vd1(tt)), float(vd2(tt)))[0]

        sol = solve_ivp(rhs, (t[0], t[-1]), x0, method="DOP853", t_eval=t, rtol=rtol,
                        atol=atol)
        S = sol.y.T
        if S.shape[0] != t.size:
            S = np.vstack([S, np.full((t.size - S.shape[0], nx), np.nan)])
        acc = np.full((t.size, N), np.nan)
        Q = np.full((t.size, N), np.nan)
        for k, (tt, s) in enumerate(zip(t, S)):
            if np.all(np.isfinite(s)):
                acc[k], _, Q[k] = forces(tt, s)
        return SimulationResult(timepts=t, states=S, u=S[:, :N], udot=S[:, N:2 * N],
                                uddot=acc, y=Q / (self.alpha * V * V), v=vs, V=V,
                                success=bool(sol.success), message=str(sol.message),
                                nfev=int(sol.nfev))

    def _forces(self, V: float, linear: bool = False):
        """``f(s, v, v', v'') -> (u'', g, Q)``: modal accelerations, strip downwash and
        generalised forces of the full state ``s = [u, u', z1, z2]`` with the flap angle and
        its rates (the right-hand side shared by :meth:`simulate` and :meth:`flap_dynamics`)."""
        c = self._coupled(V)
        am, Minv, N, ng = c["am"], c["Minv"], c["N"], c["ng"]
        U = self.airspeed(V)
        w2 = self._omega ** 2
        c2 = 2 * self._zeta() * self._omega
        a0 = 1.0 - sum(JONES_A)
        lam1, lam2 = am.lams
        A1, A2 = JONES_A
        Gx, Gx1, Gv, Gv1 = am.Gx, am.Gx1, am.Gv, am.Gv1

        def forces_at(s, vv, vdv, vddv):
            uu, ud = s[:N], s[N:2 * N]
            z1, z2 = s[2 * N:2 * N + ng], s[2 * N + ng:]
            g = Gx @ uu + Gx1 @ ud + Gv * vv + Gv1 * vdv
            geff = a0 * g + A1 * lam1 * z1 + A2 * lam2 * z2
            if linear:
                gs, qx = geff, 0.0
            else:
                gs, qx = self._nonlinear_circulation(geff, U)
            # (I - Mx) u'' = -w2 u - c2 u' + Cx u' + Fv v + Fv1 v' + Fv2 v'' + W gs + qx
            rhs_f = (am.Cx @ ud + am.Fv * vv + am.Fv1 * vdv + am.Fv2 * vddv + am.W @ gs + qx)
            acc = Minv @ (-w2 * uu - c2 * ud + rhs_f)
            return acc, g, rhs_f + am.Mx @ acc

        return forces_at

    def flap_dynamics(self, V: float, linear: bool = False):
        """The nonlinear truth as ``f(s, v, v', v'') -> (ds/dt, u'')`` for a flap driven from
        outside (a controller and actuator), e.g. closed-loop suppression simulations.

        ``s = [u, u', z1, z2]`` is the full state of :meth:`simulate`.  The right-hand side
        of :meth:`_forces` written as the linear truth (:meth:`state_matrix` and its flap
        columns) plus what the saturation changes:

        ``ds/dt = A s + B [v, v', v''] + E (g_sat - g_eff) + Q g_sat^2``,
        ``g_eff = G s + H [v, v']``, ``g_sat = sat(g_eff)``

        (``E`` the circulatory lift and moment, ``Q`` the leading-edge suction, both on the
        modal accelerations only): the same sums as :meth:`_forces` in one product, for the
        simulations call it four times per Runge-Kutta step.
        """
        if linear:
            return super().flap_dynamics(V, linear=True)
        V = self._check_V(V)
        c = self._coupled(V)
        am, Minv, N, ng = c["am"], c["Minv"], c["N"], c["ng"]
        p = self.params
        lam1, lam2 = am.lams
        A1, A2 = JONES_A
        a0 = 1.0 - sum(JONES_A)
        nx = 2 * N + 2 * ng
        ud_ = slice(N, 2 * N)
        # the effective downwash geff = a0 (Gx u + Gx1 u' + Gv v + Gv1 v') + A1 lam1 z1
        # + A2 lam2 z2, on [s; v; v']
        GH = np.hstack([a0 * am.Gx, a0 * am.Gx1, A1 * lam1 * np.eye(ng),
                        A2 * lam2 * np.eye(ng), a0 * np.column_stack([am.Gv, am.Gv1])])
        # the suction's generalised force per unit g_sat^2 of each strip
        # (:meth:`_nonlinear_circulation`: qx = -(X e^T) dy / m, X = k g_sat^2)
        k = p.suction * p.rho * p.b * p.lift_slope
        E, Q = np.zeros((nx, ng)), np.zeros((nx, ng))
        E[ud_] = Minv @ am.W
        Q[ud_] = Minv @ (-k * self._dy / p.modal_mass * self._e)
        ABEQ = np.hstack([c["A"], c["Bflap"], E, Q])
        sat = self.airspeed(V) * p.alpha_sat
        z = np.empty(nx + 3 + 2 * ng)      # [s; v; v'; v''; g_sat - g_eff; g_sat^2]
        dg_, gs2_ = slice(nx + 3, nx + 3 + ng), slice(nx + 3 + ng, nx + 3 + 2 * ng)

        def f(s, vv, vdv, vddv):
            z[:nx] = s
            z[nx], z[nx + 1], z[nx + 2] = vv, vdv, vddv
            geff = GH @ z[:nx + 2]
            gs = sat * np.tanh(geff / sat)
            np.subtract(gs, geff, out=z[dg_])
            np.multiply(gs, gs, out=z[gs2_])
            ds = ABEQ @ z
            return ds, ds[ud_]

        return f

    def vector_field(self) -> ca.Function:
        """The nonlinear wing without flap as a CasADi function ``f(x, V) -> dx/dt``.

        The right-hand side of :meth:`flap_dynamics` with the flap at rest, state
        ``x = [u, u', z1, z2]``: the strip operator of :meth:`aero_matrices` (each block a
        quadratic polynomial in ``V``, see :meth:`_quadratic_in_V`), the saturating lift and
        the leading-edge suction of :meth:`_nonlinear_circulation` written with CasADi's
        ``tanh``.

        Returns
        -------
        casadi.Function
            ``f(x, V)`` with ``x`` of length ``10 + 2 n_strips``.
        """
        p = self.params
        N = self.n_modes
        blocks = {}
        for name in ("Cx", "W", "Gx", "Gx1"):
            blocks[name] = self._quadratic_in_V(
                lambda V, name=name: getattr(self.aero_matrices(V), name))
        lam = self._quadratic_in_V(lambda V: np.array(self.aero_matrices(V).lams))
        c_lo = self._coupled(self._V_NODES[0])
        Minv, ng = c_lo["Minv"], c_lo["ng"]
        w2 = self._omega ** 2
        c2 = 2 * self._zeta() * self._omega
        a0 = 1.0 - sum(JONES_A)
        A1, A2 = JONES_A
        x = ca.SX.sym("x", 2 * N + 2 * ng)
        V = ca.SX.sym("V")

        def poly(c):
            return ca.DM(c[0]) + V * ca.DM(c[1]) + V * V * ca.DM(c[2])

        uu, ud = x[:N], x[N:2 * N]
        z1, z2 = x[2 * N:2 * N + ng], x[2 * N + ng:]
        lv = poly(lam)
        g = ca.mtimes(poly(blocks["Gx"]), uu) + ca.mtimes(poly(blocks["Gx1"]), ud)
        geff = a0 * g + A1 * lv[0] * z1 + A2 * lv[1] * z2
        s = V * p.U_ref * p.alpha_sat
        gsat = s * ca.tanh(geff / s)
        X = p.suction * p.rho * p.b * p.lift_slope * gsat ** 2
        qx = -ca.mtimes(ca.DM(self._e), X) * self._dy / p.modal_mass
        rhs_f = ca.mtimes(poly(blocks["Cx"]), ud) + ca.mtimes(poly(blocks["W"]), gsat) + qx
        acc = ca.mtimes(ca.DM(Minv), -w2 * uu - c2 * ud + rhs_f)
        dx = ca.vertcat(ud, acc, -lv[0] * z1 + g, -lv[1] * z2 + g)
        return ca.Function("seed_wing_vector_field", [x, V], [dx], ["x", "V"], ["xdot"])

    def _names(self) -> dict:
        return {"mode_names": SEED_MODE_NAMES,
                "coordinate_names": tuple(f"u{i + 1} ({n})" for i, n in enumerate(SEED_MODE_NAMES)),
                "sensor_rows": np.asarray(SEED_SENSOR_ROWS, float),
                "sensor_names": ("Acc1 (bending/torsion)", "Acc2 (lateral)"),
                # Hs u: the tip store's deflections [m] (the shapes are per unit u)
                "sensor_units": ("m", "m"),
                "sensor": "acceleration"}
