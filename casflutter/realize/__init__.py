"""Linearisation, ERA and Tustin: the continuous linear aerodynamic ROM Σf (paper eq. 5);
rational-function approximations of frequency-domain aerodynamics Q(ik).

- :func:`realize` — balanced ERA of the linearised HWL ROM and the inverse Tustin transform;
- :func:`canonical_realization` — the block observer-canonical form, a fixed-dimension
  realisation continuous in the model's coefficients;
- :class:`ParametricROM` — ROMs identified at several speeds, interpolated in V;
- :func:`fit_roger`, :func:`fit_minimum_state`, :func:`fit_rfa` — Roger and minimum-state
  rational-function approximations of a Q(ik) table (:class:`RationalApproximation`).

The stage shares its name with its main function, which the flat namespace exports as
``casflutter.realize``.  Python binds an imported subpackage as an attribute of its parent,
so once anything imports this stage ``casflutter.realize`` is this module; the module is
therefore callable, ``casflutter.realize(model, order)`` is :func:`realize` whichever object
the name holds, and ``import casflutter.realize as rz; rz.era(...)`` keeps working.
"""

import inspect as _inspect
import sys as _sys
import types as _types

from ._canonical import canonical_matrices, canonical_realization, lag_coefficients
from ._parametric import ParametricROM, speed_nodes
from ._realize import (Realization, choose_order, continuous_to_tustin, era, inverse_tustin,
                       realize, tustin_to_continuous)
from ._rfa import RationalApproximation, RFASettings, fit_minimum_state, fit_rfa, fit_roger

__all__ = ["Realization", "realize", "era", "choose_order", "inverse_tustin",
           "tustin_to_continuous", "continuous_to_tustin", "canonical_realization",
           "canonical_matrices", "lag_coefficients", "ParametricROM", "speed_nodes",
           "RationalApproximation", "RFASettings", "fit_roger", "fit_minimum_state", "fit_rfa"]



class _CallableStage(_types.ModuleType):
    """This module, callable as :func:`realize` (module docstring)."""

    def __call__(self, *args, **kwargs):
        return realize(*args, **kwargs)


__signature__ = _inspect.signature(realize)
_sys.modules[__name__].__class__ = _CallableStage
