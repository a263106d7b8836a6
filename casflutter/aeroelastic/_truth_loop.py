"""ΣAE(V) of a truth simulator's own linearisation: the loop the ROM stands in for.

The paper designs and analyses on the ROM loop ΣAE(V) (eq. 8-9).  What a controller can do
on the ROM is a property of the ROM; whether the *wing* allows the same is asked of the
truth's full-order linearisation (:meth:`casflutter.truth.AeroelasticTruth.statespace`:
structure, unsteady-lag states and the flap) with the flap behind a second-order servo, so
that the controller commands the servo as it would on the wind-tunnel model.  The result is
an :class:`~casflutter.aeroelastic.AeroelasticLoop` at every speed, with the same sensors
(the problem's rows, read as the truth's sensor kind) and the same modal disturbance
inputs, so everything that takes the ROM loop (:func:`casflutter.design.design_over_speeds`,
:func:`casflutter.verify.verify_family`, closed-loop pole maps) takes this one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ..structure import ModalStructure
from ..truth import AeroelasticTruth
from ._loop import AeroelasticLoop, LoopFamily, check_servo

__all__ = ["TruthLoop"]


@dataclass(frozen=True)
class TruthLoop(LoopFamily):
    """The truth's linear aeroelastic loop at any speed index, flap behind a servo.

    Attributes
    ----------
    truth : casflutter.truth.AeroelasticTruth
        The simulator whose linearisation is used.
    servo_omega : float
        Servo natural frequency [rad per time unit of the truth] (> 0).
    servo_zeta : float
        Servo damping ratio (>= 0).
    sensors : ModalStructure, optional
        Whose sensor rows and kind to read (e.g. a run's own, with its ``[sensors]``
        changes); default the truth's :meth:`~casflutter.truth.AeroelasticTruth.modal_structure`.

    Raises
    ------
    ConfigError
        A truth that is not an :class:`~casflutter.truth.AeroelasticTruth`, a servo
        frequency or damping out of range, or sensors on another number of modes.

    Notes
    -----
    States ``[u, u', lags, v, v']`` (the truth's order plus two); the input ``v`` of the
    returned loops is the servo command, and ``zm`` are the problem's sensors: ``Hs u``,
    ``Hs u'`` or ``Hs u''`` (the acceleration with its exact feed-through from the command
    and the disturbances) as the truth's sensor kind says.
    """

    __repr__ = result_repr

    truth: AeroelasticTruth
    servo_omega: float
    servo_zeta: float = 0.7
    sensors: ModalStructure | None = None

    def __post_init__(self):
        if not isinstance(self.truth, AeroelasticTruth):
            raise ConfigError(f"truth must be a casflutter.truth.AeroelasticTruth, got "
                              f"{type(self.truth).__name__}")
        check_servo(self.servo_omega, self.servo_zeta, ("servo_omega", "servo_zeta"))
        if self.sensors is not None and (not isinstance(self.sensors, ModalStructure) or
                                         self.sensors.n_modes != self.truth.n_modes):
            raise ConfigError(f"sensors must be a ModalStructure on the truth's "
                              f"{self.truth.n_modes} modes")

    @property
    def n_modes(self) -> int:
        """N."""
        return self.truth.n_modes

    def modal_structure(self) -> ModalStructure:
        """The sensors' structure (``sensors``, or the truth's own); see
        :meth:`LoopFamily.modal_structure`."""
        return self.sensors if self.sensors is not None else self.truth.modal_structure()

    def loop(self, V: float) -> AeroelasticLoop:
        """The truth's linear loop at speed index V, flap behind the servo; see
        :meth:`LoopFamily.loop`.  Its ``n_f`` counts every state beyond the structure's ``2N``
        (lags and servo)."""
        P = self.truth.statespace(float(V), actuator_omega=self.servo_omega,
                                  actuator_zeta=self.servo_zeta)
        A, B = np.asarray(P.A, float), np.asarray(P.B, float)
        N = self.n_modes
        s = self.modal_structure()
        nx = A.shape[0]
        if s.sensor == "state":
            C2, D2 = np.hstack([s.Hs, np.zeros((s.n_sensors, nx - 2 * N))]), np.zeros_like(B)
        else:
            rows = {"displacement": (np.eye(nx)[:N], np.zeros((N, B.shape[1]))),
                    "velocity": (np.eye(nx)[N:2 * N], np.zeros((N, B.shape[1]))),
                    "acceleration": (A[N:2 * N], B[N:2 * N])}[s.sensor]
            C2, D2 = s.Hs @ rows[0], s.Hs @ rows[1]
        Cu = np.eye(nx)[:N]
        return AeroelasticLoop(float(V), A, B[:, 1:], B[:, 0].copy(), C2, D2[:, 1:],
                               D2[:, 0].copy(), Cu, N, nx - 2 * N)
