"""The modal structure Σs (paper eq. 6-7), shared by the truth simulators and the loop.

:class:`ModalStructure` holds the in-vacuo modes (``omega``, ``zeta``), the flow constant
``alpha``, the sensors (rows ``Hs`` in modal coordinates and their kind), the names of the
modes and sensors, and the problem's :class:`SpeedConvention` (what the speed index ``V`` is,
the unit of time, the airspeed and dynamic pressure).  A structural state is a
:class:`ModalState` (``u`` and ``u̇`` by name); each model's :class:`ModalLayout` says where
it keeps one (Σs: ``[u_1, u̇_1, ..., u_N, u̇_N]``, one block per mode as in eq. 7).
"""

from ._modal import SENSOR_KINDS, ModalStructure, check_sensor_rows
from ._speed import AirspeedMixin, SpeedConvention
from ._state import ModalLayout, ModalState, ModalStates

__all__ = ["ModalStructure", "SENSOR_KINDS", "check_sensor_rows", "ModalState", "ModalLayout",
           "ModalStates", "SpeedConvention", "AirspeedMixin"]
