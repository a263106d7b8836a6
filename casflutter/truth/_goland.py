"""The Goland wing: a modal cantilever beam with strip-theory Jones/Wagner aerodynamics.

Structure (Goland 1945; Goland & Luke 1948): a uniform cantilever of semispan ``L`` with
bending stiffness ``EI``, torsional stiffness ``GJ``, mass ``m`` per length and pitch
inertia ``I`` about the elastic axis; the centre of mass lies ``x_cg = (cg - ea) chord``
aft of the elastic axis, coupling bending and torsion through the mass
(``S = m x_cg``).  Assumed modes: exact clamped-free Euler--Bernoulli bending shapes
``phi_r`` (``int phi_r^2 = L``) and uniform-torsion shapes
``vartheta_s = sin((2s-1) pi y / (2L))``; ``h(y,t) = phi^T a``, ``theta(y,t) = vartheta^T b``,

    Mhat = [[m Phh, S Pht], [S Pht^T, I Ptt]] / (m L),
    Khat = blockdiag(EI int phi'' phi''^T, GJ int vartheta' vartheta'^T) / (m L),

with ``Phh = int phi phi^T dy`` etc. (Gauss--Legendre quadrature of the exact shapes).

Aerodynamics: Theodorsen strip theory with Jones' two-lag Wagner function, integrated over
the span; the lag states are attached to the spanwise downwash patterns (one per assumed
mode plus one for the flap), which is exact because the lag is linear and the same at every
strip (uniform chord).  The trailing-edge flap (``flap_chord`` of the chord, from
``flap_span_start`` of the semispan to the tip, massless and prescribed) is OUR OWN addition,
not in Goland's paper.

Conventions: time in seconds; speed index ``V = U / (b omega_ref)`` with
``omega_ref = (pi / 2L) sqrt(GJ / I)`` the uncoupled first-torsion frequency; the flow
constant of eq. (6) is ``alpha = omega_ref^2 / (pi mu)``, ``mu = m / (pi rho b^2)``, so that
``alpha V^2 = rho U^2 / m`` and ``y = Phi^T f / (rho U^2 L)`` with ``f`` the generalised forces
on the assumed-mode coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq
from scipy.special import hankel2

from ..errors import ConfigError
from ..structure import AirspeedMixin, SpeedConvention
from ._aero import JONES_B, jones_C, strip_coefficients
from ._base import AeroelasticTruth, AeroMatrices
from ._params import ChordGeometryMixin, ParamsMixin, require
from ._params import parameter as _p  # the parameter fields below

__all__ = ["GolandParams", "GolandWing", "clamped_free_roots", "theodorsen_C"]

_NQUAD = 200


@dataclass(frozen=True)
class GolandParams(ChordGeometryMixin, ParamsMixin):
    """Goland-wing parameters; defaults are the published wing at sea-level density."""

    semispan: float = _p(6.096, "m", "semispan L (20 ft)")
    chord: float = _p(1.8288, "m", "chord 2b (6 ft)")
    ea_chord: float = _p(0.33, "-", "elastic axis, fraction of chord from the leading edge")
    cg_chord: float = _p(0.43, "-", "centre of mass, fraction of chord from the leading edge")
    mass: float = _p(35.71, "kg/m", "mass per unit span m")
    inertia: float = _p(8.64, "kg m^2/m", "pitch inertia per span about the elastic axis")
    EI: float = _p(9.77e6, "N m^2", "bending stiffness")
    GJ: float = _p(0.987e6, "N m^2", "torsional stiffness")
    rho: float = _p(1.225, "kg/m^3", "air density")
    lift_slope: float = _p(2 * np.pi, "1/rad", "circulatory lift-curve slope")
    zeta: float = _p(0.0, "-", "structural damping ratio of every in-vacuo mode")
    n_bending: int = _p(4, "-", "number of clamped-free bending assumed modes")
    n_torsion: int = _p(3, "-", "number of torsion assumed modes")
    flap_chord: float = _p(0.25, "-", "flap chord fraction (our addition, not Goland's)")
    flap_span_start: float = _p(0.75, "-", "flap inboard end, fraction of semispan (to the tip)")

    def _validate(self) -> None:
        for name in ("semispan", "chord", "mass", "inertia", "EI", "GJ", "rho", "lift_slope"):
            require(getattr(self, name) > 0, f"{name} = {getattr(self, name)} must be positive")
        require(0 < self.ea_chord < 1, f"ea_chord = {self.ea_chord} must lie in (0, 1)")
        require(0 < self.cg_chord < 1, f"cg_chord = {self.cg_chord} must lie in (0, 1)")
        xcg = (self.cg_chord - self.ea_chord) * self.chord
        require(self.inertia > self.mass * xcg ** 2,
                f"inertia = {self.inertia} must exceed mass * x_cg^2 = {self.mass * xcg ** 2:g} "
                "(the mass matrix must be positive definite)")
        require(self.zeta >= 0, f"damping ratio zeta = {self.zeta} must be >= 0")
        require(1 <= self.n_bending <= 8, f"n_bending = {self.n_bending} must be in 1..8")
        require(1 <= self.n_torsion <= 8, f"n_torsion = {self.n_torsion} must be in 1..8")
        require(0 < self.flap_chord < 1, f"flap_chord = {self.flap_chord} must lie in (0, 1)")
        require(0 <= self.flap_span_start < 1,
                f"flap_span_start = {self.flap_span_start} must lie in [0, 1)")

    @property
    def x_cg(self) -> float:
        """Centre of mass aft of the elastic axis [m]."""
        return (self.cg_chord - self.ea_chord) * self.chord

    @property
    def omega_ref(self) -> float:
        """Uncoupled first-torsion frequency ``(pi/2L) sqrt(GJ/I)`` [rad/s]."""
        return 0.5 * np.pi / self.semispan * np.sqrt(self.GJ / self.inertia)

    @property
    def mu(self) -> float:
        """Mass ratio ``m / (pi rho b^2)``."""
        return self.mass / (np.pi * self.rho * self.b ** 2)


def clamped_free_roots(n: int) -> np.ndarray:
    """First ``n`` roots of ``cos(x) cosh(x) = -1`` (clamped-free beam, ``beta_r L``)."""
    f = lambda x: np.cos(x) + 1.0 / np.cosh(x)  # same roots, well scaled
    return np.array([brentq(f, (r - 1) * np.pi + 0.3, r * np.pi, xtol=1e-14)
                     for r in range(1, n + 1)])


def theodorsen_C(k) -> np.ndarray:
    """Theodorsen's function ``C(k) = H1(k) / (H1(k) + i H0(k))`` (exact, Hankel functions).

    Parameters
    ----------
    k : array_like
        Reduced frequencies ``omega b / U >= 0``; ``C(0) = 1``.

    Returns
    -------
    numpy.ndarray
        Complex ``C(k)``, shaped like ``k``; ``H0, H1`` are the Hankel functions of the
        second kind (``scipy.special.hankel2``).
    """
    k = np.asarray(k, dtype=float)
    out = np.ones(k.shape, dtype=complex)
    pos = k > 0
    H1, H0 = hankel2(1, k[pos]), hankel2(0, k[pos])
    out[pos] = H1 / (H1 + 1j * H0)
    return out


def _bending_shapes(y: np.ndarray, L: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Clamped-free shapes and their second derivatives at ``y``, ``(n, len(y))`` each.

    ``phi = cosh - cos - s (sinh - sin)`` written stably as
    ``((1-s) e^x + (1+s) e^-x)/2 - cos + s sin``; normalised to ``int_0^L phi^2 = L``.
    """
    out, out2 = [], []
    for bl in clamped_free_roots(n):
        beta = bl / L
        x = beta * y
        # s = (cosh + cos)/(sinh + sin); 1 - s = (sin - cos - e^-bl)/(sinh + sin)
        den = np.sinh(bl) + np.sin(bl)
        s = (np.cosh(bl) + np.cos(bl)) / den
        one_minus_s = (np.sin(bl) - np.cos(bl) - np.exp(-bl)) / den
        ch_m_s_sh = 0.5 * (one_minus_s * np.exp(x) + (1.0 + s) * np.exp(-x))  # cosh - s sinh
        phi = ch_m_s_sh - np.cos(x) + s * np.sin(x)
        # phi'' / beta^2 = cosh + cos - s (sinh + sin) = (cosh - s sinh) + cos - s sin
        phi2 = beta ** 2 * (ch_m_s_sh + np.cos(x) - s * np.sin(x))
        out.append(phi)
        out2.append(phi2)
    return np.array(out), np.array(out2)


class GolandWing(AirspeedMixin, AeroelasticTruth):
    """Full-order truth: the Goland wing, assumed modes + strip-theory Jones aerodynamics.

    Parameters
    ----------
    params : GolandParams, optional
        Defaults to the published wing at ``rho = 1.225``.

    Notes
    -----
    The modes of eq. (6) are the coupled in-vacuo modes of the assumed-mode model
    (``x = Phi u``).  Speed index ``V = U / (b omega_ref)``, see :meth:`speed_index`.
    """

    Params = GolandParams
    name = "goland"

    def __init__(self, params: GolandParams | None = None) -> None:
        p = GolandParams() if params is None else params
        L = p.semispan
        xg, wg = np.polynomial.legendre.leggauss(_NQUAD)
        y = 0.5 * L * (xg + 1.0)
        w = 0.5 * L * wg
        phi, phi2 = _bending_shapes(y, L, p.n_bending)
        gam = (2 * np.arange(1, p.n_torsion + 1) - 1) * np.pi / (2 * L)
        th = np.sin(np.outer(gam, y))
        th1 = gam[:, None] * np.cos(np.outer(gam, y))
        self._Phh = (phi * w) @ phi.T
        self._Pht = (phi * w) @ th.T
        self._Ptt = (th * w) @ th.T
        self._Kbb = (phi2 * w) @ phi2.T
        self._Ktt = (th1 * w) @ th1.T
        # flap region [y0, L]
        y0 = p.flap_span_start * L
        yf = y0 + 0.5 * (L - y0) * (xg + 1.0)
        wf = 0.5 * (L - y0) * wg
        phif, _ = _bending_shapes(yf, L, p.n_bending)
        self._ch = phif @ wf
        self._ct = np.sin(np.outer(gam, yf)) @ wf
        # tip values for sensors
        phiL, _ = _bending_shapes(np.array([L]), L, p.n_bending)
        self._phi_tip = phiL[:, 0]
        self._th_tip = np.sin(gam * L)
        super().__init__(p)

    # conventions --------------------------------------------------------------------
    @property
    def speed(self) -> SpeedConvention:
        """Speed index ``V = U / (b omega_ref)`` (``U_ref = b omega_ref``), time in seconds,
        dynamic pressure from ``rho``."""
        p = self.params
        return SpeedConvention("V = U / (b omega_ref), omega_ref = (pi/2L) sqrt(GJ/I)", "s",
                               U_ref=(p.b, p.omega_ref), rho=p.rho)

    @property
    def alpha(self) -> float:
        """Flow constant of eq. (6): ``omega_ref^2 / (pi mu)``, so ``alpha V^2 = rho U^2 / m``."""
        p = self.params
        return p.omega_ref ** 2 / (np.pi * p.mu)

    # model ----------------------------------------------------------------------------
    def _structure_matrices(self):
        p = self.params
        nb, nt = p.n_bending, p.n_torsion
        mL = p.mass * p.semispan
        S = p.mass * p.x_cg
        M = np.block([[p.mass * self._Phh, S * self._Pht], [S * self._Pht.T, p.inertia * self._Ptt]])
        K = np.block([[p.EI * self._Kbb, np.zeros((nb, nt))],
                      [np.zeros((nt, nb)), p.GJ * self._Ktt]])
        return M / mL, K / mL

    def aero_matrices(self, V: float) -> AeroMatrices:
        """Strip-theory Jones/Wagner operator at speed index ``V`` (module docstring).
        """
        p = self.params
        V = self._check_V(V)
        U = self.airspeed(V)
        b = p.b
        sc = strip_coefficients(rho=p.rho, b=b, U=U, a=p.a, c=1.0 - 2.0 * p.flap_chord,
                                lift_slope=p.lift_slope)
        nb, nt = p.n_bending, p.n_torsion
        n, ng = nb + nt, nb + nt + 1
        ia, ib = slice(0, nb), slice(nb, n)
        Phh, Pht, Ptt, ch, ct = self._Phh, self._Pht, self._Ptt, self._ch, self._ct
        Cx = np.zeros((n, n))
        Mx = np.zeros((n, n))
        Cx[ia, ib] = -sc.La1 * Pht
        Cx[ib, ib] = sc.Ma1 * Ptt
        Mx[ia, ia] = -sc.Lh2 * Phh
        Mx[ia, ib] = -sc.La2 * Pht
        Mx[ib, ia] = sc.Mh2 * Pht.T
        Mx[ib, ib] = sc.Ma2 * Ptt
        Fv, Fv1, Fv2 = np.zeros(n), np.zeros(n), np.zeros(n)
        Fv[ib] = sc.Mb0 * ct
        Fv1[ia], Fv1[ib] = -sc.Lb1 * ch, sc.Mb1 * ct
        Fv2[ia], Fv2[ib] = -sc.Lb2 * ch, sc.Mb2 * ct
        W = np.zeros((n, ng))
        W[ia] = -sc.Lc * np.hstack([Phh, Pht, ch[:, None]])
        W[ib] = sc.Mc * np.hstack([Pht.T, Ptt, ct[:, None]])
        Gx, Gx1 = np.zeros((ng, n)), np.zeros((ng, n))
        Gx[nb:n, ib] = sc.Qa0 * np.eye(nt)
        Gx1[0:nb, ia] = sc.Qh1 * np.eye(nb)
        Gx1[nb:n, ib] = sc.Qa1 * np.eye(nt)
        Gv, Gv1 = np.zeros(ng), np.zeros(ng)
        Gv[n], Gv1[n] = sc.Qb0, sc.Qb1
        mL = p.mass * p.semispan
        return AeroMatrices(Kx=np.zeros((n, n)), Cx=Cx / mL, Mx=Mx / mL, Fv=Fv / mL,
                            Fv1=Fv1 / mL, Fv2=Fv2 / mL, W=W / mL, Gx=Gx, Gx1=Gx1, Gv=Gv,
                            Gv1=Gv1, lams=tuple(bj * U / b for bj in JONES_B))

    def _names(self) -> dict:
        p = self.params
        nb = p.n_bending
        Phi, M = self._Phi, self._Mhat
        names, counts = [], {"bending": 0, "torsion": 0}
        for i in range(Phi.shape[1]):
            ph = Phi[:, i]
            eb = ph[:nb] @ M[:nb, :nb] @ ph[:nb]
            et = ph[nb:] @ M[nb:, nb:] @ ph[nb:]
            kind = "bending" if eb >= et else "torsion"
            counts[kind] += 1
            names.append(f"{kind} {counts[kind]}")
        nt = p.n_torsion
        hrow = np.concatenate([self._phi_tip, np.zeros(nt)])
        trow = np.concatenate([np.zeros(nb), self._th_tip])
        b, a = p.b, p.a
        rows = np.array([hrow, trow, hrow - b * (1 + a) * trow, hrow + b * (1 - a) * trow]) @ Phi
        return {"mode_names": names,
                "coordinate_names": tuple([f"bending a{r + 1} [m]" for r in range(nb)]
                                          + [f"torsion b{s + 1} [rad]" for s in range(nt)]),
                "sensor_rows": rows,
                "sensor_names": ("tip plunge [m]", "tip pitch [rad]",
                                 "tip leading edge [m]", "tip trailing edge [m]"),
                "sensor_units": ("m", "rad", "m", "m")}

    # frequency domain ---------------------------------------------------------------
    def generalized_aero_forces(self, k, *, theodorsen: str = "exact") -> np.ndarray:
        """Strip-theory generalised aerodynamic forces ``Q(ik)`` on the in-vacuo modes.

        For harmonic motion ``u = Re(u_hat e^{i omega t})``, flap ``v = Re(v_hat e^{i omega t})``
        at reduced frequency ``k = omega b / U``, the generalised forces of eq. (6) are
        ``y = Re(Q(ik) [u_hat; v_hat] e^{i omega t})``: the same normalisation as
        :meth:`aero_forces` (``y = Phi^T f / (rho U^2 L)``), so that the modal equations are

            u'' + 2 zeta omega u' + omega^2 u = alpha V^2 Q(ik) [u; v],   alpha V^2 = rho U^2 / m,

        with ``V = U / (b omega_ref)`` the speed index.  ``Q`` depends on ``k`` only (not on
        ``U`` or ``rho``).  The assembly is that of :meth:`aero_matrices` (same assumed modes,
        strips and flap) with Theodorsen's circulation function ``C(k)`` in place of the Jones
        lag states.

        Parameters
        ----------
        k : array_like
            Reduced frequencies ``omega b / U >= 0``, shape ``(nk,)``.
        theodorsen : {"exact", "jones"}
            ``"exact"``: :func:`theodorsen_C` (Hankel functions); ``"jones"``: R. T. Jones'
            two-lag approximation, which reproduces the frequency response of the truth's own
            state space (:meth:`state_matrix`).

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(nk, N, N + 1)``: columns are the N modes (in the order of
            :meth:`modal_structure`) and the flap (last column, per radian).

        Raises
        ------
        ConfigError
            ``theodorsen`` not one of the two names, or ``k`` negative or not finite.
        """
        kk = np.atleast_1d(np.asarray(k, dtype=float))
        if kk.ndim != 1 or not np.all(np.isfinite(kk)) or np.any(kk < 0):
            raise ConfigError(f"reduced frequencies k must be a 1-D array of finite values >= 0, "
                              f"got {np.asarray(k)!r}")
        if theodorsen == "exact":
            Ck = theodorsen_C(kk)
        elif theodorsen == "jones":
            Ck = jones_C(kk)
        else:
            raise ConfigError(f"theodorsen={theodorsen!r}: use 'exact' or 'jones'")
        V = 1.0
        U, b = self.airspeed(V), self.params.b
        am = self.aero_matrices(V)
        Phi = self._Phi
        N = Phi.shape[1]
        out = np.empty((kk.size, N, N + 1), dtype=complex)
        for n, (kn, Cn) in enumerate(zip(kk, Ck)):
            s = 1j * kn * U / b
            Fx = am.Kx + s * am.Cx + s * s * am.Mx + Cn * am.W @ (am.Gx + s * am.Gx1)
            Fv = am.Fv + s * am.Fv1 + s * s * am.Fv2 + Cn * am.W @ (am.Gv + s * am.Gv1)
            out[n, :, :N] = Phi.T @ Fx @ Phi
            out[n, :, N] = Phi.T @ Fv
        return out / (self.alpha * V * V)
