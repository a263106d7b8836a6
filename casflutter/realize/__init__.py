"""Linearisation, ERA and Tustin: the continuous linear aerodynamic ROM Σf (paper eq. 5);
rational-function approximations of frequency-domain aerodynamics Q(ik).

- :func:`realize` — balanced ERA of the linearised HWL ROM and the inverse Tustin transform;
- :func:`canonical_realization` — the block observer-canonical form, a fixed-dimension
  realisation continuous in the model's coefficients;
- :class:`ParametricROM` — ROMs identified at several speeds, interpolated in V;
- :func:`fit_roger`, :func:`fit_minimum_state`, :func:`fit_rfa` — Roger and minimum-state
  rational-function approximations of a Q(ik) table (:class:`RationalApproximation`).
"""

from ._canonical import canonical_matrices, canonical_realization, lag_coefficients
from ._parametric import ParametricROM, speed_nodes
from ._realize import (Realization, choose_order, continuous_to_tustin, era, inverse_tustin,
                       realize, tustin_to_continuous)
from ._rfa import RationalApproximation, RFASettings, fit_minimum_state, fit_rfa, fit_roger

__all__ = ["Realization", "realize", "era", "choose_order", "inverse_tustin",
           "tustin_to_continuous", "continuous_to_tustin", "canonical_realization",
           "canonical_matrices", "lag_coefficients", "ParametricROM", "speed_nodes",
           "RationalApproximation", "RFASettings", "fit_roger", "fit_minimum_state", "fit_rfa"]
