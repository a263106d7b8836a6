"""Identification of the Hammerstein--Wiener-like ROM (paper §II, eq. 1--4).

``identify(data, orders)`` runs stage 1 (over-parameterised least squares and rank-one SVD,
Bai 1998, extended to MIMO) and stage 2 (an Ipopt NLP through CasADi).
``identify_common_denominator(data, na, nb)`` identifies the linear model with one scalar
denominator by variable projection (for aerodynamics linear in the motion).
"""

from ._common_denominator import (CommonDenominatorResult,  # noqa: F401
                                  identify_common_denominator)
from ._identify import (FitReport, IdentificationResult, IdentificationSettings,  # noqa: F401
                        fit_report, identify)
from ._model import (HWLModel, HWLStructure, hwl_predict_function,  # noqa: F401
                     hwl_simulate_function, paper_parameter_count)
from ._orders import HWLOrders  # noqa: F401
from ._regression import Stage1Result, stage1  # noqa: F401
from ._synthetic import random_hwl_model, synthetic_data  # noqa: F401
