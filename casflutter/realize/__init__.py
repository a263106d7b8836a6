"""Linearisation, ERA and Tustin: the continuous linear aerodynamic ROM Σf (paper eq. 5)."""

from ._realize import (Realization, choose_order, continuous_to_tustin, era,  # noqa: F401
                       realize, tustin_to_continuous)
from ._canonical import canonical_realization, lag_coefficients  # noqa: F401
