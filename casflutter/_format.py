"""Numbers and results as a person reads them: a few significant digits on screen and in the
report, full precision only in JSON.

- :func:`sig` writes a number (or a pair, a list, ``None``, ``inf``) with ``digits``
  significant digits: ``sig(9.153151391264155) == "9.1532"``.
- :func:`result_repr` is the one-screen ``__repr__`` of the frozen result dataclasses: each
  field on a line, arrays by shape and range, state-space systems by their dimensions, nested
  results by their scalar fields, long sequences by their length (the style of
  ``scipy.optimize.OptimizeResult`` and python-control's ``StateSpace`` summaries).  A result
  class takes it with ``__repr__ = result_repr`` in its body.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from numbers import Integral, Real
from pathlib import PurePath

import numpy as np

__all__ = ["sig", "result_repr", "short_value"]

#: longest rendering of one field before it is shortened
_WIDTH = 88
#: items of a sequence or mapping written out in full
_ITEMS = 6


def sig(x, digits: int = 5, *, none: str = "-") -> str:
    """``x`` with ``digits`` significant digits (``9.153151391264155`` -> ``"9.1532"``).

    Parameters
    ----------
    x : float, int, sequence of them, or None
        A number, or a pair / list of numbers (written ``(a, b)``).
    digits : int
        Significant digits (4-6 on screen and in the report); at least the integer part's
        below 10^6 (no exponent for 11410).
    none : str
        What ``None`` becomes.

    Returns
    -------
    str
        Integers as they are, ``inf`` and ``nan`` by name.
    """
    if x is None:
        return none
    if isinstance(x, bool):
        return str(x)
    if isinstance(x, Integral):
        return str(int(x))
    if isinstance(x, Real):
        x = float(x)
        if not math.isfinite(x):
            return str(x)
        if 1.0 <= abs(x) < 1e6:        # the integer part whole: 11410, not 1.141e+04
            digits = max(digits, len(str(int(abs(x)))))
        return f"{x:.{digits}g}"
    if isinstance(x, complex):
        return f"{x.real:.{digits}g}{x.imag:+.{digits}g}j"
    if isinstance(x, (list, tuple, np.ndarray)):
        return "(" + ", ".join(sig(v, digits, none=none) for v in x) + ")"
    return str(x)


def _clip(text: str, width: int = _WIDTH) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= width else text[:width - 1] + "…"


def _is_scalar(v) -> bool:
    return v is None or isinstance(v, (bool, Real, complex, str, np.generic, PurePath))


def _array(a: np.ndarray) -> str:
    if a.size == 0:
        return f"array(shape={a.shape})"
    if a.ndim <= 1 and a.size <= _ITEMS and a.dtype.kind in "biufc":
        return "array([" + ", ".join(sig(v) for v in a.tolist()) + "])"
    text = f"array(shape={a.shape}, {a.dtype}"
    if a.dtype.kind in "iuf":
        finite = a[np.isfinite(a)] if a.dtype.kind == "f" else a
        if finite.size:
            text += f", range [{sig(finite.min(), 4)}, {sig(finite.max(), 4)}]"
    elif a.dtype.kind == "c":
        text += f", |max| {sig(float(np.nanmax(np.abs(a))), 4)}"
    return text + ")"


def _nested(v) -> str:
    """A nested result by its scalar fields, on one line."""
    parts = []
    for f in dataclasses.fields(v):
        if not f.repr:
            continue
        x = getattr(v, f.name)
        if _is_scalar(x):
            parts.append(f"{f.name}={short_value(x)}")
    return _clip(f"{type(v).__name__}({', '.join(parts)})")


def short_value(v) -> str:
    """One line for a field of :func:`result_repr`.

    Parameters
    ----------
    v : object
        The field's value.

    Returns
    -------
    str
        Numbers with 6 significant digits, arrays by shape and range, systems by their
        dimensions, nested results by their scalar fields, long sequences by their length.
    """
    if v is None or isinstance(v, (bool, np.bool_, Integral)):
        return repr(v) if not isinstance(v, np.generic) else repr(v.item())
    if isinstance(v, (Real, complex)):
        return sig(v, 6)
    if isinstance(v, str):
        return repr(_clip(v, _WIDTH - 2)) if len(v) > _WIDTH - 2 else repr(v)
    if isinstance(v, PurePath):
        return repr(str(v))
    if isinstance(v, np.ndarray):
        return _array(v)
    if hasattr(v, "nstates") and hasattr(v, "ninputs") and hasattr(v, "noutputs"):
        dt = getattr(v, "dt", 0)
        time = "" if not dt else f", dt={sig(dt) if dt is not True else 'True'}"
        return (f"{type(v).__name__}(nstates={v.nstates}, ninputs={v.ninputs}, "
                f"noutputs={v.noutputs}{time})")
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        if type(v).__str__ is not object.__str__:     # its own short form (HWLModel)
            text = str(v)
            if "\n" not in text and len(text) <= _WIDTH:
                return text
        return _nested(v)
    if isinstance(v, Mapping):
        if len(v) <= _ITEMS and all(_is_scalar(x) for x in v.values()):
            return _clip("{" + ", ".join(f"{k!r}: {short_value(x)}" for k, x in v.items())
                         + "}")
        return f"{type(v).__name__} with {len(v)} keys: " + _clip(
            ", ".join(repr(k) for k in v), _WIDTH - 30)
    if isinstance(v, (tuple, list)):
        if len(v) <= _ITEMS and all(_is_scalar(x) for x in v):
            open_, close = ("(", ")") if isinstance(v, tuple) else ("[", "]")
            text = open_ + ", ".join(short_value(x) for x in v) + close
            if len(text) <= _WIDTH:
                return text
        kinds = sorted({type(x).__name__ for x in v})
        return f"{type(v).__name__} of {len(v)} {'/'.join(kinds) or 'items'}"
    if type(v).__repr__ is not object.__repr__:
        text = repr(v)
        if "\n" not in text and len(text) <= _WIDTH:
            return text
    return f"<{type(v).__name__}>"


def _unset(obj, f: dataclasses.Field) -> bool:
    """A field left at an empty default (``None``, ``{}``, ``()``): not worth a line."""
    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
        return False
    v = getattr(obj, f.name)
    return v is None or (isinstance(v, (Mapping, tuple, list)) and len(v) == 0)


def result_repr(self) -> str:
    """The one-screen representation of a frozen result dataclass.

    Parameters
    ----------
    self : dataclass instance
        The result.

    Returns
    -------
    str
        ``Name(field=value, ...)`` on one line when it fits, else one field per line; each
        value from :func:`short_value`; a field left at an empty default (``None``, ``{}``,
        ``()``) is not shown.
    """
    items = [f"{f.name}={short_value(getattr(self, f.name))}"
             for f in dataclasses.fields(self) if f.repr and not _unset(self, f)]
    name = type(self).__name__
    one = f"{name}({', '.join(items)})"
    if len(one) <= _WIDTH and "\n" not in one:
        return one
    return name + "(\n" + "".join(f"    {item},\n" for item in items) + ")"
