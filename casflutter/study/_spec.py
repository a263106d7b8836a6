"""Study definitions: the swept parameters, the design (grid or Latin hypercube), the evaluator.

A study file is TOML::

    [study]
    name = "hp1_mass_damping"
    evaluator = "truth_flutter"     # a registered evaluator or "package.module:function"
    design = "grid"                 # "grid" (full factorial) or "lhs" (Latin hypercube)
    samples = 64                    # lhs only
    seed = 0                        # lhs only
    outputs = ["Vf", "frequency_hz"]  # optional: columns to keep (default: all)
    workers = 2                     # optional: local worker processes
    scheduler = "tcp://host:8786"   # optional: an existing Dask scheduler

    [settings]                      # evaluator settings held fixed over the study
    problem = "typical_section"

    [parameters]                    # one entry per swept parameter
    mu = [10.0, 20.0, 40.0]                       # explicit values
    zeta = {low = 0.0, high = 0.02, num = 3}      # linspace (grid) / range (lhs)
    sigma = {low = 0.2, high = 0.6, num = 5, scale = "log"}
    order = {low = 0, high = 4, integer = true}   # integers (lhs rounds, grid steps 1)
"""

from __future__ import annotations

import datetime
import hashlib
import itertools
import json
import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .._resources import read_toml
from .._settings import reject_unknown
from ..errors import ConfigError

__all__ = ["Parameter", "Study", "load_study", "point_key", "check_setting"]

_DESIGNS = ("grid", "lhs")


def _jsonable(value: Any) -> Any:
    """Plain JSON types (numpy scalars to Python numbers)."""
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        return float(value)
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return value


def _is_int(value) -> bool:
    return (not isinstance(value, bool) and isinstance(value, numbers.Integral)) or (
        isinstance(value, float) and value.is_integer())


def _is_real(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, numbers.Real)


def _integer(value, what: str, minimum: int | None = None) -> int:
    """An integer field of the study file (``16`` or ``16.0``), or a ConfigError."""
    if not _is_int(value) or (minimum is not None and value < minimum):
        more = f" >= {minimum}" if minimum is not None else ""
        raise ConfigError(f"{what} = {value!r}: give an integer{more}")
    return int(value)


def check_setting(settings: Mapping[str, Any], key: str, default: Any, *,
                  integer: bool = False, low: float | None = None, high: float | None = None,
                  positive: bool = False) -> float | int:
    """A numeric evaluator setting (or swept value) checked before any point runs: the
    pre-flight checks of the evaluators call it.

    Parameters
    ----------
    settings : mapping
        The point's merged settings and parameters.
    key : str
        The setting; ``default`` when absent.
    integer, low, high, positive
        The type and range allowed.

    Returns
    -------
    float or int

    Raises
    ------
    ConfigError
        Names the key, its value and what is allowed.
    """
    value = settings.get(key, default)
    ok = _is_int(value) if integer else (_is_real(value) and math.isfinite(float(value)))
    if ok:
        v = float(value)
        ok = (low is None or v >= low) and (high is None or v <= high) and (not positive or v > 0)
    if not ok:
        rng = "".join([" > 0" if positive else "", f" >= {low:g}" if low is not None else "",
                       f" <= {high:g}" if high is not None else ""])
        raise ConfigError(f"{key} = {value!r}: give {'an integer' if integer else 'a finite number'}"
                          f"{rng}")
    return int(value) if integer else float(value)


def _check_value(value, what: str) -> None:
    """A parameter or setting value that can be hashed into a point key and stored as JSON:
    text, a finite number, a boolean, or lists and tables of them."""
    if isinstance(value, Mapping):
        for k, v in value.items():
            _check_value(v, f"{what}.{k}")
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_value(v, f"{what}[{i}]")
    elif isinstance(value, (datetime.date, datetime.time)):
        raise ConfigError(f"{what} = {value!r}: a TOML date or time is not a usable value; "
                          "quote it to pass it as text")
    elif _is_real(value) and not math.isfinite(float(value)):
        raise ConfigError(f"{what} = {value!r}: not a finite number; give a finite value")
    elif not (isinstance(value, (str, bool, numbers.Real)) or value is None):
        raise ConfigError(f"{what} = {value!r}: give text, a number, a boolean, or a list "
                          "or table of them")


def point_key(evaluator: str, settings: Mapping[str, Any], params: Mapping[str, Any]) -> str:
    """Stable hash of one point (evaluator, fixed settings and swept values).

    Two points with the same key are the same computation: the store skips a key that is
    already finished.  Floats are hashed through their shortest round-trip ``repr``.
    """
    blob = json.dumps({"evaluator": evaluator, "settings": _jsonable(dict(settings)),
                       "params": _jsonable(dict(params))}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class Parameter:
    """One swept parameter.

    Attributes
    ----------
    name : str
        Parameter name passed to the evaluator.
    values : tuple or None
        Explicit values (grid: used as they are; lhs: one value chosen per stratum).
    low, high : float or None
        Range (when ``values`` is not given).
    num : int
        Number of grid values over ``[low, high]`` (grid design only).
    scale : str
        ``"linear"`` or ``"log"`` spacing/sampling of the range.
    integer : bool
        Round to integers (ROM orders, controller order).
    """

    name: str
    values: tuple | None = None
    low: float | None = None
    high: float | None = None
    num: int = 5
    scale: str = "linear"
    integer: bool = False

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ConfigError(f"parameter name {self.name!r}: give a non-empty name")
        if self.values is not None:
            if isinstance(self.values, (str, bytes)) or not hasattr(self.values, "__len__"):
                raise ConfigError(f"parameter {self.name!r}: values = {self.values!r} is not a "
                                  "list of values")
            if len(self.values) == 0:
                raise ConfigError(f"parameter {self.name!r}: the list of values is empty")
            for i, v in enumerate(self.values):
                _check_value(v, f"parameter {self.name!r} value {i + 1}")
            return
        if self.low is None or self.high is None:
            raise ConfigError(f"parameter {self.name!r}: give a list of values or a table "
                              "{low = ..., high = ..., num = ...}")
        for key in ("low", "high"):
            v = getattr(self, key)
            if not _is_real(v) or not math.isfinite(float(v)):
                raise ConfigError(f"parameter {self.name!r}: {key} = {v!r} must be a finite "
                                  "number")
        if not _is_int(self.num):
            raise ConfigError(f"parameter {self.name!r}: num = {self.num!r} must be an integer "
                              ">= 1")
        if not isinstance(self.integer, bool):
            raise ConfigError(f"parameter {self.name!r}: integer = {self.integer!r} must be "
                              "true or false")
        if not float(self.high) >= float(self.low):
            raise ConfigError(f"parameter {self.name!r}: need high >= low, got "
                              f"low={self.low}, high={self.high}")
        if self.integer and math.floor(float(self.high)) < math.ceil(float(self.low)):
            raise ConfigError(f"parameter {self.name!r}: no integer between low={self.low} and "
                              f"high={self.high}")
        if self.scale not in ("linear", "log"):
            raise ConfigError(f"parameter {self.name!r}: scale must be 'linear' or 'log', got "
                              f"{self.scale!r}")
        if self.scale == "log" and float(self.low) <= 0:
            raise ConfigError(f"parameter {self.name!r}: a log scale needs low > 0")
        if int(self.num) < 1:
            raise ConfigError(f"parameter {self.name!r}: num must be >= 1")

    @classmethod
    def from_toml(cls, name: str, spec: Any) -> "Parameter":
        """From a TOML value: a list of values, a single value, or a range table."""
        if isinstance(spec, list):
            return cls(name, values=tuple(spec))
        if isinstance(spec, (int, float, str, bool)):
            return cls(name, values=(spec,))
        if isinstance(spec, Mapping):
            allowed = {"low", "high", "num", "scale", "integer", "values"}
            reject_unknown(spec, allowed, f"parameter {name!r}: unknown key(s)")
            vals = spec.get("values")
            if vals is not None and not isinstance(vals, list):
                raise ConfigError(f"parameter {name!r}: values = {vals!r} must be a list")
            return cls(name, values=None if vals is None else tuple(vals), low=spec.get("low"),
                       high=spec.get("high"), num=spec.get("num", 5),
                       scale=str(spec.get("scale", "linear")),
                       integer=spec.get("integer", False))
        raise ConfigError(f"parameter {name!r}: {spec!r} is neither a list of values nor a "
                          "{low, high, num} table")

    def _cast(self, x):
        return int(round(x)) if self.integer else float(x)

    def grid_values(self) -> list:
        """The values of a full-grid design."""
        if self.values is not None:
            return list(self.values)
        lo, hi = float(self.low), float(self.high)
        if self.integer:
            return list(range(int(math.ceil(lo)), int(math.floor(hi)) + 1))
        n = int(self.num)
        if self.scale == "log":
            return [float(v) for v in np.geomspace(lo, hi, n)]
        return [float(v) for v in np.linspace(lo, hi, n)]

    def from_unit(self, u: np.ndarray) -> list:
        """Map samples ``u`` in ``[0, 1)`` to parameter values (Latin-hypercube design)."""
        if self.values is not None:
            idx = np.minimum((u * len(self.values)).astype(int), len(self.values) - 1)
            return [self.values[i] for i in idx]
        lo, hi = float(self.low), float(self.high)
        if self.integer:  # equal-probability integers lo..hi
            n = int(math.floor(hi)) - int(math.ceil(lo)) + 1
            return [int(math.ceil(lo)) + int(min(k, n - 1)) for k in (u * n).astype(int)]
        if self.scale == "log":
            x = np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))
        else:
            x = lo + u * (hi - lo)
        return [self._cast(v) for v in x]


@dataclass(frozen=True)
class Study:
    """A parameter study: what to evaluate, at which points, and where.

    Attributes
    ----------
    name : str
        Name of the study (default file stem), used for output file names.
    evaluator : str
        Registered evaluator name (:func:`evaluator_names`) or ``"module:function"``.
    parameters : tuple of Parameter
        The swept parameters.
    settings : dict
        Fixed evaluator settings (problem name, speed range, plant file ...).
    design : str
        ``"grid"`` (full factorial) or ``"lhs"`` (Latin hypercube).
    samples : int
        Number of Latin-hypercube points.
    seed : int
        Seed of the Latin-hypercube design.
    outputs : tuple of str
        Output columns to keep (empty: all outputs of the evaluator).
    workers : int
        Default number of local worker processes.
    scheduler : str or None
        Address of an existing Dask scheduler (``tcp://HOST:PORT``); ``None``: local.
    base_dir : str
        Directory that relative paths in ``settings`` refer to (the study file's folder).
    """

    name: str
    evaluator: str
    parameters: tuple
    settings: Mapping[str, Any] = field(default_factory=dict)
    design: str = "grid"
    samples: int = 16
    seed: int = 0
    outputs: tuple = ()
    workers: int = 2
    scheduler: str | None = None
    base_dir: str = "."

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip() or self.name in (".", "..") \
                or any(c in self.name for c in "/\\\0"):
            raise ConfigError(f"study name {self.name!r} names the output files: give a "
                              "non-empty name without '/' or '\\'")
        if not isinstance(self.evaluator, str) or not self.evaluator:
            raise ConfigError(f"evaluator = {self.evaluator!r}: give a registered name or "
                              "'package.module:function'")
        _integer(self.samples, "samples", 1)
        _integer(self.seed, "seed", 0)
        _integer(self.workers, "workers", 0)
        if isinstance(self.outputs, (str, bytes)) or not all(
                isinstance(o, str) and o for o in self.outputs):
            raise ConfigError(f"outputs = {self.outputs!r}: give a list of output names, e.g. "
                              'outputs = ["Vf"]')
        if self.scheduler is not None and not isinstance(self.scheduler, str):
            raise ConfigError(f"scheduler = {self.scheduler!r}: give the address as text, "
                              "e.g. \"tcp://host:8786\"")
        if not isinstance(self.settings, Mapping):
            raise ConfigError(f"settings must be a table, got {type(self.settings).__name__}")
        for k, v in self.settings.items():
            _check_value(v, f"[settings] {k}")
        if self.design not in _DESIGNS:
            raise ConfigError(f"design must be one of {_DESIGNS}, got {self.design!r}")
        if not self.parameters:
            raise ConfigError("a study needs at least one parameter in [parameters]")
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ConfigError(f"duplicate parameter names in {names}")
        clash = set(names) & set(self.settings)
        if clash:
            raise ConfigError(f"{sorted(clash)} appear both in [parameters] and [settings]; "
                              "keep each name in one of them")
        if self.design == "lhs" and int(self.samples) < 1:
            raise ConfigError(f"samples must be >= 1 for a Latin hypercube, got {self.samples}")
        if int(self.workers) < 0:
            raise ConfigError(f"workers must be >= 0 (0: in this process), got {self.workers}")

    @property
    def parameter_names(self) -> list[str]:
        """Names of the swept parameters, in file order."""
        return [p.name for p in self.parameters]

    def points(self) -> list[dict[str, Any]]:
        """The design points (each a dict ``name -> value``), in a reproducible order.

        Grid: the Cartesian product of every parameter's values (last parameter fastest).
        LHS: ``samples`` points of :class:`scipy.stats.qmc.LatinHypercube` with ``seed``.
        """
        if self.design == "grid":
            axes = [p.grid_values() for p in self.parameters]
            return [dict(zip(self.parameter_names, combo)) for combo in itertools.product(*axes)]
        from scipy.stats import qmc  # noqa: PLC0415

        u = qmc.LatinHypercube(d=len(self.parameters), seed=int(self.seed)).random(int(self.samples))
        cols = [p.from_unit(u[:, j]) for j, p in enumerate(self.parameters)]
        return [dict(zip(self.parameter_names, row)) for row in zip(*cols)]

    def resolved_settings(self) -> dict[str, Any]:
        """``settings`` with the study's ``base_dir`` added (key ``"_base_dir"``) for
        evaluators that read files relative to the study file."""
        out = dict(self.settings)
        out.setdefault("_base_dir", str(self.base_dir))
        return out

    def key(self, point: Mapping[str, Any]) -> str:
        """Hash key of one point (see :func:`point_key`)."""
        return point_key(self.evaluator, self.settings, point)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, name: str = "study",
                  base_dir: str | Path = ".") -> "Study":
        """From the parsed TOML tables ``study``, ``settings``, ``parameters``."""
        allowed_top = {"study", "settings", "parameters"}
        reject_unknown(data, allowed_top, "unknown table(s)", where=" in the study file")
        st = dict(data.get("study", {}))
        allowed = {"name", "evaluator", "design", "samples", "seed", "outputs", "workers",
                   "scheduler"}
        reject_unknown(st, allowed, where=" in [study]")
        if "evaluator" not in st:
            raise ConfigError("[study] needs evaluator = \"NAME\" (e.g. \"truth_flutter\")")
        for table in ("study", "settings", "parameters"):
            if not isinstance(data.get(table, {}), Mapping):
                raise ConfigError(f"[{table}] must be a table of keys, got "
                                  f"{type(data[table]).__name__}")
        outputs = st.get("outputs", ())
        if not isinstance(outputs, (list, tuple)):
            raise ConfigError(f"outputs = {outputs!r}: give a list of output names, e.g. "
                              'outputs = ["Vf"]')
        params = tuple(Parameter.from_toml(k, v) for k, v in data.get("parameters", {}).items())
        return cls(name=str(st.get("name", name)), evaluator=st["evaluator"],
                   parameters=params, settings=dict(data.get("settings", {})),
                   design=str(st.get("design", "grid")),
                   samples=_integer(st.get("samples", 16), "samples", 1),
                   seed=_integer(st.get("seed", 0), "seed", 0), outputs=tuple(outputs),
                   workers=_integer(st.get("workers", 2), "workers", 0),
                   scheduler=st.get("scheduler") or None, base_dir=str(base_dir))


def load_study(path: str | Path) -> Study:
    """Read a study TOML file (module docstring for the format).

    Raises
    ------
    ConfigError
        Missing file, malformed TOML or an invalid entry (the message names it).
    """
    path = Path(path)
    data = read_toml(path, "study file")
    try:
        return Study.from_dict(data, name=path.stem, base_dir=path.resolve().parent)
    except ConfigError as exc:
        raise ConfigError(f"study file {path}: {exc}") from None

