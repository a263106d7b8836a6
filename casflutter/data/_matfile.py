"""Reading MATLAB files safely: the MAT v5 layout is checked before scipy parses it.

``scipy.io.loadmat`` parses MAT v5 data elements in compiled code that trusts the sizes
written in the file: a truncated download or a flipped byte (a data element whose declared
size runs past its parent, a "small" element that claims more than 4 bytes, an unknown
data type) can crash the whole Python process with a segmentation fault instead of raising.
:func:`read_mat` walks the element tree of the file first (tags, sizes, data types, array
dimensions against the bytes present, compressed elements inflated with :mod:`zlib`) and
raises :class:`~casflutter.errors.DataError` on anything inconsistent; only a file whose
layout holds together reaches scipy.

The layout is MathWorks' "MAT-File Format" (version 5): a 128-byte header, then data
elements, each an 8-byte tag ``(data type, number of bytes)`` -- or a 4-byte "small" tag
whose upper 16 bits hold the size (at most 4 bytes of data) -- padded to 8 bytes; a
``miMATRIX`` element holds sub-elements (array flags, dimensions, name, data), and a
``miCOMPRESSED`` element holds zlib-compressed elements.

:func:`_mat_matrix` turns one variable into the samples-by-channels float matrix the records
need, or a DataError that says what the variable is instead.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
from scipy.io import loadmat

from ..errors import DataError

__all__ = ["read_mat", "check_mat5_layout", "mat_strings"]

_MI_MATRIX, _MI_COMPRESSED = 14, 15
#: numeric/text data types and their item sizes (miINT8 ... miUTF32)
_ITEM = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8, 16: 1, 17: 2, 18: 4}
_MX_CELL, _MX_STRUCT, _MX_OBJECT, _MX_CHAR, _MX_SPARSE = 1, 2, 3, 4, 5
_MX_NUMERIC = set(range(6, 16))
_MAX_DEPTH = 32

_FIX = "save it again from MATLAB with save(file, ..., '-v7')"


class _Bad(Exception):
    """Internal: the layout is inconsistent (turned into a DataError with the path)."""


def _tags(buf: bytes, start: int, stop: int, endian: str):
    """Yield ``(data type, payload start, payload size)`` of the elements in ``buf[start:stop]``."""
    pos = start
    while pos < stop:
        if stop - pos < 8:
            raise _Bad(f"{stop - pos} stray bytes at offset {pos} (a tag needs 8)")
        word, size = struct.unpack_from(endian + "II", buf, pos)
        if word >> 16:  # small data element: size in the upper half, data in the next 4 bytes
            dtype, small = word & 0xFFFF, word >> 16
            if small > 4:
                raise _Bad(f"a small data element at offset {pos} claims {small} bytes "
                           "(at most 4)")
            yield dtype, pos + 4, small
            pos += 8
            continue
        end = pos + 8 + size
        if end > stop:
            raise _Bad(f"the element at offset {pos} declares {size} bytes, but only "
                       f"{stop - pos - 8} remain")
        yield word, pos + 8, size
        pos = pos + 8 + ((size + 7) // 8) * 8 if word != _MI_COMPRESSED else end


def _matrix(buf: bytes, start: int, size: int, endian: str, depth: int) -> None:
    """Check one ``miMATRIX`` payload: flags, dimensions, name, then the data elements."""
    if depth > _MAX_DEPTH:
        raise _Bad(f"arrays nested deeper than {_MAX_DEPTH} levels")
    if size == 0:  # an empty placeholder (e.g. an empty cell)
        return
    elements = list(_tags(buf, start, start + size, endian))
    if len(elements) < 3:
        raise _Bad(f"an array at offset {start} has {len(elements)} parts (flags, "
                   "dimensions and name at least)")
    (ft, fpos, fsize), (dt, dpos, dsize), (nt, _, nsize) = elements[:3]
    if ft != 6 or fsize != 8:
        raise _Bad(f"the array flags at offset {fpos} are not 8 bytes of miUINT32")
    flags = struct.unpack_from(endian + "I", buf, fpos)[0]
    mx_class, is_complex = flags & 0xFF, bool(flags & 0x0800)
    if not 1 <= mx_class <= 15:
        raise _Bad(f"unknown array class {mx_class} at offset {fpos}")
    if dt != 5 or dsize < 8 or dsize % 4:
        raise _Bad(f"the dimensions at offset {dpos} are not at least two miINT32")
    dims = struct.unpack_from(endian + f"{dsize // 4}i", buf, dpos)
    if min(dims) < 0:
        raise _Bad(f"negative array dimension {min(dims)} at offset {dpos}")
    if nt not in (1, 2):
        raise _Bad(f"the array name at offset {start} is not text (data type {nt})")
    count = 1
    for d in dims:
        count *= d
    rest = elements[3:]
    if mx_class in _MX_NUMERIC or mx_class == _MX_CHAR:
        if len(rest) != 1 + is_complex:
            raise _Bad(f"a {'complex' if is_complex else 'real'} array at offset {start} has "
                       f"{len(rest)} data parts (real, and imaginary if complex)")
        for t, p, s in rest:
            if t not in _ITEM:
                raise _Bad(f"unknown data type {t} at offset {p}")
            if t != 16 and s != count * _ITEM[t]:  # UTF-8 text has no fixed item size
                raise _Bad(f"the data at offset {p} has {s} bytes for {count} elements of "
                           f"{_ITEM[t]} bytes")
    elif mx_class == _MX_CELL:
        if len(rest) != count:
            raise _Bad(f"a cell array at offset {start} has {len(rest)} of {count} cells")
        for t, p, s in rest:
            if t != _MI_MATRIX:
                raise _Bad(f"a cell at offset {p} is not an array")
            _matrix(buf, p, s, endian, depth + 1)
    elif mx_class in (_MX_STRUCT, _MX_OBJECT):
        if mx_class == _MX_OBJECT:  # the class name comes first
            if not rest or rest[0][0] not in (1, 2):
                raise _Bad(f"an object at offset {start} has no class name")
            rest = rest[1:]
        if len(rest) < 2 or rest[0][0] != 5 or rest[0][2] != 4 or rest[1][0] not in (1, 2):
            raise _Bad(f"a struct at offset {start} has no field-name length and names")
        name_len = struct.unpack_from(endian + "i", buf, rest[0][1])[0]
        if name_len <= 0 or rest[1][2] % name_len:
            raise _Bad(f"a struct at offset {start} has field names of length {name_len} "
                       f"in {rest[1][2]} bytes")
        n_fields = rest[1][2] // name_len
        fields = rest[2:]
        if len(fields) != count * n_fields:
            raise _Bad(f"a struct at offset {start} has {len(fields)} field values for "
                       f"{count} elements of {n_fields} fields")
        for t, p, s in fields:
            if t != _MI_MATRIX:
                raise _Bad(f"a struct field at offset {p} is not an array")
            _matrix(buf, p, s, endian, depth + 1)
    elif mx_class == _MX_SPARSE:
        if len(rest) != 3 + is_complex:
            raise _Bad(f"a sparse array at offset {start} has {len(rest)} parts "
                       "(row indices, column pointers, values and imaginary values if complex)")
        (it, _, isz), (jt, _, jsz) = rest[:2]
        if it not in (5, 6) or jt not in (5, 6) or isz % 4 or jsz != 4 * (dims[-1] + 1):
            raise _Bad(f"the sparse indices at offset {start} do not match its "
                       f"{dims[-1]} columns")
        for t, p, s in rest[2:]:
            if t not in _ITEM or s % _ITEM[t] or s // _ITEM[t] > isz // 4:
                raise _Bad(f"the sparse values at offset {p} do not match the row indices")
    else:  # function handles and other opaque classes: bounds only
        for t, p, s in rest:
            if t == _MI_MATRIX:
                _matrix(buf, p, s, endian, depth + 1)


def _elements(buf: bytes, start: int, endian: str, depth: int) -> None:
    for t, p, s in _tags(buf, start, len(buf), endian):
        if t == _MI_MATRIX:
            _matrix(buf, p, s, endian, depth)
        elif t == _MI_COMPRESSED:
            if depth > 0:
                raise _Bad("a compressed element inside a compressed element")
            try:
                inner = zlib.decompress(buf[p:p + s])
            except zlib.error as exc:
                raise _Bad(f"the compressed element at offset {p} does not inflate "
                           f"({exc})") from None
            _elements(inner, 0, endian, depth + 1)
        else:
            raise _Bad(f"a top-level element of data type {t} at offset {p - 8} (a variable "
                       "is miMATRIX or miCOMPRESSED)")


def check_mat5_layout(buf: bytes) -> None:
    """Check the element tree of a MAT v5 file held in ``buf``.

    Parameters
    ----------
    buf : bytes
        The whole file (header included).

    Raises
    ------
    DataError
        The layout is inconsistent (the message names the offset and what is wrong).
    """
    if len(buf) < 128:
        raise DataError(f"a MAT v5 file has a 128-byte header; this one has {len(buf)} bytes")
    marker = buf[126:128]
    if marker not in (b"IM", b"MI"):
        raise DataError(f"the MAT v5 endian indicator is {marker!r} (expected 'IM' or 'MI')")
    endian = "<" if marker == b"IM" else ">"
    try:
        _elements(buf, 128, endian, 0)
    except _Bad as exc:
        raise DataError(f"corrupt MAT v5 layout: {exc}") from None
    except struct.error as exc:
        raise DataError(f"corrupt MAT v5 layout: {exc}") from None


def _is_mat5(head: bytes) -> bool:
    """A MAT v5 header: text, then version 0x0100 and the endian indicator at 124..128."""
    return len(head) >= 128 and head[124:128] in (b"\x00\x01IM", b"\x01\x00MI")


def read_mat(path) -> dict:
    """``scipy.io.loadmat`` of a file whose MAT v5 layout has been checked first.

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file (v4, v5 or v7; v7.3 HDF5 files are refused with the fix).

    Returns
    -------
    dict
        Variable name -> value, as :func:`scipy.io.loadmat` returns it.

    Raises
    ------
    DataError
        An empty file, a v7.3 file, a corrupt layout, or any failure to parse it.
    """
    path = Path(path)
    buf = path.read_bytes()
    if not buf:
        raise DataError(f"{path}: empty file (0 bytes); {_FIX}")
    if len(buf) >= 128 and buf[124:128] in (b"\x00\x02IM", b"\x02\x00MI"):
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file, which scipy cannot read; {_FIX}, "
                        "or read it with h5py and build the arrays yourself")
    if _is_mat5(buf):
        try:
            check_mat5_layout(buf)
        except DataError as exc:
            raise DataError(f"{path}: {exc}; the file is truncated or corrupt -- "
                            f"{_FIX}") from None
    try:
        return loadmat(path)
    except NotImplementedError as exc:  # v7.3 detected by scipy
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file, which scipy cannot read ({exc}); "
                        f"{_FIX}") from None
    except Exception as exc:  # noqa: BLE001 - any failure to parse the file is bad data
        raise DataError(f"{path}: cannot be read as a MAT-file ({type(exc).__name__}: {exc}); "
                        f"the file may be truncated or not a MAT-file -- {_FIX}") from None


def mat_strings(arr, what: str = "names") -> tuple[str, ...]:
    """Strings from what :func:`read_mat` returns for a cell array of strings or a char matrix.

    Parameters
    ----------
    arr : array_like
        A ``loadmat`` cell array (object array of char arrays) or char matrix (one string
        per row).
    what : str
        The variable's name, for the message.

    Returns
    -------
    tuple of str
        Stripped of surrounding blanks (a char matrix pads its rows).

    Raises
    ------
    DataError
        Anything else (numbers, structs).
    """
    a = np.asarray(arr)
    if a.dtype == object:
        return tuple(str(np.asarray(x).ravel()[0]).strip() if np.asarray(x).size else ""
                     for x in a.ravel())
    if a.dtype.kind == "U":
        return tuple(str(s).strip() for s in a.ravel())
    raise DataError(f"{what} must be a cell array of strings or a char matrix, got "
                    f"dtype {a.dtype}")


def _mat_matrix(path: Path, name: str, value) -> np.ndarray:
    """A numeric MATLAB variable as a float array, samples along the first axis."""
    import scipy.sparse

    if scipy.sparse.issparse(value):
        value = value.toarray()
    arr = np.asarray(value)
    if arr.dtype.names:
        raise DataError(f"{path}: variable {name!r} is a struct (fields "
                        f"{list(arr.dtype.names)}); save the numeric field as its own variable "
                        "and name that one")
    if arr.dtype.kind in "USa":
        raise DataError(f"{path}: variable {name!r} holds text, not numbers; name a numeric "
                        "matrix")
    if arr.dtype.kind == "O":
        raise DataError(f"{path}: variable {name!r} is a cell array or an object; save the "
                        "numbers as a plain matrix (cell2mat in MATLAB) and name that one")
    if arr.dtype.kind == "c":
        raise DataError(f"{path}: variable {name!r} is complex; the records are real time "
                        "series -- save real(...) if the imaginary part is rounding noise")
    if arr.dtype.kind not in "biuf":
        raise DataError(f"{path}: variable {name!r} has MATLAB type {arr.dtype}, not a "
                        "numeric matrix")
    if arr.size == 0:
        raise DataError(f"{path}: variable {name!r} is empty (size {arr.shape})")
    if arr.ndim > 2:
        raise DataError(f"{path}: variable {name!r} is {arr.ndim}-D (size {arr.shape}); give "
                        "a samples-by-channels matrix")
    arr = arr.astype(float)
    if arr.ndim == 2 and arr.shape[0] < arr.shape[1]:
        arr = arr.T
    return arr
