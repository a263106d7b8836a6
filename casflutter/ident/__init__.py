"""Identification of the Hammerstein--Wiener-like ROM (paper §II, eq. 1--4).

``identify(data, orders)`` runs stage 1 (over-parameterised least squares and rank-one SVD,
Bai 1998, extended to MIMO) and stage 2: the mu-step prediction error (Ipopt through CasADi)
or the free-run simulation error (Levenberg--Marquardt with exact forward sensitivities
through the recursion of eq. 3, or Ipopt on a multiple-shooting NLP).
``select_orders(data, grid)`` compares candidate orders by free-run error on held-out data.
``identify_common_denominator(data, na, nb)`` identifies the linear model with one scalar
denominator by variable projection (for aerodynamics linear in the motion).
"""

from ._common_denominator import CommonDenominatorResult, identify_common_denominator
from ._identify import (FitReport, IdentificationResult, IdentificationSettings,
                        IdentificationWarning, fit_report, identify)
from ._model import HWLModel, UnstableModelWarning
from ._orders import HWLOrders
from ._regression import Stage1Result, stage1
from ._select import OrderCandidate, OrderSelection, order_grid, parse_grid, select_orders
from ._structure import HWLStructure, paper_parameter_count
from ._synthetic import duffing_data, example_rom, random_hwl_model, synthetic_data
from ._twins import hwl_predict_function, hwl_simulate_function

__all__ = ["identify", "IdentificationSettings", "IdentificationResult", "IdentificationWarning",
           "FitReport", "fit_report", "HWLModel", "HWLStructure", "HWLOrders",
           "UnstableModelWarning", "paper_parameter_count", "Stage1Result", "stage1",
           "select_orders", "OrderCandidate", "OrderSelection", "order_grid", "parse_grid",
           "identify_common_denominator", "CommonDenominatorResult", "synthetic_data",
           "random_hwl_model", "duffing_data", "example_rom", "hwl_predict_function",
           "hwl_simulate_function"]
