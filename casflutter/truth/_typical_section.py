"""Pitch--plunge typical section with Wagner (R. T. Jones) aerodynamics and a flap.

Equations (Hodges & Pierce, ch. 5; Theodorsen 1935), nondimensional with ``xi = h/b``,
``tau = omega_theta t`` and speed index ``V = U / (b omega_theta)``::

    xi''      + x_theta theta'' + sigma^2 xi  = -L / (m b omega_theta^2)
    x_theta xi'' + r^2 theta''  + r^2 k(theta) theta = M / (m b^2 omega_theta^2)

with ``x_theta = e - a``, ``mu = m / (rho pi b^2)``, ``k(theta) = 1 + kappa1 theta + ... +
kappa4 theta^4`` (polynomial pitch stiffness for LCO studies, as in the NATA section) and
Theodorsen's lift ``L`` and moment ``M`` with the circulatory part through Jones' two-lag
Wagner function.  The optional trailing-edge flap (hinge ``c``) is prescribed (massless).

Time unit: ``1/omega_theta`` seconds (``omega_theta = 1`` by default, i.e. nondimensional
time ``tau``).  Normalisation of eq. (6): ``alpha = omega_theta^2 / (pi mu)``, so that
``y = Phi^T [-c_l, 2 c_m]`` (lift coefficient and moment coefficient about the elastic
axis, both on the chord ``2b``), the paper's force-coefficient outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..structure import SpeedConvention
from ._aero import JONES_B, strip_coefficients
from ._base import AeroelasticTruth, AeroMatrices
from ._params import ParamsMixin, require
from ._params import parameter as _p  # the parameter fields below

__all__ = ["TypicalSectionParams", "TypicalSection"]


@dataclass(frozen=True)
class TypicalSectionParams(ParamsMixin):
    """Typical-section parameters; defaults are Hodges & Pierce case HP-1 (problem 5.5)."""

    a: float = _p(-0.2, "semichords", "elastic axis aft of mid-chord")
    e: float = _p(-0.1, "semichords", "centre of mass aft of mid-chord")
    mu: float = _p(20.0, "-", "mass ratio m / (rho pi b^2)")
    r2: float = _p(0.24, "-", "squared radius of gyration I_P / (m b^2) about the elastic axis")
    sigma: float = _p(0.4, "-", "frequency ratio omega_h / omega_theta")
    zeta: float = _p(0.0, "-", "structural damping ratio of every in-vacuo mode")
    omega_theta: float = _p(1.0, "rad/s", "uncoupled pitch frequency (1: nondimensional time)")
    flap_hinge: float = _p(0.5, "semichords", "flap hinge aft of mid-chord (our flap, 25% chord)")
    lift_slope: float = _p(2 * np.pi, "1/rad", "circulatory lift-curve slope")
    kappa1: float = _p(0.0, "1/rad", "pitch stiffness polynomial k(theta) = 1 + kappa1 theta + ...")
    kappa2: float = _p(0.0, "1/rad^2", "pitch stiffness polynomial, theta^2 coefficient")
    kappa3: float = _p(0.0, "1/rad^3", "pitch stiffness polynomial, theta^3 coefficient")
    kappa4: float = _p(0.0, "1/rad^4", "pitch stiffness polynomial, theta^4 coefficient")

    def _validate(self) -> None:
        require(-1 < self.a < 1, f"a = {self.a} must lie in (-1, 1) (semichords from mid-chord)")
        require(-1 < self.e < 1, f"e = {self.e} must lie in (-1, 1) (semichords from mid-chord)")
        require(self.mu > 0, f"mass ratio mu = {self.mu} must be positive")
        require(self.r2 > (self.e - self.a) ** 2,
                f"r2 = {self.r2} must exceed (e - a)^2 = {(self.e - self.a) ** 2:g} "
                "(the mass matrix must be positive definite)")
        require(self.sigma > 0, f"frequency ratio sigma = {self.sigma} must be positive")
        require(self.zeta >= 0, f"damping ratio zeta = {self.zeta} must be >= 0")
        require(self.omega_theta > 0, f"omega_theta = {self.omega_theta} must be positive")
        require(-1 < self.flap_hinge < 1, f"flap_hinge = {self.flap_hinge} must lie in (-1, 1)")
        require(self.lift_slope > 0, f"lift_slope = {self.lift_slope} must be positive")

    @property
    def x_theta(self) -> float:
        """Static unbalance ``e - a`` [semichords]."""
        return self.e - self.a

    @property
    def divergence_speed(self) -> float:
        """Static divergence speed index ``sqrt(mu r^2 / (1 + 2a))`` (``inf`` if ``a <= -1/2``)."""
        k = (1 + 2 * self.a) * self.lift_slope / (2 * np.pi)
        return float(np.sqrt(self.mu * self.r2 / k)) if k > 0 else float("inf")


class TypicalSection(AeroelasticTruth):
    """Full-order truth: pitch--plunge typical section with Jones/Wagner aerodynamics.

    Parameters
    ----------
    params : TypicalSectionParams, optional
        Defaults to Hodges & Pierce HP-1.

    Notes
    -----
    Physical coordinates ``x = [h/b, theta]``; the modes of eq. (6) are the two coupled
    in-vacuo modes (``x = Phi u``, ``Phi^T Mhat Phi = I``).  Speed index
    ``V = U / (b omega_theta)``; ``alpha = omega_theta^2 / (pi mu)``.
    """

    Params = TypicalSectionParams
    name = "typical_section"

    def __init__(self, params: TypicalSectionParams | None = None) -> None:
        super().__init__(TypicalSectionParams() if params is None else params)

    def _structure_matrices(self):
        p = self.params
        s2 = p.omega_theta ** 2
        M = np.array([[1.0, p.x_theta], [p.x_theta, p.r2]])
        K = s2 * np.diag([p.sigma ** 2, p.r2])
        return M, K

    @property
    def alpha(self) -> float:
        """Flow constant of eq. (6): ``omega_theta^2 / (pi mu)``."""
        return self.params.omega_theta ** 2 / (np.pi * self.params.mu)

    def aero_matrices(self, V: float) -> AeroMatrices:
        """Jones/Wagner aerodynamic operator at speed index ``V`` (module docstring).
        """
        p = self.params
        V = self._check_V(V)
        s = p.omega_theta
        sc = strip_coefficients(rho=1.0, b=1.0, U=V, a=p.a, c=p.flap_hinge,
                                lift_slope=p.lift_slope)
        m = np.pi * p.mu  # m / (rho b^2) with rho = b = 1
        Z = np.zeros((2, 2))
        return AeroMatrices(
            Kx=Z.copy(),
            Cx=s * np.array([[0.0, -sc.La1], [0.0, sc.Ma1]]) / m,
            Mx=np.array([[-sc.Lh2, -sc.La2], [sc.Mh2, sc.Ma2]]) / m,
            Fv=s * s * np.array([0.0, sc.Mb0]) / m,
            Fv1=s * np.array([-sc.Lb1, sc.Mb1]) / m,
            Fv2=np.array([-sc.Lb2, sc.Mb2]) / m,
            W=s * s * np.array([[-sc.Lc], [sc.Mc]]) / m,
            Gx=np.array([[0.0, sc.Qa0]]),
            Gx1=np.array([[sc.Qh1, sc.Qa1]]) / s,
            Gv=np.array([sc.Qb0]),
            Gv1=np.array([sc.Qb1]) / s,
            lams=tuple(bj * V * s for bj in JONES_B),
        )

    def _nonlinear_force(self, x):
        p = self.params
        if not any((p.kappa1, p.kappa2, p.kappa3, p.kappa4)):
            return None
        th = x[1]
        extra = p.r2 * p.omega_theta ** 2 * th * (p.kappa1 * th + p.kappa2 * th ** 2
                                                  + p.kappa3 * th ** 3 + p.kappa4 * th ** 4)
        return np.array([0.0, extra])

    def _names(self) -> dict:
        p = self.params
        Phi = self._Phi
        # kinetic-energy share of plunge vs pitch in each mode
        share = np.array([Phi[0] ** 2, p.r2 * Phi[1] ** 2])
        names = ["plunge" if share[0, i] >= share[1, i] else "pitch" for i in range(2)]
        if names[0] == names[1]:
            names = [f"{names[0]} {i + 1}" for i in range(2)]
        return {"mode_names": names, "coordinate_names": ("h/b", "theta"),
                "sensor_rows": Phi.copy(), "sensor_names": ("h/b", "theta"),
                "sensor_units": ("-", "rad")}

    @property
    def speed(self) -> SpeedConvention:
        """Speed index ``V = U / (b omega_theta)`` without an airspeed scale (the section is
        nondimensional); time in ``1/omega_theta`` (seconds when ``omega_theta`` is given)."""
        return SpeedConvention("V = U / (b omega_theta)",
                               "s" if self.params.omega_theta != 1.0 else "1/omega_theta")
