"""Parameter dataclasses: ``with_updates`` / ``from_sets`` with clear errors."""

from __future__ import annotations

import dataclasses
from typing import Any, Iterable, Mapping

from ..errors import ConfigError

__all__ = ["ParamsMixin", "ChordGeometryMixin", "parse_sets"]


class ParamsMixin:
    """Mixin for frozen parameter dataclasses.

    Subclasses are frozen dataclasses whose fields carry ``metadata={"doc": ..., "unit": ...}``
    and implement ``_validate()`` (raising :class:`ConfigError` naming the fault and the fix).
    """

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.type in ("int", int):
                if isinstance(v, bool) or int(v) != v:
                    raise ConfigError(f"parameter {f.name!r} must be an integer, got {v!r}")
                object.__setattr__(self, f.name, int(v))
            else:
                try:
                    object.__setattr__(self, f.name, float(v))
                except (TypeError, ValueError):
                    raise ConfigError(f"parameter {f.name!r} must be a number, got {v!r}") from None
        self._validate()

    def _validate(self) -> None:  # pragma: no cover - overridden
        pass

    @classmethod
    def parameter_names(cls) -> list[str]:
        """Names of all parameters, in declaration order."""
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def describe(cls) -> list[tuple[str, Any, str, str]]:
        """``(name, default, unit, doc)`` for every parameter."""
        return [(f.name, f.default, f.metadata.get("unit", ""), f.metadata.get("doc", ""))
                for f in dataclasses.fields(cls)]

    def as_dict(self) -> dict[str, float]:
        """Parameters as a plain dict.

        Returns
        -------
        dict
        """
        return dataclasses.asdict(self)

    def with_updates(self, **changes: float):
        """A copy with some parameters changed.

        Parameters
        ----------
        **changes : float
            New values by parameter name.

        Returns
        -------
        Parameters of this class.
            The copy, checked like a new instance.

        Raises
        ------
        ConfigError
            If a name is not a parameter (the message lists the valid names) or a value is
            not physical.
        """
        valid = self.parameter_names()
        unknown = [k for k in changes if k not in valid]
        if unknown:
            raise ConfigError(f"unknown parameter(s) {', '.join(map(repr, unknown))} for "
                              f"{type(self).__name__}; valid names: {', '.join(valid)}")
        return dataclasses.replace(self, **changes)

    @classmethod
    def from_sets(cls, sets: Mapping[str, Any] | Iterable[str] = (), base=None):
        """Parameters with changes: a mapping ``{name: value}`` or ``["name=value", ...]``
        strings (the CLI's ``--set``).

        Parameters
        ----------
        sets : mapping or iterable of str
            The changes, numeric values.
        base : optional
            Parameters to start from (default: the published case).

        Returns
        -------
        Parameters of this class.
            ``base`` with the changes.

        Raises
        ------
        ConfigError
            Malformed item, unknown name (valid names listed) or non-physical value.
        """
        base = cls() if base is None else base
        items = sets if isinstance(sets, Mapping) else parse_sets(sets)
        changes: dict[str, float] = {}
        for name, value in items.items():
            if name not in cls.parameter_names():
                raise ConfigError(f"unknown parameter {name!r} for {cls.__name__}; valid "
                                  f"names: {', '.join(cls.parameter_names())}")
            try:
                if isinstance(value, bool):
                    raise ValueError
                changes[name] = float(value)
            except (TypeError, ValueError):
                raise ConfigError(f"--set {name}={value!r}: value must be a number") from None
        return base.with_updates(**changes)



def parse_sets(items: Iterable[str]) -> dict[str, str]:
    """``["name=value", ...]`` (the CLI's ``--set``) as ``{name: value}``.

    Parameters
    ----------
    items : iterable of str
        The items.

    Returns
    -------
    dict
        Name -> value text (the parameter class converts and checks it).

    Raises
    ------
    ConfigError
        An item that is not of the form ``name=value``.
    """
    out = {}
    for item in items:
        name, sep, value = str(item).partition("=")
        name = name.strip()
        if not sep or not name:
            raise ConfigError(f"--set item {item!r} is not of the form name=value")
        out[name] = value.strip()
    return out


def parameter(default, unit: str, doc: str):
    """A parameter field of a truth's parameter dataclass: its default, unit and meaning
    (read by :meth:`ParamsMixin.describe` and the problem listings)."""
    return dataclasses.field(default=default, metadata={"unit": unit, "doc": doc})


def require(cond: bool, message: str) -> None:
    """Raise :class:`ConfigError` with ``message`` unless ``cond``."""
    if not cond:
        raise ConfigError(message)


class ChordGeometryMixin:
    """Section geometry of wing parameter sets with fields ``chord`` [m] and ``ea_chord``
    (elastic axis as a fraction of the chord from the leading edge)."""

    @property
    def b(self) -> float:
        """Semichord [m]."""
        return 0.5 * self.chord

    @property
    def a(self) -> float:
        """Elastic axis in semichords aft of mid-chord."""
        return 2.0 * self.ea_chord - 1.0
