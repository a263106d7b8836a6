"""JSON files for plants and controllers (``casflutter verify PLANT.json CONTROLLER.json``).

Plant file (casflutter format)::

    {"A": [[...]], "B": [[...]], "C": [[...]], "D": [[...]],
     "nmeas": 2, "ncon": 1, "Vf": 1.2, "n_delta": 2, "name": "..."}

COMPleib plant files (keys ``A, B1, B, C1, D11, D12, C, D21, D22``, as in
``problems/compleib``; ``B2`` and ``C2`` are read for ``B`` and ``C``) are also read:
``P = [[A, [B1 B]], [[C1; C], [[D11 D12]; [D21 D22]]]]`` with ``nmeas = ny`` and
``ncon = nu``.

Controller file: ``{"A", "B", "C", "D"}``; ``A``, ``B``, ``C`` may be omitted (or empty)
for a static gain ``D``.  Matrices with a zero dimension are stored with their shape
(``"shape_A"`` etc.) so that they round-trip.

Both files may describe themselves (``casflutter run`` writes ``plant.json`` and
``controller.json`` so): ``time_base`` ``{"domain": "continuous" | "discrete", "dt": ...,
"time_unit": ...}``, ``inputs`` / ``outputs`` (signal names and units),
``sign_convention``, the speeds in every unit and the verification the run found.  The
loaders read ``time_base`` (a discrete-time system is loaded with its ``dt``, so that the
continuous-time verification refuses it instead of misreading it) and ignore the other
descriptive keys.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import control
import numpy as np

from .._format import result_repr
from ..errors import DataError, DimensionError
from ._common import SystemLike, as_statespace, ssdata

__all__ = ["PlantData", "plant_to_json", "plant_from_json", "controller_to_json",
           "controller_from_json", "load_plant", "load_controller", "save_json"]

_COMPLEIB_KEYS = ("A", "B1", "B", "C1", "C", "D11", "D12", "D21")


@dataclass(frozen=True)
class PlantData:
    """A partitioned plant read from JSON.

    Attributes
    ----------
    sys : control.StateSpace
        Inputs ``[w̄; u]``, outputs ``[z; y]``.
    nmeas, ncon : int or None
        Number of measurements (last outputs) and controls (last inputs).
    Vf : float or None
        Nominal speed index (eq. 10), if the plant is an LFT in ΔV.
    n_delta : int or None
        Size of the ΔV channel (first inputs/outputs).
    name : str or None
    source_format : str
        ``"casflutter"`` or ``"compleib"``.
    """

    __repr__ = result_repr

    sys: control.StateSpace
    nmeas: int | None
    ncon: int | None
    Vf: float | None = None
    n_delta: int | None = None
    name: str | None = None
    source_format: str = "casflutter"


def _mat(d: dict, key: str, shape: tuple[int, int] | None = None) -> np.ndarray:
    raw = d.get(key)
    if raw is None and shape is not None:
        return np.zeros(shape)
    if isinstance(raw, (str, bool, dict)):
        raise DataError(f"matrix {key!r} must be a list of rows of numbers, got "
                        f"{type(raw).__name__} {raw!r:.40}")
    try:
        M = np.asarray(raw if raw is not None else [], dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataError(f"matrix {key!r} is not numeric ({exc}); give a list of rows of "
                        "numbers of equal length") from None
    if f"shape_{key}" in d:
        dims = d[f"shape_{key}"]
        if not (isinstance(dims, list) and len(dims) == 2
                and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in dims)
                and dims[0] * dims[1] == M.size):
            raise DataError(f"shape_{key} = {dims!r} must be two non-negative integers whose "
                            f"product is the {M.size} entries of {key!r}")
        M = M.reshape(tuple(dims))
    elif shape is not None and M.size == 0:
        M = np.zeros(shape)
    elif M.ndim == 1 and M.size:
        raise DataError(f"matrix {key!r} must be a list of rows (2-D), got a flat list")
    if M.ndim != 2 and M.size:
        raise DataError(f"matrix {key!r} must be 2-D, got {M.ndim}-D")
    if not np.all(np.isfinite(M)):
        raise DataError(f"matrix {key!r} contains NaN or inf")
    return M if M.ndim == 2 else M.reshape(shape or (0, 0))


def _dump(M: np.ndarray) -> list:
    return np.asarray(M, dtype=float).tolist()


def _ss_dict(sys: control.StateSpace) -> dict:
    A, B, C, D = ssdata(sys)
    out = {k: _dump(M) for k, M in zip("ABCD", (A, B, C, D))}
    for k, M in zip("ABCD", (A, B, C, D)):
        if 0 in M.shape:
            out[f"shape_{k}"] = list(M.shape)
    return out


def _dt(d: dict, what: str):
    """The sample time of a file's ``time_base`` (0: continuous time)."""
    tb = d.get("time_base")
    if tb is None:
        return 0
    if not isinstance(tb, dict) or tb.get("domain", "continuous") not in ("continuous",
                                                                          "discrete"):
        raise DataError(f"{what}: time_base = {tb!r:.80}; give {{\"domain\": \"continuous\"}} "
                        "or {\"domain\": \"discrete\", \"dt\": SECONDS}")
    if tb.get("domain", "continuous") == "continuous":
        return 0
    dt = tb.get("dt")
    if dt is None:
        return True            # discrete, sample time unspecified (python-control's rule)
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not (math.isfinite(dt)
                                                                          and dt > 0):
        raise DataError(f"{what}: time_base.dt = {dt!r} must be a positive number (or null)")
    return float(dt)


def _ss_from(d: dict, what: str) -> control.StateSpace:
    if "D" not in d:
        raise DataError(f"{what}: key 'D' is missing (keys found: {sorted(d)})")
    D = _mat(d, "D")
    p, m = D.shape
    A = _mat(d, "A", (0, 0))
    n = A.shape[0]
    B = _mat(d, "B", (n, m))
    C = _mat(d, "C", (p, n))
    if A.shape != (n, n) or B.shape != (n, m) or C.shape != (p, n):
        raise DimensionError(f"{what}: inconsistent shapes A{A.shape}, B{B.shape}, "
                             f"C{C.shape}, D{D.shape}; need A (n,n), B (n,m), C (p,n), D (p,m)")
    return control.ss(A, B, C, D, _dt(d, what))


def plant_to_json(P: SystemLike, nmeas: int, ncon: int, *, Vf: float | None = None,
                  n_delta: int | None = None, name: str | None = None) -> dict:
    """JSON-ready dict of a partitioned plant (see module docstring)."""
    P = as_statespace(P, "plant P")
    out = _ss_dict(P)
    out.update(nmeas=int(nmeas), ncon=int(ncon))
    if Vf is not None:
        out["Vf"] = float(Vf)
    if n_delta is not None:
        out["n_delta"] = int(n_delta)
    if name is not None:
        out["name"] = str(name)
    return out


def plant_from_json(d: dict) -> PlantData:
    """Read a plant dict in casflutter or COMPleib format.

    Raises
    ------
    DataError
        Missing keys or non-numeric matrices.
    DimensionError
        Blocks whose shapes do not fit together.
    """
    if not isinstance(d, dict):
        raise DataError(f"a plant file must hold a JSON object, got {type(d).__name__}")
    name = d.get("name")
    if "B1" in d:
        # B2 / C2 are the names some COMPleib exports use for B / C (as load_compleib reads)
        d = {**{k: d[k + "2"] for k in ("B", "C") if k not in d and k + "2" in d}, **d}
        missing = [k for k in _COMPLEIB_KEYS if k not in d]
        if missing:
            raise DataError(f"COMPleib plant {name!r}: keys {missing} are missing")
        A, B1, B2 = _mat(d, "A"), _mat(d, "B1"), _mat(d, "B")
        C1, C2 = _mat(d, "C1"), _mat(d, "C")
        ny, nu = C2.shape[0], B2.shape[1]
        D11, D12, D21 = _mat(d, "D11"), _mat(d, "D12"), _mat(d, "D21")
        D22 = _mat(d, "D22", (ny, nu))
        try:
            B = np.hstack([B1, B2])
            C = np.vstack([C1, C2])
            D = np.block([[D11, D12], [D21, D22]])
            sys = control.ss(A, B, C, D)
        except ValueError as exc:
            raise DimensionError(
                f"COMPleib plant {name!r}: blocks do not fit: A{A.shape} B1{B1.shape} "
                f"B{B2.shape} C1{C1.shape} C{C2.shape} D11{D11.shape} D12{D12.shape} "
                f"D21{D21.shape} D22{D22.shape} ({exc})") from None
        return PlantData(sys, int(ny), int(nu), _opt_float(d, "Vf"), _opt_int(d, "n_delta"),
                         name, "compleib")
    sys = _ss_from(d, f"plant {name!r}")
    return PlantData(sys, _opt_int(d, "nmeas"), _opt_int(d, "ncon"), _opt_float(d, "Vf"),
                     _opt_int(d, "n_delta"), name, "casflutter")


def _opt_int(d: dict, key: str) -> int | None:
    v = d.get(key)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or not float(v).is_integer() or v < 0:
        raise DataError(f"{key!r} must be a non-negative integer, got {v!r}")
    return int(v)


def _opt_float(d: dict, key: str) -> float | None:
    v = d.get(key)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise DataError(f"{key!r} must be a number, got {v!r}")
    v = float(v)
    if not math.isfinite(v):
        raise DataError(f"{key!r} must be finite, got {v!r}")
    return v


def controller_to_json(K: SystemLike) -> dict:
    """JSON-ready dict ``{"A", "B", "C", "D"}`` of a controller (static gains included)."""
    return _ss_dict(as_statespace(K, "controller K"))


def controller_from_json(d: dict) -> control.StateSpace:
    """The controller of a dict written by :func:`controller_to_json` (or hand-written,
    with only ``"D"`` for a static gain)."""
    if not isinstance(d, dict):
        raise DataError(f"a controller file must hold a JSON object, got {type(d).__name__}")
    return _ss_from(d, "controller")


def _read(path: str | os.PathLike) -> dict:
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except FileNotFoundError:
        raise DataError(f"file not found: {path}") from None
    except IsADirectoryError:
        raise DataError(f"{path} is a folder; give the JSON file inside it") from None
    except UnicodeDecodeError as exc:
        raise DataError(f"{path} is not a UTF-8 text file ({exc.reason} at byte {exc.start}); "
                        "give a JSON file") from None
    except json.JSONDecodeError as exc:
        raise DataError(f"{path} is not valid JSON: {exc}") from None
    except RecursionError:
        raise DataError(f"{path}: JSON nested too deeply to be a plant or controller") from None
    except OSError as exc:
        raise DataError(f"{path} cannot be read ({exc.strerror or exc})") from None


def load_plant(path: str | os.PathLike) -> PlantData:
    """:func:`plant_from_json` of a file."""
    return plant_from_json(_read(path))


def load_controller(path: str | os.PathLike) -> control.StateSpace:
    """:func:`controller_from_json` of a file."""
    return controller_from_json(_read(path))


def save_json(d: dict, path: str | os.PathLike) -> None:
    """Write a dict from :func:`plant_to_json` / :func:`controller_to_json`."""
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(d, fh, indent=1)
