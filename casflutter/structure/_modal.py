"""Modal structural dynamics Σs (paper eq. 6-7).

Each of the first N structural modes obeys (eq. 6)

    ü_i + 2 ζ_i ω_i u̇_i + ω_i² u_i = α (V² y_i + w_i),

with modal displacement output ``u = Cs x_s`` and measured output ``zm``.

State ordering
--------------
The structural state is ``x_s = [u_1, u̇_1, u_2, u̇_2, ..., u_N, u̇_N]``: one block of two
states per mode (:attr:`ModalStructure.layout`).  This is the ordering of eq. 7, where
``As = diag(A_s^i)`` and ``Bs = diag(B_s^i)`` are block diagonal, so each mode's states are
contiguous and the matrices read as in the paper.  The truth simulators keep their own
full-order state (``[u, u', lag states]``); neither ordering leaks to callers:
:meth:`ModalStructure.displaced_state` and :meth:`ModalStructure.modal_state` (and the
truths' methods of the same names) return a :class:`~casflutter.structure.ModalState`, which
every simulation puts where its own model keeps it (:mod:`casflutter.structure._state`).

Sensors
-------
The paper writes ``zm = Hs x_s``.  Accelerometers, however, measure acceleration, which
is not a function of the state alone: ``ü = -ω² u - 2ζω u̇ + α (V² y + w)`` depends on the
aerodynamic force and the disturbance.  :class:`ModalStructure` therefore takes the
sensor rows in *modal* coordinates, ``Hs`` of shape ``(n_sensors, N)`` (mode-shape values
at the sensor locations, from FEA), and a ``sensor`` kind:

``"acceleration"`` (default)
    ``zm = Hs ü`` computed exactly, including the feed-through from ``V² y + w``.
``"velocity"`` / ``"displacement"``
    ``zm = Hs u̇`` / ``zm = Hs u``.
``"state"``
    the paper's literal ``zm = Hs x_s`` with ``Hs`` of shape ``(n_sensors, 2N)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError, DimensionError
from ._speed import SpeedConvention
from ._state import ModalLayout, ModalStates

__all__ = ["ModalStructure", "SENSOR_KINDS", "check_sensor_rows"]

#: Allowed values of ``ModalStructure.sensor``.
SENSOR_KINDS = ("acceleration", "velocity", "displacement", "state")


def check_sensor_rows(rows, n_modes: int, *, key: str = "sensors.rows",
                      problem: str = "the problem") -> list[list[float]]:
    """Check sensor rows ``Hs`` (eq. 7) given as nested lists: ``(n_sensors, n_modes)``.

    Parameters
    ----------
    rows : sequence of sequences of float
        One row per sensor, one number per mode.
    n_modes : int
        Number of modes ``N`` of the problem.
    key : str
        Name of the setting, for the error message.
    problem : str
        Name of the problem, for the error message.

    Returns
    -------
    list of list of float
        The rows as floats.

    Raises
    ------
    ConfigError
        Not a non-empty list of lists, a row whose length is not ``n_modes``, an entry that
        is not a finite number, or a row of zeros (a sensor that sees no mode).
    """
    if isinstance(rows, np.ndarray):
        rows = rows.tolist()
    want = (f"give a list of rows, one per sensor, each a list of {n_modes} numbers (one per "
            f"mode of {problem}), e.g. {key} = [[{', '.join(['0.1'] * n_modes)}]]")
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__len__") or len(rows) == 0:
        raise ConfigError(f"{key} = {rows!r}: {want}")
    out = []
    for i, row in enumerate(rows):
        if isinstance(row, (str, bytes)) or not hasattr(row, "__len__"):
            raise ConfigError(f"{key}[{i}] = {row!r} is not a list: {want}")
        if len(row) != n_modes:
            raise ConfigError(f"{key}[{i}] has {len(row)} entries, {problem} has {n_modes} "
                              f"modes: {want}")
        vals = []
        for j, x in enumerate(row):
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                raise ConfigError(f"{key}[{i}][{j}] = {x!r}: must be a finite number")
            vals.append(float(x))
        if not any(vals):
            raise ConfigError(f"{key}[{i}] is all zeros: a sensor that sees no mode; drop the "
                              "row")
        out.append(vals)
    return out


@dataclass(frozen=True)
class ModalStructure(ModalStates):
    """N-mode structural model Σs of eq. 6-7, with its sensors and names.

    Parameters
    ----------
    omega : array_like, shape (N,)
        In-vacuo natural frequencies ω_i [rad per time unit], all > 0.
    zeta : array_like, shape (N,)
        Damping ratios ζ_i (≥ 0).
    alpha : float
        Flow-condition constant α of eq. 6 (scales the generalised force ``V² y``).
    Hs : array_like, shape (n_sensors, N) or (n_sensors, 2N)
        Sensor rows in modal coordinates.  Shape ``(n_sensors, N)`` for the kinds
        ``"acceleration"``, ``"velocity"``, ``"displacement"``; ``(n_sensors, 2N)`` for
        ``"state"``.  ``None`` means one sensor per mode (identity).
    sensor : str
        One of :data:`SENSOR_KINDS`; see the module docstring.
    mode_names : tuple of str, optional
        A name per mode (default ``"mode 1"``, ...).
    sensor_names : tuple of str, optional
        A name per sensor row (default ``"zm[0]"``, ...).
    shapes : array_like, shape (n, N), optional
        Mode shapes ``Phi`` in physical (or assumed-mode) coordinates ``x = Phi u``
        (default: the identity, the modes themselves).
    coordinate_names : tuple of str, optional
        Names of the ``n`` physical coordinates (default: the mode names).
    speed : SpeedConvention
        What the speed index ``V`` is, the unit of time of ``omega``, and the airspeed and
        dynamic pressure when the problem knows them (default: ``V`` in seconds, no
        airspeed scale).

    Attributes
    ----------
    n_modes : int
        Number of modes ``N`` (from ``omega``).
    time_unit : str
        The unit of time of ``omega`` (``speed.time_unit``).
    speed_index : str
        What the speed index ``V`` is (``speed.definition``).

    Raises
    ------
    DimensionError
        ``omega``/``zeta``/``Hs``/``shapes``/names of inconsistent sizes.
    ConfigError
        Non-positive or non-finite frequencies, negative damping, unknown sensor kind.
    """

    __repr__ = result_repr

    omega: np.ndarray
    zeta: np.ndarray
    alpha: float = 1.0
    Hs: np.ndarray | None = None
    sensor: str = "acceleration"
    mode_names: tuple = ()
    sensor_names: tuple = ()
    shapes: np.ndarray | None = None
    coordinate_names: tuple = ()
    speed: SpeedConvention = field(default_factory=SpeedConvention)
    n_modes: int = field(init=False)

    def __post_init__(self):
        omega = np.atleast_1d(np.asarray(self.omega, dtype=float))
        zeta = np.atleast_1d(np.asarray(self.zeta, dtype=float))
        if omega.ndim != 1 or zeta.shape != omega.shape:
            raise DimensionError(
                f"omega {omega.shape} and zeta {zeta.shape} must be 1-D of the same length N; "
                "give one natural frequency and one damping ratio per mode")
        if np.any(~np.isfinite(omega)) or np.any(omega <= 0):
            raise ConfigError(f"omega must be finite and > 0, got {omega}")
        if np.any(~np.isfinite(zeta)) or np.any(zeta < 0):
            raise ConfigError(f"zeta must be finite and >= 0, got {zeta}")
        if not np.isfinite(self.alpha):
            raise ConfigError(f"alpha must be finite, got {self.alpha}")
        if not isinstance(self.speed, SpeedConvention):
            raise ConfigError(f"speed must be a SpeedConvention, got {type(self.speed).__name__}")
        if self.sensor not in SENSOR_KINDS:
            raise ConfigError(f"sensor={self.sensor!r} is not allowed; choose one of {SENSOR_KINDS}")
        n = omega.size
        ncol = 2 * n if self.sensor == "state" else n
        Hs = np.eye(n, ncol) if self.Hs is None else np.atleast_2d(np.asarray(self.Hs, dtype=float))
        if Hs.ndim != 2 or Hs.shape[1] != ncol:
            raise DimensionError(
                f"Hs has shape {Hs.shape} but sensor={self.sensor!r} with N={n} modes needs "
                f"(n_sensors, {ncol}); give modal sensor rows (n_sensors, N), or (n_sensors, 2N) "
                "with sensor='state'")
        shapes = np.eye(n) if self.shapes is None else np.atleast_2d(np.asarray(self.shapes,
                                                                                  dtype=float))
        if shapes.ndim != 2 or shapes.shape[1] != n:
            raise DimensionError(f"shapes has shape {shapes.shape}; it needs one column per "
                                 f"mode ({n})")
        modes = tuple(self.mode_names) or tuple(f"mode {i + 1}" for i in range(n))
        sensors = tuple(self.sensor_names) or tuple(f"zm[{j}]" for j in range(Hs.shape[0]))
        coords = tuple(self.coordinate_names) or (modes if shapes.shape[0] == n else tuple(
            f"x{k + 1}" for k in range(shapes.shape[0])))
        for what, names, size in (("mode_names", modes, n), ("sensor_names", sensors, Hs.shape[0]),
                                  ("coordinate_names", coords, shapes.shape[0])):
            if len(names) != size:
                raise DimensionError(f"{what} has {len(names)} names for {size} entries")
        for name, value in (("omega", omega), ("zeta", zeta), ("alpha", float(self.alpha)),
                            ("Hs", Hs), ("shapes", shapes), ("mode_names", modes),
                            ("sensor_names", sensors), ("coordinate_names", coords),
                            ("n_modes", n)):
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ sensors and states
    def with_sensors(self, rows=None, kind: str | None = None, names=None) -> "ModalStructure":
        """The same structure read by other sensors.

        Parameters
        ----------
        rows : array_like, shape (n_sensors, N), optional
            New sensor rows ``Hs`` (checked by :func:`check_sensor_rows`); ``None`` or empty:
            keep the current rows.
        kind : str, optional
            New sensor kind (:data:`SENSOR_KINDS`); default: keep.
        names : sequence of str, optional
            Sensor names (default: the current ones when the rows are kept, else generic).

        Returns
        -------
        ModalStructure

        Raises
        ------
        ConfigError
            Rows of the wrong length, non-finite entries, a row of zeros, an unknown kind.
        """
        changes: dict = {}
        if rows is not None and len(rows) > 0:
            checked = check_sensor_rows(rows, self.n_modes, key="sensor rows")
            changes.update(Hs=np.array(checked, dtype=float), sensor_names=tuple(names or ()))
        elif names is not None:
            changes["sensor_names"] = tuple(names)
        if kind is not None:
            changes["sensor"] = kind
        return replace(self, **changes) if changes else self

    @property
    def time_unit(self) -> str:
        """The unit of time of ``omega`` (``speed.time_unit``)."""
        return self.speed.time_unit

    @property
    def speed_index(self) -> str:
        """What the speed index ``V`` is (``speed.definition``)."""
        return self.speed.definition

    @property
    def layout(self) -> ModalLayout:
        """Where ``x_s`` keeps each mode: ``[u_1, u̇_1, u_2, u̇_2, ...]`` (eq. 7)."""
        return ModalLayout(self.n_modes, interleaved=True)

    @property
    def mode_states(self) -> list[np.ndarray]:
        """State indices ``[u_i, u̇_i]`` of each mode in ``x_s`` (for eigenvector
        participation)."""
        return self.layout.mode_states

    # ------------------------------------------------------------------ matrices
    @property
    def n_states(self) -> int:
        """Number of structural states, 2N."""
        return 2 * self.n_modes

    @property
    def n_sensors(self) -> int:
        """Number of measured outputs (rows of ``zm``)."""
        return self.Hs.shape[0]

    @property
    def As(self) -> np.ndarray:
        """Block-diagonal ``As = diag([[0, 1], [-ω_i², -2ζ_i ω_i]])`` (eq. 7)."""
        A = np.zeros((self.n_states, self.n_states))
        for i, (w, z) in enumerate(zip(self.omega, self.zeta)):
            A[2 * i, 2 * i + 1] = 1.0
            A[2 * i + 1, 2 * i] = -w * w
            A[2 * i + 1, 2 * i + 1] = -2.0 * z * w
        return A

    @property
    def Bs(self) -> np.ndarray:
        """Block-diagonal ``Bs = diag([0, α]ᵀ)`` (eq. 7), shape (2N, N)."""
        B = np.zeros((self.n_states, self.n_modes))
        B[1::2, :] = self.alpha * np.eye(self.n_modes)
        return B

    @property
    def Cs(self) -> np.ndarray:
        """Displacement selector, ``u = Cs x_s``, shape (N, 2N)."""
        C = np.zeros((self.n_modes, self.n_states))
        C[np.arange(self.n_modes), 2 * np.arange(self.n_modes)] = 1.0
        return C

    @property
    def Cv(self) -> np.ndarray:
        """Velocity selector, ``u̇ = Cv x_s``, shape (N, 2N)."""
        C = np.zeros((self.n_modes, self.n_states))
        C[np.arange(self.n_modes), 2 * np.arange(self.n_modes) + 1] = 1.0
        return C

    def sensor_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """Sensor output as ``zm = Hx x_s + Hf (V² y + w)``.

        Returns
        -------
        Hx : ndarray, shape (n_sensors, 2N)
            State rows.  For accelerometers ``Hs Cv As``.
        Hf : ndarray, shape (n_sensors, N)
            Rows multiplying the structural forcing ``V² y + w``; zero unless
            ``sensor == "acceleration"``, where it is ``Hs Cv Bs = α Hs``.
        """
        if self.sensor == "state":
            Hx = self.Hs.copy()
        elif self.sensor == "displacement":
            Hx = self.Hs @ self.Cs
        elif self.sensor == "velocity":
            Hx = self.Hs @ self.Cv
        else:
            Hx = self.Hs @ self.Cv @ self.As
        if self.sensor == "acceleration":
            Hf = self.Hs @ self.Cv @ self.Bs
        else:
            Hf = np.zeros((self.n_sensors, self.n_modes))
        return Hx, Hf

    def eigenvalues(self) -> np.ndarray:
        """Analytic structural poles ``-ζω ± jω√(1-ζ²)`` (pairs, mode by mode).

        Returns
        -------
        ndarray, shape (2N,), complex
        """
        out = []
        for w, z in zip(self.omega, self.zeta):
            r = np.sqrt(complex(1.0 - z * z))
            out += [-z * w + 1j * w * r, -z * w - 1j * w * r]
        return np.asarray(out)

    def statespace(self, V: float = 0.0) -> control.StateSpace:
        """Σs at speed index V as a ``control.StateSpace`` (eq. 7).

        Parameters
        ----------
        V : float
            Speed index: the generalised forces ``y`` enter scaled by ``V²``.

        Returns
        -------
        control.StateSpace
            Inputs ``[y_1..y_N, w_1..w_N]`` (generalised forces, disturbance), outputs
            ``[u_1..u_N, zm_1..zm_m]``, states ``[u_1, u̇_1, ...]``.  The forcing enters as
            ``Bs (V² y + w)``.  With accelerometers the ``zm`` rows have the feed-through
            ``α Hs (V² y + w)``.
        """
        n = self.n_modes
        V2 = float(V) ** 2
        Hx, Hf = self.sensor_matrices()
        B = np.hstack([V2 * self.Bs, self.Bs])
        C = np.vstack([self.Cs, Hx])
        D = np.zeros((n + self.n_sensors, 2 * n))
        D[n:, :n] = V2 * Hf
        D[n:, n:] = Hf
        return control.ss(
            self.As, B, C, D,
            inputs=[f"y[{i}]" for i in range(n)] + [f"w[{i}]" for i in range(n)],
            outputs=[f"u[{i}]" for i in range(n)] + [f"zm[{j}]" for j in range(self.n_sensors)],
            states=[s for i in range(n) for s in (f"u[{i}]", f"udot[{i}]")],
            name="Sigma_s")
