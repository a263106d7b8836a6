"""Linearisation, ERA and Tustin: the continuous linear aerodynamic ROM Σf (paper eq. 5).

- :func:`realize` — balanced ERA of the linearised HWL ROM and the inverse Tustin transform;
- :func:`canonical_realization` — the block observer-canonical form, a fixed-dimension
  realisation continuous in the model's coefficients;
- :class:`ParametricROM` — ROMs identified at several speeds, interpolated in V.
"""

from ._canonical import canonical_matrices, canonical_realization, lag_coefficients
from ._parametric import ParametricROM, speed_nodes
from ._realize import (Realization, choose_order, continuous_to_tustin, era, inverse_tustin,
                       realize, tustin_to_continuous)

__all__ = ["Realization", "realize", "era", "choose_order", "inverse_tustin",
           "tustin_to_continuous", "continuous_to_tustin", "canonical_realization",
           "canonical_matrices", "lag_coefficients", "ParametricROM", "speed_nodes"]
