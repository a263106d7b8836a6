"""One small exception hierarchy; every class also subclasses a builtin.

Catch :class:`CasflutterError` to catch anything the package raises on purpose,
or the builtin (``ValueError``, ``RuntimeError``) when that is more natural.
"""

from __future__ import annotations

__all__ = [
    "CasflutterError",
    "DataError",
    "OrderError",
    "DimensionError",
    "ConfigError",
    "ConvergenceError",
    "SynthesisError",
    "OutputError",
    "StoreLockedError",
    "DataWarning",
]


class CasflutterError(Exception):
    """Base class of every error raised on purpose by casflutter."""


class DataError(CasflutterError, ValueError):
    """Input--output data that cannot be used (NaN/inf, length mismatch, too short,
    not exciting enough)."""


class DataWarning(UserWarning):
    """Data that can be used but probably not as meant: a column of a record file that no
    channel names, records whose chirp band or length miss the problem's lowest structural
    mode (e.g. settings in seconds applied to a problem in nondimensional time)."""


class OrderError(CasflutterError, ValueError):
    """Model orders out of range or inconsistent with the data."""


class DimensionError(CasflutterError, ValueError):
    """Systems or matrices whose dimensions do not fit together."""


class ConfigError(CasflutterError, ValueError):
    """A configuration key, type or value that is not allowed."""


class ConvergenceError(CasflutterError, RuntimeError):
    """A numerical solve that did not converge.

    The (non-converged) result object is attached as ``.result`` so that a caller
    can inspect it; it is never returned as if it were a result.
    """

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result


class SynthesisError(CasflutterError, RuntimeError):
    """Fixed-order synthesis found no stabilising controller.

    ``.best_spectral_abscissa`` holds the smallest closed-loop spectral abscissa
    reached over all starts, ``.starts`` the record of every start (with its status and
    why it failed).
    """

    def __init__(self, message: str, best_spectral_abscissa: float | None = None, result=None,
                 starts: tuple = ()):
        super().__init__(message)
        self.best_spectral_abscissa = best_spectral_abscissa
        self.result = result
        self.starts = tuple(starts)


class OutputError(CasflutterError, OSError):
    """An output file or folder that cannot be created or written; checked before any work
    starts (``casflutter._outputs.check_output_path``)."""


class StoreLockedError(CasflutterError, RuntimeError):
    """A sweep store that another running sweep holds (its lock file is taken)."""
