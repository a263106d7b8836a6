"""The modal structure Σs (paper eq. 6-7), shared by the truth simulators and the loop.

:class:`ModalStructure` holds the in-vacuo modes (``omega``, ``zeta``), the flow constant
``alpha``, the sensors (rows ``Hs`` in modal coordinates and their kind) and the names of the
modes and sensors.  Its state is ``[u_1, u̇_1, ..., u_N, u̇_N]`` (one block per mode, as
eq. 7); :meth:`ModalStructure.displaced_state` builds initial states without indexing.
"""

from ._modal import SENSOR_KINDS, ModalStructure, check_sensor_rows

__all__ = ["ModalStructure", "SENSOR_KINDS", "check_sensor_rows"]
