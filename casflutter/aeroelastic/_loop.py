"""The linear aeroelastic loop ΣAE(V) (paper eq. 8-9).

Σf (eq. 5) is the continuous linearised aerodynamic ROM,

    ẋf = Af xf + Bf u + bf v,     y = Cf xf + Df u + df v,

given as a continuous ``control.StateSpace`` with N outputs ``y`` and inputs
``[u_1..u_N, v]`` (the flap column may be absent).  Closing it with Σs (eq. 7) gives

    Â(V)  = [[As + V² Bs Df Cs, V² Bs Cf], [Bf Cs, Af]]       (eq. 8a)
    B̂1    = [Bs; 0],   B̂2(V) = [V² Bs df; bf]
    zm    = C2(V) x + D21 w + D22(V) v                          (eq. 8b, 9)

where for state sensors ``C2 = [Hs 0]`` and ``D21 = D22 = 0`` exactly as in the paper;
for accelerometers the zm rows carry the aerodynamic and disturbance feed-through
(see :mod:`casflutter.structure`).
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, replace

import control
import numpy as np

from .._format import result_repr
from .._linalg import spectral_abscissa
from ..errors import ConfigError, DimensionError
from ..structure import ModalStructure
from ._family import FamilySignals, PlantFamily

__all__ = ["AeroelasticSystem", "AeroelasticLoop", "LoopFamily", "ParametricSystem",
           "ServoSystem", "aeroelastic_loop", "check_servo",
           "split_sigma_f"]


def split_sigma_f(sigma_f, n_modes: int | None = None):
    """Split Σf into ``(Af, Bf, bf, Cf, Df, df)`` following eq. 5.

    Parameters
    ----------
    sigma_f : control.StateSpace
        Continuous Σf with N outputs and N or N+1 inputs ``[u, v]``.
    n_modes : int, optional
        Expected N (from Σs); a mismatch raises :class:`DimensionError` naming both.

    Returns
    -------
    tuple of ndarray
        ``Af (nf, nf), Bf (nf, N), bf (nf,), Cf (N, nf), Df (N, N), df (N,)``; ``bf`` and
        ``df`` are zero when Σf has no flap column.
    """
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in
                  (sigma_f.A, sigma_f.B, sigma_f.C, sigma_f.D))
    dt = getattr(sigma_f, "dt", 0)
    if dt not in (0, None) and dt is not False:
        raise DimensionError(
            f"Σf must be continuous-time (dt=0) but has dt={dt}; convert the discrete ROM with "
            "Tustin's transform (casflutter.realize) first")
    nf = A.shape[0] if A.size else 0
    N = C.shape[0]
    if n_modes is not None and N != n_modes:
        raise DimensionError(
            f"Σf has {N} outputs (generalised forces) but Σs has {n_modes} modes; "
            "they must be equal: identify the ROM on the same modes as the structure")
    m = D.shape[1]
    if m not in (N, N + 1):
        raise DimensionError(
            f"Σf has {m} inputs but {N} outputs; inputs must be the N={N} modal displacements, "
            "optionally followed by the flap v")
    if nf == 0:
        A = np.zeros((0, 0))
        B = np.zeros((0, m))
        C = np.zeros((N, 0))
    Bf, Df = B[:, :N], D[:, :N]
    bf = B[:, N] if m == N + 1 else np.zeros(nf)
    df = D[:, N] if m == N + 1 else np.zeros(N)
    return A, Bf, bf, C, Df, df


@dataclass(frozen=True)
class AeroelasticLoop:
    """ΣAE at one speed index V (eq. 9): ``ẋ = A x + B1 w + B2 v``, ``zm = C2 x + D21 w + D22 v``.

    Attributes
    ----------
    V : float
        Speed index.
    A, B1, B2, C2, D21, D22 : ndarray
        Â(V), B̂1, B̂2(V), and the sensor rows (D21, D22 zero for state sensors).
    Cu : ndarray
        Modal displacement rows ``u = Cu x``.
    n_modes, n_f : int
        N and the order of Σf; the state is ``x = (x_s, x_f)``.
    """

    __repr__ = result_repr

    V: float
    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C2: np.ndarray
    D21: np.ndarray
    D22: np.ndarray
    Cu: np.ndarray
    n_modes: int
    n_f: int

    def statespace(self, include_modal: bool = False) -> control.StateSpace:
        """ΣAE as ``control.StateSpace`` with inputs ``[w_1..w_N, v]`` and outputs ``zm``.

        Parameters
        ----------
        include_modal : bool
            Also the modal displacements ``u`` as outputs (after ``zm``).

        Returns
        -------
        control.StateSpace
        """
        C, D = self.C2, np.hstack([self.D21, self.D22[:, None]])
        outs = [f"zm[{j}]" for j in range(C.shape[0])]
        if include_modal:
            C = np.vstack([C, self.Cu])
            D = np.vstack([D, np.zeros((self.n_modes, D.shape[1]))])
            outs += [f"u[{i}]" for i in range(self.n_modes)]
        return control.ss(self.A, np.hstack([self.B1, self.B2[:, None]]), C, D,
                          inputs=[f"w[{i}]" for i in range(self.n_modes)] + ["v"],
                          outputs=outs, name="Sigma_AE")

    def flap_to_sensors(self) -> control.StateSpace:
        """The loop from the flap ``v`` to the sensors ``zm`` alone (the plant a controller
        ``v = K zm`` closes).

        Returns
        -------
        control.StateSpace
        """
        return control.ss(self.A, self.B2[:, None], self.C2, self.D22[:, None])

    def closed_loop_state_matrix(self, controller) -> np.ndarray:
        """State matrix of this loop closed with ``v = K zm`` (positive feedback, paper Fig. 3).

        An algebraic loop through ``D22 Dk`` (accelerometers with a direct flap feed-through)
        is solved exactly.

        Parameters
        ----------
        controller : control.StateSpace
            Continuous K with ``n_sensors`` inputs and one output.

        Returns
        -------
        ndarray
            The state matrix of ``(x, x_K)``.

        Raises
        ------
        DimensionError
            K does not map the sensors to the flap, or ``1 − Dk D22 = 0``.
        """
        Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in
                          (controller.A, controller.B, controller.C, controller.D))
        m = self.C2.shape[0]
        if Dk.shape != (1, m):
            raise DimensionError(
                f"the controller has {Dk.shape[1]} inputs and {Dk.shape[0]} outputs; it needs "
                f"{m} inputs (the sensors zm) and 1 output (the flap v)")
        nk = Ak.shape[0] if Ak.size else 0
        if nk == 0:
            Ak, Bk, Ck = np.zeros((0, 0)), np.zeros((0, m)), np.zeros((1, 0))
        if abs(1.0 - float((Dk @ self.D22)[0])) < 1e-12:
            raise DimensionError("the loop v = K zm is algebraically singular (1 - Dk D22 = 0)")
        return self.closed_loop_parts(Ak, Bk, Ck, Dk)[0]

    def closed_loop_parts(self, Ak: np.ndarray, Bk: np.ndarray, Ck: np.ndarray,
                          Dk: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
        """The closed loop of :meth:`closed_loop_state_matrix` from the controller's matrices,
        unchecked, with the pieces a gradient with respect to them needs.

        Parameters
        ----------
        Ak, Bk, Ck, Dk : ndarray
            The controller's matrices (``Ck`` of one row, ``Dk`` of shape ``(1, n_sensors)``).

        Returns
        -------
        A_cl : ndarray
            The state matrix of ``(x, x_K)``.
        s : float
            ``1 − Dk D22``, the algebraic loop's factor.
        vx : ndarray
            ``Dk C2 / s``: the flap's dependence on the loop's state.
        zx : ndarray
            ``C2 + D22 vx``: the sensors' dependence on the loop's state.
        """
        s = 1.0 - float((Dk @ self.D22)[0])
        # v = (Ck xk + Dk C2 x) / s
        vx = (Dk @ self.C2) / s
        B2, D22 = self.B2[:, None], self.D22[:, None]
        zx = self.C2 + D22 @ vx
        A_cl = np.block([[self.A + B2 @ vx, (B2 / s) @ Ck], [Bk @ zx, Ak + Bk @ D22 @ Ck / s]])
        return A_cl, s, vx, zx

    def with_servo(self, omega: float, zeta: float = 0.7) -> "AeroelasticLoop":
        """This loop with the flap behind a second-order servo, ``v̈ = ω² (c − v) − 2ζω v̇``.

        The controller then commands ``c`` as it would on a wind-tunnel model (the truth's
        :class:`~casflutter.aeroelastic.TruthLoop` puts its flap behind the same servo), and the
        flap position ``v`` becomes a state: the sensors' flap feed-through ``D22`` moves into
        ``C2``, so the returned loop is strictly proper in ``c``.

        Parameters
        ----------
        omega : float
            Servo natural frequency [rad per time unit] (> 0).
        zeta : float
            Servo damping ratio (>= 0).

        Returns
        -------
        AeroelasticLoop
            States ``(x, v, v̇)``; ``n_f`` counts the two servo states.

        Raises
        ------
        ConfigError
            A frequency or damping out of range.
        """
        check_servo(omega, zeta)
        n, m = self.A.shape[0], self.C2.shape[0]
        w2 = float(omega) ** 2
        A = np.zeros((n + 2, n + 2))
        A[:n, :n], A[:n, n] = self.A, self.B2
        A[n, n + 1] = 1.0
        A[n + 1, n], A[n + 1, n + 1] = -w2, -2.0 * float(zeta) * float(omega)
        B2 = np.zeros(n + 2)
        B2[n + 1] = w2
        C2 = np.hstack([self.C2, self.D22[:, None], np.zeros((m, 1))])
        return AeroelasticLoop(self.V, A, np.vstack([self.B1, np.zeros((2, self.B1.shape[1]))]),
                               B2, C2, self.D21, np.zeros(m),
                               np.hstack([self.Cu, np.zeros((self.n_modes, 2))]),
                               self.n_modes, self.n_f + 2)

    def poles(self) -> np.ndarray:
        """Eigenvalues of Â(V).

        Returns
        -------
        ndarray, complex
        """
        return np.linalg.eigvals(self.A)


def check_servo(omega: float, zeta: float, names: tuple = ("servo omega", "zeta")) -> None:
    """Raise :class:`~casflutter.errors.ConfigError` unless ``omega > 0`` and ``zeta >= 0``
    are finite (a second-order flap servo, ``v̈ = ω² (c − v) − 2ζω v̇``); ``names`` are the
    caller's names of the two, for the message."""
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(zeta) and zeta >= 0):
        raise ConfigError(f"{names[0]} = {omega!r} must be > 0 and {names[1]} = {zeta!r} >= 0")


class LoopFamily(PlantFamily):
    """A linear aeroelastic loop with one flap at every speed index: the
    :class:`~casflutter.aeroelastic.PlantFamily` of the paper's ΣAE(V) (eq. 8-9).

    Its plant has the modal disturbances ``w[0] .. w[N-1]`` and the flap ``v`` (or the
    servo's command) as inputs and the sensors ``zm`` (named after the structure's sensors)
    as outputs; a controller closes ``v = K zm`` (positive feedback, paper Fig. 3).  A family
    defines :meth:`loop` and :meth:`modal_structure`; the state matrices follow from
    :meth:`loop` (a family may compute :meth:`state_matrix` more directly).
    """

    speed_degree = 2    # strip theory: the lags scale with V, the forces with V²

    @property
    def name(self) -> str:
        """The class name (for messages)."""
        return type(self).__name__

    def modal_structure(self) -> ModalStructure:
        """Σs: the modes, the sensors (their rows, kind and names) and the units.

        Returns
        -------
        ModalStructure
        """
        raise NotImplementedError

    @property
    def time_unit(self) -> str:
        """The structure's unit of time."""
        return str(self.modal_structure().time_unit)

    @property
    def signals(self) -> FamilySignals:
        """Inputs ``w[0] .. w[N-1]`` (disturbances) and ``v`` (the control), outputs the
        sensors (the measurements)."""
        s = self.modal_structure()
        return FamilySignals([f"w[{i}]" for i in range(s.n_modes)] + ["v"],
                             list(s.sensor_names), controls=("v",),
                             input_units=("",) * s.n_modes + ("rad",))

    def plant(self, V: float) -> control.StateSpace:
        """The loop at speed index V as a named plant (:meth:`AeroelasticLoop.statespace`);
        see :meth:`PlantFamily.plant`."""
        P, sig = self.loop(float(V)).statespace(), self.signals
        return control.ss(P.A, P.B, P.C, P.D, inputs=list(sig.inputs),
                          outputs=list(sig.outputs))

    def loop(self, V: float) -> AeroelasticLoop:
        """The loop at speed index V.

        Parameters
        ----------
        V : float
            Speed index, inside :attr:`speed_range`.

        Returns
        -------
        AeroelasticLoop
        """
        raise NotImplementedError

    def state_matrix(self, V: float) -> np.ndarray:
        """The open-loop state matrix of :meth:`loop` at speed index V; see
        :meth:`PlantFamily.state_matrix`."""
        return self.loop(V).A

    def closed_loop_state_matrix(self, V: float, controller) -> np.ndarray:
        """State matrix at V closed with ``v = K zm`` (positive feedback, paper Fig. 3); see
        :meth:`AeroelasticLoop.closed_loop_state_matrix`.

        Parameters
        ----------
        V : float
            Speed index.
        controller : control.StateSpace
            Continuous K with ``n_sensors`` inputs and one output (the flap, or the servo's
            command for a family with a servo).

        Returns
        -------
        ndarray
            The state matrix of ``(x, x_K)``.
        """
        return self.loop(V).closed_loop_state_matrix(controller)


@dataclass(frozen=True)
class AeroelasticSystem(LoopFamily):
    """Σf and Σs together, giving ΣAE(V) at any speed index (eq. 8-9).

    Use :func:`AeroelasticSystem.from_parts` (or :func:`aeroelastic_loop`) to build it
    from a ``control.StateSpace`` Σf and a :class:`ModalStructure`.

    Attributes
    ----------
    structure : ModalStructure
        Σs.
    Af, Bf, bf, Cf, Df, df : ndarray
        The blocks of Σf (eq. 5).
    convective_V0 : float, optional
        The speed index at which Σf was identified, to scale its time with the speed:
        ``Σf(s; V) = Σf(s V0 / V)``, i.e. ``Af, Bf, bf`` times ``V / V0`` in eq. 8.  The
        aerodynamics of a wing in incompressible flow depend on the reduced frequency
        ``ω b / U``, so their lags speed up with V; eq. 8 as the paper writes it (``None``,
        the default) scales only the forces by ``V²`` and keeps the lags of ``V0``.  With the
        scaling, ΣAE(V) is a quadratic polynomial in V (the lags ∝ V, the forces ∝ V²), and
        the paper's LFT in ``V²`` (eq. 14) describes it only near its nominal speed
        (:func:`build_lft` uses :meth:`frozen_at` that speed).

    Notes
    -----
    With ``convective_V0`` set, eq. 8a reads
    ``Â(V) = [[As + V² Bs Df Cs, V² Bs Cf], [(V/V0) Bf Cs, (V/V0) Af]]`` and
    ``B̂2(V) = [V² Bs df; (V/V0) bf]``.
    """

    __repr__ = result_repr

    structure: ModalStructure
    Af: np.ndarray
    Bf: np.ndarray
    bf: np.ndarray
    Cf: np.ndarray
    Df: np.ndarray
    df: np.ndarray
    convective_V0: float | None = None

    def __post_init__(self):
        V0 = self.convective_V0
        if V0 is not None and not (isinstance(V0, numbers.Real) and not isinstance(V0, bool)
                                   and math.isfinite(V0) and V0 > 0):
            raise ConfigError(f"convective_V0 = {V0!r}: the identification speed index of Σf "
                              "(> 0), or None for eq. 8 without time scaling")

    def lag_scale(self, V: float) -> float:
        """The factor on ``Af, Bf, bf`` at speed index V: ``V / convective_V0``, or 1.

        Parameters
        ----------
        V : float
            Speed index at which the loop is closed.

        Returns
        -------
        float
        """
        return 1.0 if self.convective_V0 is None else float(V) / float(self.convective_V0)

    def frozen_at(self, V: float) -> "AeroelasticSystem":
        """This system with Σf's time scale held at that of speed index V (eq. 8 as the paper
        writes it, Σf identified at V): the same loop at V, the forces alone scaled by V²
        elsewhere.  Without ``convective_V0`` the system itself.

        Parameters
        ----------
        V : float
            The speed index (> 0) whose time scale Σf keeps.

        Returns
        -------
        AeroelasticSystem
            ``convective_V0`` None; ``loop(V)`` equals this system's ``loop(V)``.
        """
        if self.convective_V0 is None:
            return self
        r = self.lag_scale(V)
        if not r > 0:
            raise ConfigError(f"V = {V!r}: freezing the ROM's time scale needs a speed > 0")
        return replace(self, Af=r * self.Af, Bf=r * self.Bf, bf=r * self.bf,
                       convective_V0=None)

    @classmethod
    def from_parts(cls, sigma_f, structure: ModalStructure, *, warn_unstable: bool = True,
                   convective_V0: float | None = None) -> "AeroelasticSystem":
        """Build from Σf (continuous ``control.StateSpace``) and Σs.

        Parameters
        ----------
        sigma_f : control.StateSpace
            Continuous Σf with N outputs and inputs ``[u_1..u_N(, v)]``.
        structure : ModalStructure
            Σs (a truth's :meth:`modal_structure` goes in as it is).
        warn_unstable : bool
            Warn when Σf is unstable on its own.
        convective_V0 : float, optional
            Scale Σf's time with the speed from this identification speed index (class
            attribute ``convective_V0``).

        Returns
        -------
        AeroelasticSystem

        Raises
        ------
        DimensionError
            When Σf's outputs do not match Σs's modes (both named), Σf is discrete, or
            ``structure`` is not a :class:`ModalStructure`.

        Warns
        -----
        RuntimeWarning
            When Σf (the ROM) is unstable on its own, i.e. ΣAE is unstable at V = 0.
        """
        if not isinstance(structure, ModalStructure):
            raise DimensionError(f"structure must be a casflutter.structure.ModalStructure "
                                 f"(Σs), got {type(structure).__name__}")
        parts = split_sigma_f(sigma_f, structure.n_modes)
        sys = cls(structure, *parts, convective_V0=convective_V0)
        if warn_unstable and not sys.rom_stable:
            warnings.warn(
                f"Σf is unstable on its own (spectral abscissa {sys.rom_spectral_abscissa:.3g} > 0), "
                "so ΣAE is unstable already at V = 0; flutter results are meaningless until the "
                "ROM is re-identified or stabilised", RuntimeWarning, stacklevel=2)
        return sys

    @property
    def n_modes(self) -> int:
        """N."""
        return self.structure.n_modes

    @property
    def n_f(self) -> int:
        """Order of Σf."""
        return self.Af.shape[0]

    @property
    def n_states(self) -> int:
        """Order of ΣAE, 2N + nf."""
        return self.structure.n_states + self.n_f

    @property
    def rom_spectral_abscissa(self) -> float:
        """max Re λ(Af) (−inf for a static Σf)."""
        return spectral_abscissa(self.Af)

    @property
    def rom_stable(self) -> bool:
        """True when Σf alone is asymptotically stable."""
        return self.rom_spectral_abscissa < 0.0

    @property
    def mode_states(self) -> list[np.ndarray]:
        """State indices ``[u_i, u̇_i]`` of each structural mode in ΣAE's state ``(x_s, x_f)``
        (for eigenvector participation)."""
        return self.structure.mode_states

    def state_matrix(self, V: float) -> np.ndarray:
        """Â(V) of eq. 8a, shape ``(2N + nf, 2N + nf)``; see :meth:`PlantFamily.state_matrix`."""
        s = self.structure
        V2, r = float(V) ** 2, self.lag_scale(V)
        As, Bs, Cs = s.As, s.Bs, s.Cs
        top = np.hstack([As + V2 * Bs @ self.Df @ Cs, V2 * Bs @ self.Cf])
        bot = np.hstack([r * self.Bf @ Cs, r * self.Af])
        return np.vstack([top, bot])

    def modal_structure(self) -> ModalStructure:
        """Σs (the attribute ``structure``); see :meth:`LoopFamily.modal_structure`."""
        return self.structure

    def with_servo(self, omega: float, zeta: float = 0.7) -> "ServoSystem":
        """ΣAE(V) with the flap behind a second-order servo at every speed (what a wind-tunnel
        model has, and :class:`~casflutter.aeroelastic.TruthLoop` puts in front of the truth).

        Parameters
        ----------
        omega, zeta : float
            The servo's natural frequency and damping ratio, as in
            :meth:`AeroelasticLoop.with_servo`.

        Returns
        -------
        ServoSystem

        Raises
        ------
        ConfigError
            A frequency or damping out of range.
        """
        check_servo(omega, zeta)
        return ServoSystem(self, omega, zeta)

    def loop(self, V: float) -> AeroelasticLoop:
        """ΣAE at speed index V (eq. 8-9), with flap input v and disturbance w; see
        :meth:`LoopFamily.loop`."""
        s = self.structure
        V2 = float(V) ** 2
        nf = self.n_f
        Bs, Cs = s.Bs, s.Cs
        A = self.state_matrix(V)
        B1 = np.vstack([Bs, np.zeros((nf, s.n_modes))])
        B2 = np.concatenate([V2 * Bs @ self.df, self.lag_scale(V) * self.bf])
        Hx, Hf = s.sensor_matrices()
        C2 = np.hstack([Hx + V2 * Hf @ self.Df @ Cs, V2 * Hf @ self.Cf])
        D21 = Hf.copy()
        D22 = V2 * Hf @ self.df
        Cu = np.hstack([Cs, np.zeros((s.n_modes, nf))])
        return AeroelasticLoop(float(V), A, B1, B2, C2, D21, D22, Cu, s.n_modes, nf)


def aeroelastic_loop(sigma_f, structure: ModalStructure, V: float) -> AeroelasticLoop:
    """ΣAE(V) (eq. 8-9) from Σf and Σs; see :class:`AeroelasticSystem`.

    Parameters
    ----------
    sigma_f : control.StateSpace
        Continuous Σf.
    structure : ModalStructure
        Σs.
    V : float
        Speed index.

    Returns
    -------
    AeroelasticLoop
    """
    return AeroelasticSystem.from_parts(sigma_f, structure).loop(V)


@dataclass(frozen=True)
class ParametricSystem(LoopFamily):
    """ΣAE(V) of a parametric ROM: Σf interpolated at the same V as the loop is closed.

    Attributes
    ----------
    rom : casflutter.realize.ParametricROM
        ROMs identified at several speeds, interpolated in V.
    structure : ModalStructure
        Σs.

    Raises
    ------
    DimensionError
        The ROMs' outputs do not match Σs's modes (both named).
    """

    __repr__ = result_repr

    rom: object
    structure: ModalStructure
    speed_degree = None    # Σf interpolated between the ROMs' speeds

    def __post_init__(self):
        N = self.rom.n_modes
        if N != self.structure.n_modes:
            raise DimensionError(f"the ROMs have {N} outputs but Σs has "
                                 f"{self.structure.n_modes} modes; they must be equal")

    def modal_structure(self) -> ModalStructure:
        """Σs (the attribute ``structure``); see :meth:`LoopFamily.modal_structure`."""
        return self.structure

    def system_at(self, V: float) -> AeroelasticSystem:
        """ΣAE with Σf of the interpolated ROM at V (control.StateSpace route).

        Parameters
        ----------
        V : float
            Speed index at which the ROMs are interpolated.

        Returns
        -------
        AeroelasticSystem
        """
        return AeroelasticSystem.from_parts(self.rom.sigma_f(V), self.structure,
                                            warn_unstable=False)

    def loop(self, V: float) -> AeroelasticLoop:
        """ΣAE at speed index V (eq. 8-9) with Σf interpolated at the same V; see
        :meth:`LoopFamily.loop`."""
        return AeroelasticSystem(self.structure, *self.rom.sigma_f_matrices(V)).loop(V)

    def state_matrix(self, V: float) -> np.ndarray:
        """Â(V) of eq. 8a with Σf interpolated at the same V; see
        :meth:`PlantFamily.state_matrix`.

        The origin mode of a branch is judged by the nearest natural frequency
        (``structure.omega``; the class has no ``mode_states``): the canonical realisation's
        states are not balanced, so eigenvector energy fractions would be dominated by the
        aerodynamic states.
        """
        return AeroelasticSystem(self.structure, *self.rom.sigma_f_matrices(V)).state_matrix(V)


@dataclass(frozen=True)
class ServoSystem(LoopFamily):
    """A loop family with the flap behind a second-order servo, ``v̈ = ω² (c − v) − 2ζω v̇``.

    Every speed's loop is the family's :meth:`AeroelasticLoop.with_servo`: the controller
    commands ``c`` and the flap position becomes a state.  It is a :class:`LoopFamily`, so the
    interval design and the verification take it as they take the truth's
    :class:`~casflutter.aeroelastic.TruthLoop`.

    Attributes
    ----------
    system : AeroelasticSystem or ParametricSystem
        The family without the servo.
    servo_omega : float
        Servo natural frequency [rad per time unit] (> 0).
    servo_zeta : float
        Servo damping ratio (>= 0).

    Raises
    ------
    ConfigError
        A frequency or damping out of range.
    """

    __repr__ = result_repr

    system: object
    servo_omega: float
    servo_zeta: float = 0.7

    def __post_init__(self):
        check_servo(self.servo_omega, self.servo_zeta, ("servo_omega", "servo_zeta"))

    def modal_structure(self) -> ModalStructure:
        """Σs of the family behind the servo; see :meth:`LoopFamily.modal_structure`."""
        return self.system.modal_structure()

    @property
    def speed_degree(self) -> int | None:
        """The degree in V of the family behind the servo (the servo does not depend on V)."""
        return self.system.speed_degree

    def loop(self, V: float) -> AeroelasticLoop:
        """The family's loop at speed index V, flap behind the servo (states ``(x, v, v̇)``);
        see :meth:`LoopFamily.loop`."""
        return self.system.loop(V).with_servo(self.servo_omega, self.servo_zeta)
