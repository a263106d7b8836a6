"""One input--output record (:class:`Record`): outputs ``y``, modal displacements ``u`` and
flap ``v`` sampled together, checked on construction (shapes, real finite numbers, equal
lengths); an array that cannot be used is a :class:`~casflutter.errors.DataError` naming the
record and the signal."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import DataError

__all__ = ["Record"]


def _check_finite(name: str, arr: np.ndarray, record: str) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise DataError(f"record {record!r}: signal {name} has {int(bad.sum())} NaN/inf "
                        f"value(s), first at sample {int(idx[0])}; remove or interpolate them")


def _real_array(name: str, value, record: str) -> np.ndarray:
    """``value`` as a float array, refusing what would silently change its meaning: ragged
    nesting, text, objects, complex numbers, dates, no samples."""
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nesting (NumPy >= 1.24 refuses it)
        raise DataError(f"record {record!r}: signal {name} is not a rectangular array "
                        f"({exc}); give a (samples, channels) array with rows of equal "
                        "length") from None
    kind = arr.dtype.kind
    if kind == "O":
        try:
            arr = arr.astype(float)
        except (ValueError, TypeError):
            try:
                arr = arr.astype(complex)
            except (ValueError, TypeError):
                raise DataError(f"record {record!r}: signal {name} holds Python objects "
                                "(ragged rows, text or None) that are not numbers; give a "
                                "numeric (samples, channels) array") from None
        kind = arr.dtype.kind
    if kind == "c":
        raise DataError(f"record {record!r}: signal {name} is complex; the records are real "
                        "time series -- pass the real part (np.real) if the imaginary part "
                        "is rounding noise")
    if kind in "USV":
        raise DataError(f"record {record!r}: signal {name} holds text (dtype {arr.dtype}), "
                        "not numbers; convert it, e.g. np.asarray(x, dtype=float)")
    if kind in "mM":
        raise DataError(f"record {record!r}: signal {name} holds dates or durations (dtype "
                        f"{arr.dtype}); give the sampled values, with the sampling time as dt")
    if kind not in "biuf":
        raise DataError(f"record {record!r}: signal {name} has dtype {arr.dtype}, not a "
                        "number type")
    arr = arr.astype(float)
    if arr.ndim == 0:
        raise DataError(f"record {record!r}: signal {name} is a single number; give one "
                        "value per sample")
    if arr.shape[0] == 0:
        raise DataError(f"record {record!r}: signal {name} has no samples (shape "
                        f"{arr.shape}); give at least one sample per channel")
    return arr


@dataclass(frozen=True)
class Record:
    """One input--output experiment sampled at a constant rate.

    Attributes
    ----------
    y : ndarray, shape (K, N)
        Outputs (generalised aerodynamic forces, or measured responses).
    u : ndarray, shape (K, N) or None
        Modal-displacement inputs (absent for e.g. shaker tests).
    v : ndarray, shape (K,) or None
        Scalar flap / actuator input (absent for e.g. CFD runs without flap).
    name : str
        Label used in messages and reports.
    """

    __repr__ = result_repr

    y: np.ndarray
    u: np.ndarray | None = None
    v: np.ndarray | None = None
    name: str = "record"

    def __post_init__(self):
        y = _real_array("y", self.y, self.name)
        if y.ndim == 1:
            y = y[:, None]
        if y.ndim != 2 or y.shape[1] == 0:
            raise DataError(f"record {self.name!r}: y must be (samples, outputs) with at least "
                            f"one output, got shape {y.shape}")
        K = y.shape[0]
        _check_finite("y", y, self.name)
        object.__setattr__(self, "y", y)
        if self.u is not None:
            u = _real_array("u", self.u, self.name)
            u = u[:, None] if u.ndim == 1 else u
            if u.ndim != 2:
                raise DataError(f"record {self.name!r}: u must be (samples, modal inputs), got "
                                f"shape {u.shape}; reshape it to 2-D (e.g. u.reshape(len(u), "
                                "-1)) if the extra axes are singletons")
            if u.shape[0] != K:
                raise DataError(f"record {self.name!r}: length mismatch, u has {u.shape[0]} "
                                f"samples and y has {K}; trim them to a common length")
            if u.shape[1] != y.shape[1]:
                raise DataError(f"record {self.name!r}: u has {u.shape[1]} channels but y has "
                                f"{y.shape[1]}; the HWL ROM maps N modal displacements to N "
                                "generalised forces")
            _check_finite("u", u, self.name)
            object.__setattr__(self, "u", u)
        if self.v is not None:
            v = _real_array("v", self.v, self.name)
            if v.ndim == 2 and 1 in v.shape:
                v = v.ravel()
            if v.ndim != 1:
                raise DataError(f"record {self.name!r}: v must be one channel, got shape {v.shape}")
            if v.shape[0] != K:
                raise DataError(f"record {self.name!r}: length mismatch, v has {v.shape[0]} "
                                f"samples and y has {K}; trim them to a common length")
            _check_finite("v", v, self.name)
            object.__setattr__(self, "v", v)
        if self.u is None and self.v is None:
            raise DataError(f"record {self.name!r} has no input: give u and/or v")

    @property
    def n_samples(self) -> int:
        return int(self.y.shape[0])

    @property
    def n_outputs(self) -> int:
        return int(self.y.shape[1])
