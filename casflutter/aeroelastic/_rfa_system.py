"""ΣAE(U) from a rational-function approximation of ``Q(ik)``, in the airspeed ``U``.

With the RFA (:mod:`casflutter.realize`)
``Q(p) ~= A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p``, ``p = s b / U``, and the modal
structure of eq. (6) ``u'' + 2 zeta omega u' + omega^2 u = alpha V^2 y + alpha w``
(``V = U / U_ref``, ``y = Q [u; v]``), the lag states ``x_a = (p I - R)^-1 E p [u; v]`` obey

    x_a' = (U / b) R x_a + E [u'; v'],

and the modal accelerations, with the apparent mass moved to the left,

    (I - alpha (b / U_ref)^2 A2_uu) u'' = -omega^2 u - 2 zeta omega u' + alpha V^2 (A0 [u; v]
        + (b / U) A1 [u'; v'] + (b / U)^2 A2_uv v'' + D x_a) + alpha w.

Unlike Σf of the paper (eq. 5), frozen at one speed and scaled by ``V^2``, the lag rates
``gamma U / b`` and the ``p, p^2`` terms follow the airspeed, so the system is valid at every
``U`` within the accuracy of the fit.  :meth:`RFASystem.state_matrix` (flap held at zero)
feeds :func:`casflutter.aeroelastic.find_flutter` with ``U`` [m/s] as the speed variable.

Bridge to the paper's machinery: :meth:`RFASystem.frozen_sigma_f` returns Σf (eq. 5) of the
aerodynamics frozen at ``U_f``, in the normalisation of eq. (6)-(8); with the same
:class:`ModalStructure`, :meth:`AeroelasticSystem.from_parts` gives ΣAE(V) with
``V = U / U_ref`` and :func:`build_lft` the LFT of eq. 10-15 about ``V_f = U_f / U_ref``.
That ΣAE equals :meth:`RFASystem.state_matrix` exactly at ``U_f``; away from ``U_f`` it keeps
the lag rates of ``U_f`` and scales all of ``Q`` by ``V^2`` (the paper's frozen-ROM
assumption), so it is an approximation there.  Σf of eq. 5 is proper (inputs ``u, v``, no
derivatives), so the bridge needs an RFA without ``A1, A2`` (``poly_order=0``; the lag
terms then carry the aerodynamic damping and apparent mass).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError, DimensionError
from ..realize import RationalApproximation
from ..structure import AirspeedMixin, ModalStructure, SpeedConvention

__all__ = ["RFASystem"]


@dataclass(frozen=True)
class RFASystem(AirspeedMixin):
    """The aeroelastic system of an RFA and a modal structure, in the airspeed ``U``.

    Parameters
    ----------
    rfa : RationalApproximation
        Fitted ``Q(p)`` with ``N`` rows (and ``N`` or ``N + 1`` columns, the last the flap).
    structure : ModalStructure
        ω, ζ, α and sensor rows of the same ``N`` modes (eq. 6-7).
    U_ref : float
        Airspeed per unit speed index [m/s]: ``V = U / U_ref``, force ``alpha V^2 y``.

    Raises
    ------
    DimensionError
        ``rfa`` and ``structure`` have different numbers of modes.
    ConfigError
        ``U_ref`` not positive.
    """

    __repr__ = result_repr

    rfa: RationalApproximation
    structure: ModalStructure
    U_ref: float

    def __post_init__(self):
        if not isinstance(self.rfa, RationalApproximation):
            raise ConfigError(f"rfa must be a RationalApproximation, got {type(self.rfa).__name__}")
        if self.rfa.n_modes != self.structure.n_modes:
            raise DimensionError(
                f"the RFA has {self.rfa.n_modes} modes (rows of Q) but the structure has "
                f"{self.structure.n_modes}; use the same modes for Q(ik) and the modal data")
        U_ref = float(self.U_ref)
        if not np.isfinite(U_ref) or U_ref <= 0:
            raise ConfigError(f"U_ref = {self.U_ref!r} must be a positive airspeed per unit speed "
                              "index [m/s]")
        object.__setattr__(self, "U_ref", U_ref)

    # -- conventions ------------------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """N."""
        return self.structure.n_modes

    @property
    def b(self) -> float:
        """Reference semichord [m]."""
        return self.rfa.b

    @property
    def mode_states(self) -> list[np.ndarray]:
        """State indices ``[u_i, u_i']`` of each mode (for :func:`find_flutter`): the
        structure's layout, its states first."""
        return self.structure.mode_states

    @cached_property
    def speed(self) -> SpeedConvention:
        """The speed convention ``V = U / U_ref``: the structure's when it has this
        ``U_ref``, else one with the structure's unit of time."""
        own = self.structure.speed
        if own.U_ref == self.U_ref:
            return own
        return SpeedConvention(f"V = U / U_ref, U_ref = {self.U_ref:g} m/s", own.time_unit,
                               U_ref=self.U_ref)

    def _check_U(self, U) -> float:
        U = float(U)
        if not np.isfinite(U) or U <= 0:
            raise ConfigError(f"airspeed U = {U} must be positive and finite [m/s]")
        return U

    # -- the coupled equations ----------------------------------------------------------------
    def _blocks(self, U: float, flap: bool) -> dict:
        U = self._check_U(U)
        r, s = self.rfa, self.structure
        N, b = self.n_modes, r.b
        q = s.alpha * self.speed_index(U) ** 2
        bu = b / U
        A0, A1, A2 = r.A
        Minv = np.linalg.inv(np.eye(N) - q * bu * bu * A2[:, :N])
        keep = np.ones(r.n_lag_states, bool) if flap else np.any(r.E[:, :N] != 0, axis=1)
        Ku = -np.diag(s.omega ** 2) + q * A0[:, :N]
        Cu = -np.diag(2.0 * s.zeta * s.omega) + q * bu * A1[:, :N]
        return {"U": U, "q": q, "bu": bu, "Minv": Minv, "keep": keep, "Ku": Ku, "Cu": Cu,
                "D": r.D[:, keep], "R": r.R[keep], "E": r.E[keep]}

    def state_matrix(self, U: float) -> np.ndarray:
        """State matrix at airspeed ``U`` [m/s], flap held at zero.

        States ``[u_1, u_1', ..., u_N, u_N', x_a]`` (the block ordering of eq. 7, then the
        lag states driven by the modes; Roger's flap-only lag states are left out).

        Parameters
        ----------
        U : float
            Airspeed [m/s] (> 0): the lag rates ``gamma U / b`` and the forcing
            ``alpha (U / U_ref)^2`` follow it.

        Returns
        -------
        numpy.ndarray
            ``(2N + n_a, 2N + n_a)``.
        """
        c = self._blocks(U, flap=False)
        N, na = self.n_modes, c["R"].size
        iu, iv = 2 * np.arange(N), 2 * np.arange(N) + 1
        A = np.zeros((2 * N + na, 2 * N + na))
        A[iu, iv] = 1.0
        A[np.ix_(iv, iu)] = c["Minv"] @ c["Ku"]
        A[np.ix_(iv, iv)] = c["Minv"] @ c["Cu"]
        A[iv, 2 * N:] = c["Minv"] @ (c["q"] * c["D"])
        A[2 * N:, 2 * N:] = np.diag(c["R"] / c["bu"])
        A[2 * N:, iv] = c["E"][:, :N]
        return A

    def statespace(self, U: float) -> control.StateSpace:
        """The linear aeroelastic system at airspeed ``U`` with flap input and sensors.

        Parameters
        ----------
        U : float
            Airspeed [m/s] (> 0), as in :meth:`state_matrix`.

        Returns
        -------
        control.StateSpace
            States ``[u_1, u_1', ..., x_a, v, v']`` (all lag states, the flap angle and rate);
            inputs ``[v'', w_1..w_N]`` (flap acceleration [rad/s^2], and the modal disturbance
            of eq. 7, entering as ``alpha w``); outputs ``[u_1..u_N, zm...]`` with ``zm`` the
            sensors of the structure (``Hs`` times displacement, velocity, acceleration or the
            structural state, by ``structure.sensor``).

        Raises
        ------
        DimensionError
            The RFA has no flap column.
        """
        r, s = self.rfa, self.structure
        if not r.has_flap:
            raise DimensionError("the RFA has no flap column (Q is N x N): fit it to a Q(ik) "
                                 "table with the flap as column N + 1 for a flap input")
        c = self._blocks(U, flap=True)
        N, na = self.n_modes, c["R"].size
        q, bu, Minv = c["q"], c["bu"], c["Minv"]
        A0, A1, A2 = r.A
        nx = 2 * N + na + 2
        jv, jvd = nx - 2, nx - 1
        iu, iv = 2 * np.arange(N), 2 * np.arange(N) + 1
        A = np.zeros((nx, nx))
        A[iu, iv] = 1.0
        A[np.ix_(iv, iu)] = Minv @ c["Ku"]
        A[np.ix_(iv, iv)] = Minv @ c["Cu"]
        A[iv, 2 * N:2 * N + na] = Minv @ (q * c["D"])
        A[iv, jv] = Minv @ (q * A0[:, N])
        A[iv, jvd] = Minv @ (q * bu * A1[:, N])
        A[2 * N:2 * N + na, 2 * N:2 * N + na] = np.diag(c["R"] / bu)
        A[2 * N:2 * N + na, iv] = c["E"][:, :N]
        A[2 * N:2 * N + na, jvd] = c["E"][:, N]
        A[jv, jvd] = 1.0
        B = np.zeros((nx, 1 + N))
        B[iv, 0] = Minv @ (q * bu * bu * A2[:, N])
        B[jvd, 0] = 1.0
        B[iv, 1:] = Minv * s.alpha
        kind = s.sensor
        Hs = s.Hs
        if kind == "displacement":
            Cz, Dz = Hs @ np.eye(nx)[iu], np.zeros((Hs.shape[0], 1 + N))
        elif kind == "velocity":
            Cz, Dz = Hs @ np.eye(nx)[iv], np.zeros((Hs.shape[0], 1 + N))
        elif kind == "acceleration":
            Cz, Dz = Hs @ A[iv], Hs @ B[iv]
        else:                                                   # "state": Hs x_s
            Cz, Dz = Hs @ np.eye(nx)[:2 * N], np.zeros((Hs.shape[0], 1 + N))
        C = np.vstack([np.eye(nx)[iu], Cz])
        D = np.vstack([np.zeros((N, 1 + N)), Dz])
        states = ([x for i in range(N) for x in (f"u[{i}]", f"udot[{i}]")]
                  + [f"xa[{j}]" for j in range(na)] + ["v", "vdot"])
        return control.ss(A, B, C, D, states=states,
                          inputs=["vddot"] + [f"w[{i}]" for i in range(N)],
                          outputs=[f"u[{i}]" for i in range(N)]
                          + [f"zm[{j}]" for j in range(s.n_sensors)],
                          name=f"Sigma_AE_RFA_U{U:g}".replace(".", "p"))

    # -- bridge to eq. 5-15 -----------------------------------------------------------------
    def frozen_sigma_f(self, U_f: float) -> control.StateSpace:
        """Σf (eq. 5) of the RFA aerodynamics frozen at airspeed ``U_f``.

        ``y = Q(s b / U_f) [u; v]`` in the normalisation of eq. (6): with this
        :attr:`structure`, ``AeroelasticSystem.from_parts(sigma_f, structure)`` is ΣAE(V)
        of eq. (8) with ``V = U / U_ref``, equal to :meth:`state_matrix` at ``U_f`` (up to
        Roger's flap-only lag states) and an approximation elsewhere (module docstring);
        :func:`build_lft` about ``V_f = U_f / U_ref`` is the LFT of eq. 10-15.

        Realisation: ``Af = (U_f / b) diag(R)``, ``Bf = E``, ``Cf = (U_f / b) D diag(R)``,
        ``Df = A0 + D E``.

        Parameters
        ----------
        U_f : float
            Airspeed [m/s] of the freeze (the flutter speed for the LFT).

        Returns
        -------
        control.StateSpace
            Continuous, inputs ``[u_1..u_N(, v)]``, outputs ``y_1..y_N``.

        Raises
        ------
        ConfigError
            The RFA has ``A1`` or ``A2`` terms (``poly_order > 0``): eq. 5 has no derivative
            feed-through; refit with ``poly_order=0``.
        """
        r = self.rfa
        if r.poly_order > 0:
            raise ConfigError(
                f"Σf of eq. 5 is proper (inputs u, v only) but this RFA has poly_order = "
                f"{r.poly_order} (A1 p{' + A2 p^2' if r.poly_order > 1 else ''} terms); refit "
                "with poly_order=0 for the frozen Σf and the LFT")
        U_f = self._check_U(U_f)
        rate = U_f / r.b
        N, M = r.n_modes, r.n_inputs
        Af = np.diag(rate * r.R)
        Cf = rate * r.D * r.R[None, :]
        Df = r.A[0] + r.D @ r.E
        inputs = [f"u[{i}]" for i in range(N)] + (["v"] if M > N else [])
        return control.ss(Af, r.E, Cf, Df, inputs=inputs,
                          outputs=[f"y[{i}]" for i in range(N)],
                          name=f"Sigma_f_RFA_U{U_f:g}".replace(".", "p"))
