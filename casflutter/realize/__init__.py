"""Linearisation, ERA and Tustin: the continuous linear aerodynamic ROM Σf (paper eq. 5);
rational-function approximations (Roger, minimum-state) of frequency-domain aerodynamics Q(ik)."""

from ._realize import (Realization, choose_order, continuous_to_tustin, era,  # noqa: F401
                       realize, tustin_to_continuous)
from ._canonical import canonical_realization, lag_coefficients  # noqa: F401
from ._rfa import (RationalApproximation, RFASettings, fit_minimum_state, fit_rfa,  # noqa: F401
                   fit_roger)
