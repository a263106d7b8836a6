"""Gridded plant-family files: linear state-space models at a grid of speeds.

What an aircraft's aeroservoelastic model usually is once it leaves NASTRAN, ZAERO, ASWING or
a flight-dynamics code: ``(A, B, C, D)`` at ``k`` flight speeds, the same states at every
speed, several control surfaces and sensors.  A **problem file** (TOML) describes it and names
a **data file** that holds the arrays.

Problem file (``kind = "plant_family"``)::

    kind = "plant_family"
    file = "models.npz"          # or models.mat; relative to this file's folder
    speed_unit = "m/s"           # unit of the grid speeds (required)
    time_unit = "s"              # unit of time of the models (default "s")
    feedback = "negative"        # how a controller is applied (required):
                                 #   "negative": u = -K y (MATLAB's feedback(P, K))
                                 #   "positive": u = +K y (the paper's v = K zm)
    interpolation = "linear"     # between grid speeds, elementwise (the only one)
    layout = "pages"             # optional, .mat only: "pages" (A n x n x k) or
                                 #   "speed_first" (A k x n x n); default: the one that fits
    controls = ["flap_1", ...]   # optional: the inputs a controller drives (default all)
    measurements = ["gyro", ...] # optional: the outputs a controller reads (default all)
    input_units = ["rad", ...]   # optional, one per input ("" where unknown)
    output_units = ["rad/s", ...]
    [problem]
    name = "..."                 # default: the folder (problem.toml) or the file's stem
    description = "..."
    source = "..."
    [reference]                  # optional, free-form: reference values (documentation)

``feedback`` has no default: the sign convention decides whether a controller damps or
drives the flutter mode, and a file that does not say it cannot be read safely.  The time
unit defaults to seconds.

Data file, NPZ (``numpy.savez`` or ``savez_compressed``; read with ``allow_pickle=False``)
    ``speeds`` ``(k,)`` strictly increasing; ``A`` ``(k, n, n)``, ``B`` ``(k, n, m)``,
    ``C`` ``(k, p, n)``, ``D`` ``(k, p, m)`` stacked over the grid; optional
    ``input_names`` ``(m,)`` and ``output_names`` ``(p,)`` (unicode strings; default
    ``u1..um``, ``y1..yp``).
Data file, MATLAB ``.mat`` (v5/v7; ``save(file, ..., '-v7')``)
    The same variables.  The arrays may be stacked as MATLAB stacks model arrays, one page
    per speed (``A(:, :, j)``, ``n x n x k``: what ``ssdata`` of an ss array gives), or with
    the speed first (``k x n x n``); the layout that fits all four arrays and ``speeds`` is
    taken.  When both fit (when ``n = m = p = k``) the pages are taken with a
    :class:`~casflutter.errors.DataWarning`, since a file saved speed first is then read
    wrong: ``layout = "pages"`` or ``"speed_first"`` in the problem file says which (the
    writer of ``.mat`` files says ``"pages"``).  ``A`` may also be a cell array
    ``{A1, ..., Ak}`` (so may ``B``, ``C``, ``D``).  Names are cell arrays of strings or
    char matrices.  v7.3 (HDF5) files are refused with the fix.

Signal names, in the data file and in ``controls`` / ``measurements``, are taken without
surrounding blanks (a MATLAB char matrix pads its rows), so ``"q "`` and ``"q"`` are the
same signal.

Every inconsistency is an error before any work: a ragged or non-numeric array, a non-finite
entry (named with its index), speeds not strictly increasing, a matrix size (the state
dimension among them) that changes along the grid, no states (a static plant has no
flutter), names that do not match the sizes, an unknown key in the problem file (with the
closest allowed one), a missing data file.
"""

from __future__ import annotations

import difflib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np
from scipy.io import savemat

from .._format import result_repr
from .._outputs import atomic_file, check_output_path
from .._resources import read_toml
from ..errors import ConfigError, DataError, DimensionError
from ._family_arrays import (ARRAYS, check_grid_speeds, check_layout, check_stack,
                             check_state_stack, read_family_arrays)

__all__ = ["FAMILY_KIND", "INTERPOLATIONS", "FEEDBACK_CONVENTIONS", "FamilyFile",
           "read_family_file"]

#: ``kind`` of a gridded plant-family problem file.
FAMILY_KIND = "plant_family"
#: Interpolations between grid speeds a family file may ask for.
INTERPOLATIONS = ("linear",)
#: Feedback conventions (``u = -K y``, ``u = +K y``).
FEEDBACK_CONVENTIONS = ("negative", "positive")

_TOP_KEYS = ("kind", "file", "speed_unit", "time_unit", "feedback", "interpolation",
             "layout", "controls", "measurements", "input_units", "output_units", "problem",
             "reference")
_PROBLEM_KEYS = ("name", "description", "source")


def _names(what: str, names, size: int, default: str) -> tuple[str, ...]:
    out = tuple(str(s).strip() for s in names) if len(names) else \
        tuple(f"{default}{i + 1}" for i in range(size))
    if len(out) != size:
        signals = ("inputs (columns of B and D)" if what == "input_names"
                   else "outputs (rows of C and D)")
        raise DimensionError(f"{what} has {len(out)} names for {size} {signals}; give one "
                             "name per signal")
    return out


@dataclass(frozen=True, eq=False)
class FamilyFile:
    """A gridded plant family as read from (or to be written to) a family file.

    The record of the file: arrays and descriptions, checked on construction.  The
    family itself (interpolation, the plant at any speed) is
    :class:`casflutter.aeroelastic.GriddedFamily`, built by
    :func:`casflutter.aeroelastic.load_family`.

    Parameters
    ----------
    speeds : array_like, shape (k,)
        Grid speeds, strictly increasing.
    A, B, C, D : array_like
        ``(k, n, n)``, ``(k, n, m)``, ``(k, p, n)``, ``(k, p, m)``.
    speed_unit : str
        Unit of the speeds.
    feedback : {"negative", "positive"}
        How a controller is applied (module docstring).
    time_unit : str
        Unit of time of the models.
    interpolation : {"linear"}
        Between grid speeds.
    name, description, source : str
        For messages and reports.
    input_names, output_names : sequence of str, optional
        One per input / output (default ``u1..um``, ``y1..yp``).
    controls, measurements : sequence of str, optional
        Roles by name (default all inputs, all outputs).  Every name (these,
        ``input_names`` and ``output_names``) is taken without surrounding blanks.
    input_units, output_units : sequence of str, optional
        One per signal.
    reference : dict, optional
        Reference values (documentation; e.g. the flutter speed of the model the grid
        was sampled from).
    path, data_path : Path, optional
        The problem file and the data file it was read from.

    Raises
    ------
    DimensionError
        Arrays ragged, non-finite or of inconsistent sizes, no states (``n = 0``); names
        that do not match them.
    ConfigError
        Speeds not strictly increasing, an unknown feedback convention or interpolation.
    """

    __repr__ = result_repr

    speeds: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    speed_unit: str
    feedback: str
    time_unit: str = "s"
    interpolation: str = "linear"
    name: str = "plant family"
    description: str = ""
    source: str = ""
    input_names: tuple = ()
    output_names: tuple = ()
    controls: tuple | None = None
    measurements: tuple | None = None
    input_units: tuple = ()
    output_units: tuple = ()
    reference: dict = field(default_factory=dict)
    path: Path | None = None
    data_path: Path | None = None

    def __post_init__(self):
        v = check_grid_speeds(self.speeds)
        k = v.size
        A = check_state_stack(self.A, k)
        n = A.shape[1]
        B = check_stack("B", self.B, k, n, None)
        C = check_stack("C", self.C, k, None, n)
        D = check_stack("D", self.D, k, C.shape[1], B.shape[2])
        m, p = B.shape[2], C.shape[1]
        if self.feedback not in FEEDBACK_CONVENTIONS:
            raise ConfigError(f"feedback = {self.feedback!r}: 'negative' (u = -K y, MATLAB's "
                              "feedback()) or 'positive' (u = +K y, the paper's v = K zm)")
        if self.interpolation not in INTERPOLATIONS:
            raise ConfigError(f"interpolation = {self.interpolation!r} is not available; "
                              f"allowed: {list(INTERPOLATIONS)} (elementwise between grid "
                              "speeds)")
        for key in ("speed_unit", "time_unit"):
            if not isinstance(getattr(self, key), str) or not getattr(self, key).strip():
                raise ConfigError(f"{key} must be a non-empty string (e.g. 'm/s', 's')")
        sets = {"speeds": v, "A": A, "B": B, "C": C, "D": D,
                "input_names": _names("input_names", self.input_names, m, "u"),
                "output_names": _names("output_names", self.output_names, p, "y"),
                "reference": dict(self.reference or {}),
                "path": None if self.path is None else Path(self.path),
                "data_path": None if self.data_path is None else Path(self.data_path)}
        for key in ("controls", "measurements"):
            value = getattr(self, key)
            sets[key] = None if value is None else tuple(str(s).strip() for s in value)
        for key in ("input_units", "output_units"):
            sets[key] = tuple(str(s) for s in getattr(self, key))
        for key, value in sets.items():
            object.__setattr__(self, key, value)

    @property
    def n_states(self) -> int:
        """n."""
        return int(self.A.shape[1])

    @property
    def n_inputs(self) -> int:
        """m."""
        return int(self.B.shape[2])

    @property
    def n_outputs(self) -> int:
        """p."""
        return int(self.C.shape[1])

    def describe(self) -> str:
        """One paragraph: name, grid, sizes, signals, conventions.

        Returns
        -------
        str
        """
        v = self.speeds
        return (f"{self.name}: {self.n_states} states, {self.n_inputs} inputs "
                f"{list(self.input_names)}, {self.n_outputs} outputs "
                f"{list(self.output_names)}, {v.size} speeds [{v[0]:g}, {v[-1]:g}] "
                f"{self.speed_unit} ({self.interpolation} between them), time in "
                f"{self.time_unit}, {self.feedback} feedback"
                + (f"; data {self.data_path}" if self.data_path is not None else ""))

    # ---------------------------------------------------------------------------- write
    def write(self, path, *, format: str = "npz", data_file: str | None = None,
              overwrite: bool = True) -> Path:
        """Write the problem file and its data file (each atomically).

        Parameters
        ----------
        path : str or Path
            The problem file (``.toml``).
        format : {"npz", "mat"}
            Data-file format (the ``.mat`` file stacks the matrices as MATLAB pages,
            ``n x n x k``, names as cell arrays; the problem file then says
            ``layout = "pages"``).
        data_file : str, optional
            Name of the data file, beside the problem file (default its stem with the
            format's suffix).
        overwrite : bool
            Replace existing files.

        Returns
        -------
        pathlib.Path
            The problem file.

        Raises
        ------
        ConfigError
            An unknown format or a data-file name with another suffix.
        OutputError
            A path that cannot be written (checked before anything is written).
        """
        if format not in ("npz", "mat"):
            raise ConfigError(f"format = {format!r}; allowed: 'npz', 'mat'")
        path = check_output_path(path, what="family file", suffixes=(".toml",),
                                 overwrite=overwrite)
        data_file = data_file or f"{path.stem}.{format}"
        if Path(data_file).suffix.lower() != f".{format}" or Path(data_file).name != data_file:
            raise ConfigError(f"data_file = {data_file!r} must be a file name (no folder) "
                              f"ending in .{format}")
        data = check_output_path(path.parent / data_file, what="family data file",
                                 overwrite=overwrite)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_file(data) as tmp:
            (self._write_npz if format == "npz" else self._write_mat)(tmp)
        with atomic_file(path) as tmp:
            tmp.write_text(self._toml(data_file, format), encoding="utf-8")
        return path

    def _write_npz(self, path: Path) -> None:
        np.savez_compressed(path, speeds=self.speeds, A=self.A, B=self.B, C=self.C,
                            D=self.D, input_names=np.array(self.input_names, dtype=str),
                            output_names=np.array(self.output_names, dtype=str))

    def _write_mat(self, path: Path) -> None:
        def cell(names):
            out = np.empty((1, len(names)), dtype=object)
            out[0, :] = list(names)
            return out

        savemat(path, {"speeds": self.speeds[None, :],
                       **{key: np.moveaxis(getattr(self, key), 0, -1) for key in ARRAYS},
                       "input_names": cell(self.input_names),
                       "output_names": cell(self.output_names)}, do_compression=True)

    def _toml(self, data_file: str, format: str) -> str:
        lines = [f"# A gridded plant family ({self.n_states} states, {self.n_inputs} inputs, "
                 f"{self.n_outputs} outputs, {self.speeds.size} speeds); layout: "
                 "casflutter/data/_family_file.py",
                 f"kind = {_toml_value(FAMILY_KIND)}",
                 f"file = {_toml_value(data_file)}",
                 f"speed_unit = {_toml_value(self.speed_unit)}",
                 f"time_unit = {_toml_value(self.time_unit)}",
                 f"feedback = {_toml_value(self.feedback)}",
                 f"interpolation = {_toml_value(self.interpolation)}"]
        if format == "mat":
            lines.append(f"layout = {_toml_value('pages')}")
        for key in ("controls", "measurements", "input_units", "output_units"):
            value = getattr(self, key)
            if value:
                lines.append(f"{key} = {_toml_value(list(value))}")
        lines += ["", "[problem]", f"name = {_toml_value(self.name)}"]
        for key in ("description", "source"):
            if getattr(self, key):
                lines.append(f"{key} = {_toml_value(getattr(self, key))}")
        lines += _toml_table("reference", self.reference)
        return "\n".join(lines) + "\n"


def _toml_value(x) -> str:
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return repr(x) if math.isfinite(x) else ("nan" if math.isnan(x) else
                                                 ("inf" if x > 0 else "-inf"))
    if isinstance(x, str):
        return json.dumps(x, ensure_ascii=False)
    if isinstance(x, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in list(x)) + "]"
    raise ConfigError(f"cannot write {x!r} ({type(x).__name__}) to a TOML file; use numbers, "
                      "strings, lists and tables")


def _toml_table(name: str, table: Mapping) -> list[str]:
    if not table:
        return []
    plain = {k: v for k, v in table.items() if not isinstance(v, Mapping)}
    lines = ["", f"[{name}]"] + [f"{k} = {_toml_value(v)}" for k, v in plain.items()] \
        if plain else []
    for k, v in table.items():
        if isinstance(v, Mapping):
            lines += _toml_table(f"{name}.{k}", v)
    return lines


# ------------------------------------------------------------------------------- read
def _check_keys(table: Mapping, allowed, where: str, source) -> None:
    for key in table:
        if key not in allowed:
            near = difflib.get_close_matches(str(key), allowed, 1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise ConfigError(f"{source}: unknown key {where}{key!r}{hint} (allowed: "
                              f"{', '.join(allowed)})")


def _string(data: Mapping, key: str, source, *, default: str | None = None) -> str:
    if key not in data:
        if default is not None:
            return default
        raise ConfigError(f"{source}: key {key!r} is missing; "
                          + {"file": "name the data file (file = \"models.npz\" or .mat)",
                             "speed_unit": "give the unit of the grid speeds (e.g. "
                                           "speed_unit = \"m/s\")",
                             "feedback": "say how a controller is applied: feedback = "
                                         "\"negative\" (u = -K y, MATLAB's feedback()) or "
                                         "\"positive\" (u = +K y, the paper's v = K zm)"
                             }.get(key, "give it"))
    value = data[key]
    if not isinstance(value, str):
        raise ConfigError(f"{source}: {key} = {value!r} must be a string")
    return value


def _strings(data: Mapping, key: str, source) -> tuple[str, ...] | None:
    if key not in data:
        return None
    value = data[key]
    if not isinstance(value, list) or not all(isinstance(s, str) for s in value):
        raise ConfigError(f"{source}: {key} = {value!r} must be a list of strings")
    return tuple(value)


def read_family_file(path) -> FamilyFile:
    """Read a plant-family problem file and its data file (module docstring).

    Parameters
    ----------
    path : str or Path
        The problem file (TOML, ``kind = "plant_family"``).

    Returns
    -------
    FamilyFile

    Raises
    ------
    ConfigError
        A missing file, invalid TOML, a missing, unknown (with the closest allowed one) or
        malformed key, an unknown feedback convention, interpolation or layout.
    DataError
        A missing or unreadable data file, or arrays, speeds or names that do not fit
        (the message names the file and the array).
    """
    path = Path(path)
    data = read_toml(path, "plant family file")
    source = f"plant family file {path}"
    if data.get("kind") != FAMILY_KIND:
        raise ConfigError(f"{source}: kind = {data.get('kind')!r}; a plant family file has "
                          f"kind = {FAMILY_KIND!r}")
    _check_keys(data, _TOP_KEYS, "", source)
    problem = data.get("problem", {})
    if not isinstance(problem, dict):
        raise ConfigError(f"{source}: [problem] must be a table (name, description, source)")
    _check_keys(problem, _PROBLEM_KEYS, "problem.", source)
    reference = data.get("reference", {})
    if not isinstance(reference, dict):
        raise ConfigError(f"{source}: [reference] must be a table")
    file = _string(data, "file", source)
    meta = {key: _string(data, key, source) for key in ("speed_unit", "feedback")}
    meta["time_unit"] = _string(data, "time_unit", source, default="s")
    meta["interpolation"] = _string(data, "interpolation", source, default="linear")
    for key in ("feedback", "interpolation"):
        allowed = FEEDBACK_CONVENTIONS if key == "feedback" else INTERPOLATIONS
        if meta[key] not in allowed:
            raise ConfigError(f"{source}: {key} = {meta[key]!r}; allowed: "
                              f"{', '.join(map(repr, allowed))}")
    try:
        layout = check_layout(data.get("layout"), Path(file).suffix)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    roles = {key: _strings(data, key, source) for key in ("controls", "measurements")}
    units = {key: _strings(data, key, source) or () for key in ("input_units", "output_units")}
    default = path.resolve().parent.name if path.name == "problem.toml" else path.stem
    info = {key: str(problem.get(key, "")) for key in ("description", "source")}
    data_path = path.parent / file
    if not data_path.is_file():
        raise DataError(f"{source}: file = {file!r}: {data_path} not found (a relative path "
                        "is taken from the problem file's folder)")
    arrays = read_family_arrays(data_path, layout=layout)
    try:
        return FamilyFile(**arrays, **meta, **roles, **units, **info,
                          name=str(problem.get("name", default)), reference=reference,
                          path=path, data_path=data_path)
    except (DimensionError, ConfigError) as exc:
        raise DataError(f"{data_path}: {exc}") from None
