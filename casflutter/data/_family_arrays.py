"""The arrays of a gridded plant-family data file, and their checks.

Reads ``.npz`` and MATLAB ``.mat`` data files (the layouts are described in
:mod:`._family_file`) into float arrays stacked speed first, and checks grid speeds and
stacked matrices (used also by :class:`casflutter.aeroelastic.GriddedFamily`): every
inconsistency is named (the array, the index of a non-finite entry, the speed where a
matrix changes size).  A ``.mat`` file whose arrays fit both of its layouts (MATLAB pages and
speed first, when ``n = m = p = k``) is read as pages with a
:class:`~casflutter.errors.DataWarning`, unless the layout is given.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, DataError, DataWarning, DimensionError
from ._matfile import mat_strings, read_mat

__all__ = ["check_grid_speeds", "check_layout", "check_stack", "check_state_stack",
           "read_family_arrays", "ARRAYS", "LAYOUTS"]

#: The stacked matrices of a family data file.
ARRAYS = ("A", "B", "C", "D")
#: How a ``.mat`` data file stacks its matrices: MATLAB pages (``A(:, :, j)``, ``n x n x k``)
#: or speed first (``A(j, :, :)``, ``k x n x n``; an ``.npz`` file is always speed first).
LAYOUTS = ("pages", "speed_first")
_SUFFIXES = (".npz", ".mat")
_LAYOUT_WORDS = {"pages": "as MATLAB pages (A n x n x k, B n x m x k, C p x n x k, "
                          "D p x m x k)",
                 "speed_first": "speed first (A k x n x n, B k x n x m, C k x p x n, "
                                "D k x p x m)"}


def check_grid_speeds(speeds) -> np.ndarray:
    """Grid speeds as a float vector: finite, strictly increasing, at least two.

    Parameters
    ----------
    speeds : array_like
        The speeds (any shape with one non-singleton axis, e.g. MATLAB's ``1 x k``).

    Returns
    -------
    ndarray, shape (k,)

    Raises
    ------
    ConfigError
        Not numbers, fewer than two, not finite or not strictly increasing (the first
        offending pair is named).
    """
    try:
        v = np.asarray(speeds, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ConfigError("speeds is not a list of numbers") from None
    if v.size < 2 or not np.all(np.isfinite(v)):
        raise ConfigError(f"speeds must be finite and strictly increasing, at least two; "
                          f"got {v.tolist()[:8]}{' ...' if v.size > 8 else ''}")
    bad = np.flatnonzero(np.diff(v) <= 0)
    if bad.size:
        j = int(bad[0]) + 1
        raise ConfigError(f"speeds must be finite and strictly increasing: speeds[{j}] = "
                          f"{v[j]:g} follows speeds[{j - 1}] = {v[j - 1]:g}; sort the grid "
                          "(and its matrices) by speed and drop repeated speeds")
    return v


def check_stack(name: str, M, k: int, rows: int | None, cols: int | None) -> np.ndarray:
    """``M`` as a finite float array of shape ``(k, rows, cols)`` (``None``: any size).

    Parameters
    ----------
    name : str
        The array's name, for the messages.
    M : array_like
        One matrix per grid speed, stacked on the first axis.
    k : int
        Number of grid speeds.
    rows, cols : int or None
        Required sizes of each matrix.

    Returns
    -------
    ndarray

    Raises
    ------
    DimensionError
        Ragged or non-numeric, of another shape (the matrices must have the same size at
        every speed), or with a non-finite entry (its index is named).
    """
    try:
        M = np.asarray(M, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(f"{name} is not a numeric array (ragged or not numbers); give "
                             f"a ({k}, rows, cols) array, one matrix per grid speed") from None
    if M.ndim != 3 or M.shape[0] != k or (rows is not None and M.shape[1] != rows) or \
            (cols is not None and M.shape[2] != cols):
        want = f"({k}, {rows if rows is not None else 'rows'}, " \
               f"{cols if cols is not None else 'cols'})"
        raise DimensionError(f"{name} has shape {M.shape}; it must be {want}: one matrix per "
                             "grid speed, the same size at every speed")
    bad = np.argwhere(~np.isfinite(M))
    if bad.size:
        j = tuple(int(x) for x in bad[0])
        raise DimensionError(f"{name}{list(j)} is {M[j]} (not finite); {len(bad)} entries of "
                             f"{name} are not finite")
    return M


def check_state_stack(A, k: int) -> np.ndarray:
    """The stacked state matrices: :func:`check_stack`, square, and at least one state.

    Parameters
    ----------
    A : array_like
        One state matrix per grid speed, stacked on the first axis.
    k : int
        Number of grid speeds.

    Returns
    -------
    ndarray
        Shape ``(k, n, n)``, ``n >= 1``.

    Raises
    ------
    DimensionError
        As :func:`check_stack`; a matrix that is not square; no states (a static plant has
        no poles, so no flutter to find or suppress).
    """
    A = check_stack("A", A, k, None, None)
    n = A.shape[1]
    if A.shape[2] != n:
        raise DimensionError(f"A has shape {A.shape}; each A must be square (n, n)")
    if n == 0:
        raise DimensionError(f"A has shape {A.shape}: the family has no states (a static "
                             "plant, D only), and a static plant has no poles, so no flutter "
                             "to find or suppress; give the model with its dynamics (A n x n "
                             "with n >= 1, B, C at every speed)")
    return A


def check_layout(layout, suffix: str = ".mat") -> str | None:
    """``layout`` checked against :data:`LAYOUTS` and the data file's suffix.

    Parameters
    ----------
    layout : str or None
        How the data file stacks its matrices (``None``: the layout that fits).
    suffix : str
        The data file's suffix (``".npz"`` files are speed first).

    Returns
    -------
    str or None

    Raises
    ------
    ConfigError
        An unknown layout, or ``"pages"`` for an ``.npz`` file.
    """
    if layout is None:
        return None
    if not isinstance(layout, str) or layout not in LAYOUTS:
        raise ConfigError(f"layout = {layout!r}; allowed: {', '.join(map(repr, LAYOUTS))} "
                          "(how a .mat data file stacks its matrices: MATLAB pages, "
                          "A(:, :, j), or speed first, A(j, :, :))")
    if layout == "pages" and suffix.lower() == ".npz":
        raise ConfigError("layout = 'pages' is for MATLAB .mat data files; an .npz data file "
                          "is stored speed first (A k x n x n): drop layout or write "
                          "layout = 'speed_first'")
    return layout


def read_family_arrays(path, *, layout: str | None = None) -> dict[str, Any]:
    """The arrays of a family data file (``.npz`` or ``.mat``), speed axis first.

    Parameters
    ----------
    path : str or Path
        The data file.
    layout : {"pages", "speed_first"}, optional
        How a ``.mat`` file stacks its matrices (:data:`LAYOUTS`).  Default: the layout
        that fits all four arrays, the pages when both fit (with a warning).

    Returns
    -------
    dict
        ``speeds``, ``A``, ``B``, ``C``, ``D`` (float arrays, speed first) and
        ``input_names``, ``output_names`` (tuples, empty when absent).

    Warns
    -----
    DataWarning
        A ``.mat`` file whose arrays fit both layouts (``n = m = p = k``) and no
        ``layout``: they are read as pages, which is wrong for a file stored speed first.

    Raises
    ------
    ConfigError
        An unknown layout, or ``"pages"`` for an ``.npz`` file.
    DataError
        Unknown suffix, unreadable file, a missing variable, ragged or non-numeric arrays,
        a matrix size that changes along the grid, arrays that do not fit the layout, a
        v7.3 MATLAB file.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in _SUFFIXES:
        raise DataError(f"{path}: unknown suffix {path.suffix!r}; a family data file is "
                        f"{' or '.join(_SUFFIXES)}")
    layout = check_layout(layout, suffix)
    if suffix == ".npz":
        out = _read_npz(path)
    else:
        out = _read_mat(path, layout)
    for key in ("input_names", "output_names"):
        out.setdefault(key, ())
    return out


def _need(path: Path, keys) -> None:
    missing = [key for key in ("speeds", *ARRAYS) if key not in keys]
    if missing:
        raise DataError(f"{path}: no variable {missing[0]!r} (variables are {sorted(keys)}); a "
                        "family data file holds speeds (k,), A (k,n,n), B (k,n,m), C (k,p,n), "
                        "D (k,p,m)")


def _read_npz(path: Path) -> dict:
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError) as exc:
        raise DataError(f"{path}: cannot read as .npz ({exc})") from None
    with z:
        _need(path, z.files)
        out = {}
        for key in ("speeds", *ARRAYS, "input_names", "output_names"):
            if key not in z.files:
                continue
            try:
                value = z[key]
            except ValueError:   # an object array: ragged, or matrices of several sizes
                raise DataError(f"{path}: {key} is an object array (ragged: matrices of "
                                "different sizes, or not numbers); save it as one numeric "
                                "array, speed first") from None
            if key.endswith("_names"):
                if value.dtype.kind not in "US":
                    raise DataError(f"{path}: {key} must hold strings, got dtype {value.dtype}")
                value = tuple(s.decode() if isinstance(s, bytes) else str(s)
                              for s in np.atleast_1d(value).tolist())
            elif value.dtype.kind not in "biuf":
                raise DataError(f"{path}: {key} has dtype {value.dtype}; it must be real "
                                "numbers")
            out[key] = value
    return out


def _cells(path: Path, key: str, value) -> np.ndarray:
    """A MATLAB cell array of matrices, stacked speed first; sizes checked."""
    cells = [np.atleast_2d(np.asarray(c)) for c in np.asarray(value, dtype=object).ravel()]
    if not cells:
        raise DataError(f"{path}: {key} is an empty cell array")
    for j, c in enumerate(cells):
        if c.dtype.kind not in "biuf" or c.ndim != 2:
            raise DataError(f"{path}: {key}{{{j + 1}}} is not a real matrix")
        if c.shape != cells[0].shape:
            what = " (the state dimension changes along the grid)" if key == "A" else ""
            raise DataError(f"{path}: {key}{{{j + 1}}} is {c.shape[0]} x {c.shape[1]} but "
                            f"{key}{{1}} is {cells[0].shape[0]} x {cells[0].shape[1]}{what}; "
                            "every grid speed needs matrices of the same size (the same states)")
    return np.stack(cells).astype(float)


def _read_mat(path: Path, layout: str | None) -> dict:
    mat = read_mat(path)
    keys = [key for key in mat if not key.startswith("__")]
    _need(path, keys)
    out: dict[str, Any] = {"speeds": np.asarray(mat["speeds"], dtype=float).ravel()}
    k = out["speeds"].size
    raw = {}
    for key in ARRAYS:
        value = np.asarray(mat[key])
        if value.dtype == object:
            raw[key] = ("cells", _cells(path, key, value))
        elif value.dtype.kind in "biuf":
            raw[key] = ("array", value.astype(float))
        else:
            raise DataError(f"{path}: {key} has MATLAB class {value.dtype}; it must be a real "
                            "numeric array (or a cell array of matrices)")
    out.update(_mat_layout(path, raw, k, layout))
    for key in ("input_names", "output_names"):
        if key in mat:
            out[key] = mat_strings(mat[key], key)
    return out


def _mat_layout(path: Path, raw: dict, k: int, layout: str | None) -> dict:
    """The four arrays speed first: MATLAB pages (``n x n x k``) or speed first.

    ``layout`` (:data:`LAYOUTS`) says which; ``None``: the one that fits, the pages when
    both fit (with a :class:`~casflutter.errors.DataWarning` naming the way to say which).
    """
    arrays = {key: value for key, (how, value) in raw.items() if how == "cells"}
    plain = {key: value for key, (how, value) in raw.items() if how == "array"}

    def pages(M):      # MATLAB drops trailing singleton dimensions: n x 1 x k stays 3-D
        return np.moveaxis(M, -1, 0) if M.ndim == 3 and M.shape[2] == k else None

    def first(M):
        if M.ndim == 3 and M.shape[0] == k:
            return M
        return M[:, :, None] if M.ndim == 2 and M.shape[0] == k else None

    fits = {}
    for name, how in (("pages", pages), ("speed_first", first)):
        got = {key: how(M) for key, M in plain.items()}
        if all(M is not None for M in got.values()):
            cand = {**arrays, **got}
            n = cand["A"].shape[1]
            ok = (cand["A"].shape[1:] == (n, n) and cand["B"].shape[1] == n
                  and cand["C"].shape[2] == n and cand["D"].shape[1:] ==
                  (cand["C"].shape[1], cand["B"].shape[2]))
            if ok:
                fits[name] = cand
    shapes = ", ".join(f"{key} {raw[key][1].shape}" for key in ARRAYS)
    if layout is not None:
        if layout in fits:
            return fits[layout]
        other = [name for name in fits if name != layout]
        fix = (f"they do fit {other[0]!r}: set layout = {other[0]!r} or drop it" if other
               else f"stack them {_LAYOUT_WORDS[layout]}, with the same n, m, p at every "
                    "speed")
        raise DataError(f"{path}: layout = {layout!r}, but the arrays do not fit {k} speeds "
                        f"stacked {_LAYOUT_WORDS[layout]} ({shapes}); {fix}")
    if len(fits) == 2 and not all(np.array_equal(fits["pages"][key], fits["speed_first"][key])
                                  for key in ARRAYS):     # the choice matters
        warnings.warn(f"{path}: the arrays fit {k} speeds both as MATLAB pages and speed first "
                      f"({shapes}); they are read as pages (A(:, :, j) is the model at "
                      "speeds(j)), so every matrix is wrong if they were saved speed first "
                      "(A(j, :, :)).  Say which in the problem file: layout = \"speed_first\" "
                      "or layout = \"pages\" (or store A, B, C, D as cell arrays, one matrix "
                      "per speed)", DataWarning, stacklevel=4)
    if fits:
        return fits.get("pages", fits.get("speed_first"))
    raise DataError(f"{path}: the arrays do not fit {k} speeds in either layout ({shapes}); "
                    f"stack them as MATLAB pages (A n x n x {k}, B n x m x {k}, C p x n x {k}, "
                    f"D p x m x {k}) or speed first (A {k} x n x n, ...), with the same n, m, p "
                    "at every speed")
