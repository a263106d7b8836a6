"""casflutter: nonlinear aerodynamic reduced-order models, flutter analysis and
fixed-order robust flutter suppression, centred on CasADi.

Carries out the method of K.-Y. Lum et al., "Reduced-order modeling and flutter
suppression control of an experimental wing", ACC 2016:

``data -> ident (HWL ROM, eq. 1-4) -> realize (ERA, Tustin, eq. 5) ->
aeroelastic (eq. 6-15) -> design (fixed-order H-infinity) -> verify -> report``
"""

from . import _logging  # noqa: F401 - the package logger's NullHandler
from .errors import (CasflutterError, ConfigError, ConvergenceError, DataError,  # noqa: F401
                     DimensionError, OrderError, SynthesisError)

__version__ = "0.1.0"
