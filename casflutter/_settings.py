"""Settings dataclasses from TOML tables: one builder, one way to change a key by dotted path.

Every settings class of casflutter is a frozen dataclass that checks its own values on
construction (``__post_init__``) and raises :class:`~casflutter.errors.ConfigError` whose
message starts with the field's name (``"dt = -0.1: must be > 0"``).  :func:`build_settings`
turns a table (a TOML file's content, or part of it) into such a class:

1. unknown keys fail with the list of allowed ones;
2. each value is checked against the field's annotation (a finite number, integer, boolean, string,
   list, tuple, table, an optional value, a union, or a nested settings class, which is
   built recursively) and converted where TOML has no own type (a list for a tuple);
3. the class is constructed, so its own checks run; their messages are prefixed with the
   dotted path of the section (``"data.dt = -0.1: must be > 0"``).

A section that extends a stage's own settings class (``class ControllerSettings(
SynthesisOptions)``) inherits its fields, so every field the stage adds becomes a
configuration key without further code; :func:`settings_as` turns the section back into the
stage's class.
"""

from __future__ import annotations

import collections.abc
import dataclasses
import difflib
import math
import numbers
import re
import types
import typing
from typing import Any, Mapping

import numpy as np

from .errors import ConfigError

__all__ = ["build_settings", "set_dotted", "settings_as", "field_names", "finite_numbers",
           "reject_unknown"]


def field_names(cls) -> list[str]:
    """Init fields of a settings class: those it adds first, then the inherited ones.

    Parameters
    ----------
    cls : type
        A dataclass.

    Returns
    -------
    list of str
    """
    inherited = {f.name for base in cls.__mro__[1:] if dataclasses.is_dataclass(base)
                 for f in dataclasses.fields(base)}
    own = [n for n in cls.__dict__.get("__annotations__", {}) if n not in inherited]
    names = [f.name for f in dataclasses.fields(cls) if f.init]
    return [n for n in own if n in names] + [n for n in names if n not in own]


def _kind(value) -> str:
    return f"{type(value).__name__} {value!r}"


def _check_type(path: str, value, typ):
    """``value`` checked (and converted) against the annotation ``typ``."""
    if typ is Any or typ is object:
        return value
    origin = typing.get_origin(typ)
    if origin is typing.Union or isinstance(typ, types.UnionType):
        errors = []
        for member in typing.get_args(typ):
            if member is type(None):
                continue
            try:
                return _check_type(path, value, member)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(errors[0]) if len(errors) == 1 else ConfigError(
            f"{path}: expected one of {typ}, got {_kind(value)}")
    if origin is typing.Literal:
        allowed = typing.get_args(typ)
        if value not in allowed:
            raise ConfigError(f"{path} = {value!r}: allowed {', '.join(map(repr, allowed))}")
        return value
    base = origin or typ
    if dataclasses.is_dataclass(base):
        if isinstance(value, base):        # already built (a Python caller's object)
            return value
        if not isinstance(value, Mapping):
            raise ConfigError(f"[{path}] must be a table, got {value!r}")
        return build_settings(base, value, path)
    if base is float:         # numbers.Real: numpy's scalars from a parameter sweep too
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise ConfigError(f"{path}: expected a number, got {_kind(value)}")
        if not math.isfinite(value):
            raise ConfigError(f"{path} = {value!r}: expected a finite number (no nan or inf)")
        return float(value)
    if base is int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise ConfigError(f"{path}: expected an integer, got {_kind(value)}")
        return int(value)
    if base is bool:
        if not isinstance(value, (bool, np.bool_)):
            raise ConfigError(f"{path}: expected true or false, got {_kind(value)}")
        return bool(value)
    if base is str:
        if not isinstance(value, str):
            raise ConfigError(f"{path}: expected a string, got {_kind(value)}")
        return value
    if base in (list, tuple, collections.abc.Sequence):
        if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
            raise ConfigError(f"{path}: expected a list, got {_kind(value)}")
        return tuple(value) if base is tuple else list(value)
    if base in (dict, collections.abc.Mapping):
        if not isinstance(value, Mapping):
            raise ConfigError(f"{path}: expected a table, got {_kind(value)}")
        return dict(value)
    return value


def build_settings(cls, table: Mapping[str, Any], path: str = ""):
    """Build the settings dataclass ``cls`` from a table, checking every key and value.

    Parameters
    ----------
    cls : type
        A (frozen) dataclass whose ``__post_init__`` checks its values.
    table : mapping
        Key -> value, as read from TOML; missing keys take the class's defaults.
    path : str
        Dotted path of the table, for the messages (``"controller"``; ``""`` at the top).

    Returns
    -------
    cls

    Raises
    ------
    ConfigError
        Unknown key (the message lists the allowed ones, and gives the class's
        ``key_hints[key]``, the table the key belongs in or the nearest spelling), a value
        of the wrong type, or a value the class refuses; the message names the dotted key.
    """
    if not isinstance(table, Mapping):
        raise ConfigError(f"[{path}] must be a table, got {table!r}")
    allowed = field_names(cls)
    unknown = [k for k in table if k not in allowed]
    hints = typing.get_type_hints(cls)
    if unknown:
        key = str(unknown[0])
        where = f"[{path}]" if path else "top level"
        # a key of a nested table given one level too high, else the nearest spelling
        home = [name for name in allowed if dataclasses.is_dataclass(hints.get(name))
                and key in field_names(hints[name])]
        close = difflib.get_close_matches(key, allowed, n=1)
        meant = getattr(cls, "key_hints", {}).get(key)
        hint = (f" ({meant})" if meant
                else f" (it belongs in [{path + '.' if path else ''}{home[0]}])" if home
                else f" (did you mean {close[0]!r}?)" if close else "")
        raise ConfigError(f"unknown key {key!r} in {where}{hint}; allowed: "
                          f"{', '.join(allowed)}")
    kwargs = {name: _check_type(f"{path}.{name}" if path else name, value, hints[name])
              for name, value in table.items()}
    try:
        return cls(**kwargs)
    except ConfigError as exc:
        raise _located(exc, path, allowed) from None
    except (TypeError, ValueError) as exc:  # a stage's own check that is not a ConfigError
        raise _located(ConfigError(str(exc)), path, allowed) from None


def reject_unknown(table: Mapping[str, Any], allowed, what: str = "unknown key(s)", *,
                   where: str = "", allowed_text: str | None = None) -> None:
    """Raise :class:`~casflutter.errors.ConfigError` when a table read by hand (not by
    :func:`build_settings`) has keys outside ``allowed``.

    The message reads ``"{what} {unknown keys, sorted}{where}; allowed: {allowed_text}"``,
    e.g. ``"unknown key(s) ['smaples'] in [study]; allowed: ['name', 'samples', ...]"``.

    Parameters
    ----------
    table : mapping
        The table (its keys are checked).
    allowed : set of str
        The keys it may have.
    what : str
        The message's start.
    where : str
        Where the table is, after the unknown keys (``" in [study]"``).
    allowed_text : str, optional
        The allowed keys as the message lists them (default ``sorted(allowed)``).

    Raises
    ------
    ConfigError
        A key outside ``allowed``.
    """
    bad = set(table) - set(allowed)
    if bad:
        listed = sorted(allowed) if allowed_text is None else allowed_text
        raise ConfigError(f"{what} {sorted(bad)}{where}; allowed: {listed}")


def _located(exc: ConfigError, path: str, names) -> ConfigError:
    """``exc`` with the section's path in front of its message."""
    msg = str(exc)
    if not path or msg.startswith(path + "."):
        return ConfigError(msg)
    head = msg.split(" ", 1)[0].split("=", 1)[0].split("[", 1)[0].rstrip(":.,")
    if head in names:
        return ConfigError(f"{path}.{msg}")
    named = re.search(r"\b(" + "|".join(map(re.escape, names)) + r")\s*=", msg)
    if named:  # a stage's own message naming the field somewhere inside
        return ConfigError(f"{path}.{named.group(1)}: {msg}")
    return ConfigError(f"[{path}] {msg}")


def set_dotted(table: dict, cls, dotted: str, value) -> None:
    """Set ``dotted`` (``"controller.order"``, ``"problem.set.zeta"``) in a raw table.

    The path follows the nested settings classes from ``cls``; inside a table-valued field
    (``problem.set``, ``solver.ipopt``) the rest of the path is one key, dots included
    (``"solver.ipopt.ipopt.tol"``).  A table value is merged key by key.  Names are not
    checked here: :func:`build_settings` rejects unknown ones with the allowed keys.

    Parameters
    ----------
    table : dict
        The raw table (changed in place).
    cls : type
        Settings class of ``table``.
    dotted : str
        The key.
    value
        The new value.

    Raises
    ------
    ConfigError
        The path runs through a single value (``"seed.x"``) or a non-table.
    """
    _set_path(table, cls, str(dotted).split("."), value, str(dotted))


def _set_path(node: dict, cls, parts: list, value, dotted: str) -> None:
    name, rest = parts[0], parts[1:]
    typ = typing.get_type_hints(cls).get(name) if cls is not None else None
    base = typing.get_origin(typ) or typ
    section = typ is not None and dataclasses.is_dataclass(base)
    mapping = typ is not None and not section and base in (dict, collections.abc.Mapping)
    if not rest:
        if isinstance(value, Mapping) and (section or mapping):
            for k, v in value.items():  # merge a table key by key
                _set_path(node, cls, [name, str(k)], v, dotted)
        else:
            node[name] = value
        return
    if typ is not None and not (section or mapping):
        raise ConfigError(f"{dotted!r}: {name!r} is a single value, not a table; drop the "
                          "rest of the path")
    sub = node.setdefault(name, {})
    if not isinstance(sub, dict):
        raise ConfigError(f"{dotted!r}: [{name}] must be a table, got {sub!r}")
    if mapping:
        sub[".".join(rest)] = value
    else:
        _set_path(sub, base if section else None, rest, value, dotted)


def settings_as(obj, cls):
    """The fields of ``obj`` that ``cls`` has, as a ``cls`` (a section -> its stage's class).

    Parameters
    ----------
    obj : dataclass instance
        A settings object, usually of a subclass of ``cls``.
    cls : type
        The stage's settings class.

    Returns
    -------
    cls
    """
    return cls(**{f.name: getattr(obj, f.name) for f in dataclasses.fields(cls) if f.init})


def finite_numbers(name: str, value, n: int | None = None, *, what: str = "") -> tuple:
    """``value`` as a tuple of finite floats, ``n`` of them when given.

    Parameters
    ----------
    name : str
        Field name, for the message.
    value : sequence or 1-D numpy.ndarray
        The numbers.
    n : int, optional
        Required length.
    what : str
        Description of the expected form, for the message (``"[low, high]"``).

    Returns
    -------
    tuple of float

    Raises
    ------
    ConfigError
        Not a sequence, wrong length, or an entry that is not a finite number.
    """
    want = what or (f"{n} numbers" if n is not None else "a list of numbers")
    if getattr(value, "ndim", None) == 1 and hasattr(value, "tolist"):    # a numpy vector
        value = value.tolist()
    if isinstance(value, (str, bytes)) or not isinstance(value, collections.abc.Sequence):
        raise ConfigError(f"{name} = {value!r}: give {want}")
    if n is not None and len(value) != n:
        raise ConfigError(f"{name} = {list(value)!r}: give {want}")
    out = []
    for x in value:
        if isinstance(x, bool) or not isinstance(x, numbers.Real) or not math.isfinite(x):
            raise ConfigError(f"{name} = {list(value)!r}: {x!r} is not a finite number; "
                              f"give {want}")
        out.append(float(x))
    return tuple(out)
