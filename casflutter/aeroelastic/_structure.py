"""Modal structural dynamics Σs (paper eq. 6-7).

Each of the first N structural modes obeys (eq. 6)

    ü_i + 2 ζ_i ω_i u̇_i + ω_i² u_i = α (V² y_i + w_i),

with modal state ``x_s = [u_1, u̇_1, u_2, u̇_2, ..., u_N, u̇_N]`` (the block-diagonal
ordering of eq. 7), modal displacement output ``u = Cs x_s`` and measured output ``zm``.

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

from dataclasses import dataclass, field

import control
import numpy as np

from ..errors import ConfigError, DimensionError

__all__ = ["ModalStructure", "SENSOR_KINDS"]

#: Allowed values of ``ModalStructure.sensor``.
SENSOR_KINDS = ("acceleration", "velocity", "displacement", "state")


@dataclass(frozen=True)
class ModalStructure:
    """N-mode structural model Σs of eq. 6-7.

    Parameters
    ----------
    omega : array_like, shape (N,)
        Natural frequencies ω_i [rad/s], all > 0.
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
    """

    omega: np.ndarray
    zeta: np.ndarray
    alpha: float = 1.0
    Hs: np.ndarray | None = None
    sensor: str = "acceleration"
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
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "zeta", zeta)
        object.__setattr__(self, "alpha", float(self.alpha))
        object.__setattr__(self, "Hs", Hs)
        object.__setattr__(self, "n_modes", n)

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

    def sensor_rows(self) -> tuple[np.ndarray, np.ndarray]:
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
        """Analytic structural poles ``-ζω ± jω√(1-ζ²)`` (pairs, mode by mode)."""
        out = []
        for w, z in zip(self.omega, self.zeta):
            r = np.sqrt(complex(1.0 - z * z))
            out += [-z * w + 1j * w * r, -z * w - 1j * w * r]
        return np.asarray(out)

    def statespace(self, V: float = 0.0) -> control.StateSpace:
        """Σs at speed index V as a ``control.StateSpace`` (eq. 7).

        Inputs ``[y_1..y_N, w_1..w_N]`` (generalised forces, disturbance), outputs
        ``[u_1..u_N, zm_1..zm_m]``, states ``[u_1, u̇_1, ...]``.  The forcing enters as
        ``Bs (V² y + w)``.  With accelerometers the ``zm`` rows have the feed-through
        ``α Hs (V² y + w)``.
        """
        n = self.n_modes
        V2 = float(V) ** 2
        Hx, Hf = self.sensor_rows()
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
