"""Input--output records for identification: modal displacements u, flap v, forces y.

Every loader (:meth:`IOData.from_npz`, :meth:`IOData.from_csv`, :meth:`IOData.from_mat`) and
:class:`Record` itself turn a file or an array that cannot be used into a
:class:`~casflutter.errors.DataError` naming the file or signal, what is wrong and what to
do; no other exception comes out of them for bad input.
"""

from __future__ import annotations

import csv
import logging
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from .._format import result_repr
from ..errors import DataError, DataWarning
from ._matfile import _mat_matrix, read_mat
from ._record import Record
from ._sampling import (TIME_NAMES, not_uniform, positive_number, significant_digits,
                        stamp_resolution, time_contradiction, time_contradicts, uniform_step)

__all__ = ["Record", "IOData"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class IOData:
    """Several input--output records sharing sampling time and channels.

    Parameters
    ----------
    records : sequence of Record
        The records; all share the channel counts.
    dt : float
        Sampling time [s].
    output_names, u_names : tuple of str, optional
        Names of the outputs ``y`` (generalised forces) and of the inputs ``u`` (modal
        displacements); default ``y1, y2, ...`` and ``u1, u2, ...``.
    v_name : str, optional
        Name of the flap input ``v``.
    meta : dict, optional
        Free-form provenance (e.g. the truth and speed the records were taken at); not
        compared by ``==``.

    Examples
    --------
    >>> import numpy as np
    >>> from casflutter.data import IOData
    >>> d = IOData.from_arrays(y=np.zeros((100, 2)), u=np.ones((100, 2)), dt=0.01)
    >>> d.n_modes, d.has_u, d.has_v
    (2, True, False)
    """

    __repr__ = result_repr

    records: tuple[Record, ...]
    dt: float
    output_names: tuple[str, ...] = ()
    u_names: tuple[str, ...] = ()
    v_name: str = "v"
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        try:
            recs = tuple(self.records)
        except TypeError:
            raise DataError(f"records must be a sequence of Record, got "
                            f"{type(self.records).__name__}") from None
        if not recs:
            raise DataError("IOData needs at least one record")
        for r in recs:
            if not isinstance(r, Record):
                raise DataError(f"records must be Record objects, got {type(r).__name__}; "
                                "use IOData.from_arrays(y, u, v, dt) for arrays")
        object.__setattr__(self, "records", recs)
        if isinstance(self.dt, (bool, np.bool_, str, bytes)) or np.iscomplexobj(self.dt):
            raise DataError(f"sampling time dt={self.dt!r} is not a real number of seconds")
        try:
            dt = float(self.dt)
        except (TypeError, ValueError):
            raise DataError(f"sampling time dt={self.dt!r} is not a number; give the "
                            "sampling time in seconds") from None
        if not np.isfinite(dt) or dt <= 0:
            raise DataError(f"sampling time dt={self.dt!r} must be a positive number of seconds")
        object.__setattr__(self, "dt", dt)
        first = recs[0]
        for rec in recs[1:]:
            if rec.n_outputs != first.n_outputs:
                raise DataError(f"records {first.name!r} and {rec.name!r} have "
                                f"{first.n_outputs} and {rec.n_outputs} outputs")
            if (rec.u is None) != (first.u is None) or (rec.v is None) != (first.v is None):
                raise DataError(f"records {first.name!r} and {rec.name!r} have different inputs "
                                "(u/v present in one and not the other)")
        N = first.n_outputs
        names = tuple(self.output_names) or tuple(f"y{i + 1}" for i in range(N))
        if len(names) != N:
            raise DataError(f"{len(names)} output names for {N} outputs")
        object.__setattr__(self, "output_names", names)
        if first.u is not None:
            un = tuple(self.u_names) or tuple(f"u{i + 1}" for i in range(N))
            if len(un) != N:
                raise DataError(f"{len(un)} u names for {N} modal inputs")
            object.__setattr__(self, "u_names", un)

    # -- construction -------------------------------------------------------------
    @classmethod
    def from_arrays(cls, y, u=None, v=None, dt: float = 1.0, name: str = "record",
                    **kw) -> "IOData":
        """One record from arrays ``y (K, N)``, ``u (K, N)``, ``v (K,)``.

        Parameters
        ----------
        y : array_like, shape (K, N)
            Outputs (generalised forces).
        u : array_like, shape (K, N), optional
            Modal-displacement inputs.
        v : array_like, shape (K,), optional
            Flap input.
        dt : float
            Sampling time [s].
        name : str
            Label of the record.
        **kw
            ``output_names``, ``u_names``, ``v_name``, ``meta`` of :class:`IOData`.

        Returns
        -------
        IOData
            One record of the arrays.

        Raises
        ------
        DataError
            Arrays that :class:`Record` refuses (ragged, text, complex, wrong shapes,
            NaN/inf, lengths that differ) or a ``dt`` that is not a positive number.
        """
        return cls((Record(y, u, v, name),), dt, **kw)

    @classmethod
    def from_npz(cls, path, *, dt: float | None = None) -> "IOData":
        """Load from an ``.npz`` with arrays ``y`` and optionally ``u``, ``v``, ``dt``.

        Several records: ``y_0, u_0, v_0, y_1, ...`` (suffix ``_<index>``).

        Parameters
        ----------
        path : str or path
            The ``.npz`` file.
        dt : float, optional
            Sampling time [s] when the file holds no ``dt`` array (a ``dt`` given here wins).

        Returns
        -------
        IOData
            One record per ``y`` (or ``y_<index>``) array, named after the file.

        Raises
        ------
        DataError
            A missing file, a folder, a file that is not an ``.npz`` archive (empty, a
            single ``.npy``, another zip, truncated or random bytes), object (pickled)
            arrays, a ``dt`` that is not one positive number, or records that
            :class:`Record` refuses; the message names the file.
        """
        path = _input_file(path, ".npz")
        arrays = read_npz(path)
        if dt is None:
            if "dt" not in arrays:
                raise DataError(f"{path}: no 'dt' array in the file; save it with "
                                "np.savez(..., dt=...) or pass dt=")
            dt = _scalar(arrays["dt"], f"{path}: 'dt'", "the sampling time in seconds")
        keys = set(arrays)
        try:
            if "y" in keys:
                recs = [Record(arrays["y"], arrays.get("u"), arrays.get("v"), path.stem)]
            else:
                idx = sorted(int(k[2:]) for k in keys if k.startswith("y_") and k[2:].isdigit())
                if not idx:
                    raise DataError(f"no 'y' (or 'y_0', 'y_1', ...) array; the arrays are "
                                    f"{sorted(keys)}; save the outputs as y")
                recs = [Record(arrays[f"y_{i}"], arrays.get(f"u_{i}"), arrays.get(f"v_{i}"),
                               f"{path.stem}[{i}]") for i in idx]
            out = cls(tuple(recs), dt)
        except DataError as exc:
            raise DataError(f"{path}: {exc}") from None
        _log.debug("read %d record(s) from %s", len(out.records), path)
        return out

    def to_npz(self, path) -> None:
        """Write in the format read by :meth:`from_npz`.

        Parameters
        ----------
        path : str or path
            The ``.npz`` file to write (``numpy.savez`` adds the suffix if missing).
        """
        arrays = {"dt": np.array(self.dt)}
        for i, r in enumerate(self.records):
            arrays[f"y_{i}"] = r.y
            if r.u is not None:
                arrays[f"u_{i}"] = r.u
            if r.v is not None:
                arrays[f"v_{i}"] = r.v
        np.savez(path, **arrays)

    @classmethod
    def from_csv(cls, path, *, y: Sequence[str], u: Sequence[str] | None = None,
                 v: str | None = None, time: str | None = "t", dt: float | None = None) -> "IOData":
        """Load a CSV with a header row naming the columns.

        Parameters
        ----------
        path : str or path
            The CSV file.
        y, u : list of str
            Column names of the outputs and modal inputs.
        v : str, optional
            Column of the flap input.
        time : str, optional
            Column of time stamps [s], from which ``dt`` is taken: uniform up to the
            rounding of the stamps (their written digits, and at least single precision:
            a time column saved in float32 is uniform).
        dt : float, optional
            Sampling time [s]; given, it overrides the time column (which is then only
            checked against it, as is a ``t`` or ``time`` column when ``time`` is not one).

        Returns
        -------
        IOData
            One record named after the file, the channels named after the columns.

        Warns
        -----
        DataWarning
            A column that is neither an output, an input, the flap nor the time column
            (named): the fit goes on without it, which is wrong when it is an input.  A
            ``dt`` given while the time column steps by another value (in seconds,
            milliseconds or microseconds alike): ``dt`` is used.

        Raises
        ------
        DataError
            A missing file, a folder, a file that is not UTF-8 text, no header, no data rows,
            rows with a different number of fields than the header, non-numeric entries
            (row and column named), missing or repeated columns, a channel named twice
            among ``y``, ``u`` and ``v``, a time column that is not increasing or not uniform
            beyond its stamps' rounding (the message gives the ``dt`` that overrides it), or
            records that :class:`Record` refuses.
        """
        path = _input_file(path, ".csv")
        y = [y] if isinstance(y, str) else [str(c) for c in (y or [])]
        u = [u] if isinstance(u, str) else ([str(c) for c in u] if u else None)
        if not y:
            raise DataError(f"{path}: no output column given; pass y=[names] (--y on the "
                            "command line)")
        try:
            with open(path, newline="", encoding="utf-8-sig") as fh:
                reader = csv.reader(fh)
                try:
                    header = [h.strip() for h in next(reader)]
                except StopIteration:
                    raise DataError(f"{path}: empty file; the first row must name the "
                                    "columns") from None
                rows = [(reader.line_num, row) for row in reader if any(c.strip() for c in row)]
        except UnicodeDecodeError as exc:
            raise DataError(f"{path}: not a UTF-8 text file ({exc.reason} at byte "
                            f"{exc.start}); export the data as CSV text") from None
        except csv.Error as exc:
            raise DataError(f"{path}: not a readable CSV file ({exc}); export the data as "
                            "CSV text") from None
        channels = list(y) + list(u or []) + ([v] if v else [])
        twice = sorted({c for c in channels if channels.count(c) > 1})
        if twice:
            raise DataError(f"{path}: column(s) {twice} named more than once among the outputs "
                            f"y = {list(y)}, the modal inputs u = {list(u or [])} and the flap "
                            f"v = {v!r}; name each channel once")
        want = channels + ([time] if time and dt is None else [])
        missing = [c for c in want if c not in header]
        if missing:
            raise DataError(f"{path}: column(s) {missing} not in the header {header}")
        repeated = sorted({c for c in want if header.count(c) > 1})
        if repeated:
            raise DataError(f"{path}: column(s) {repeated} appear more than once in the header; "
                            "rename them so that each name is unique")
        if not rows:
            raise DataError(f"{path}: the header names the columns but there are no data rows")
        table = np.empty((len(rows), len(header)))
        for i, (line, row) in enumerate(rows):
            if len(row) != len(header):
                raise DataError(f"{path}: line {line} has {len(row)} fields but the header has "
                                f"{len(header)}; fix the row or the header")
            for j, x in enumerate(row):
                try:
                    table[i, j] = float(x)
                except ValueError:
                    raise DataError(f"{path}: line {line}, column {header[j]!r}: {x!r} is not a "
                                    "number; fix or remove the entry") from None
        col = {name: table[:, header.index(name)] for name in header}
        if dt is None:
            if not time or time not in col:
                raise DataError(f"{path}: give dt= or a time column")
            if len(rows) < 2:
                raise DataError(f"{path}: one data row: the time column {time!r} cannot give "
                                "the sampling time; pass dt=")
            steps = np.diff(col[time])
            dt = float(np.median(steps))
            if not np.all(np.isfinite(steps)) or not dt > 0:
                raise DataError(f"{path}: time column {time!r} is not increasing; sort the "
                                "rows by time or pass dt=")
            j = header.index(time)
            digits = max(significant_digits(row[j]) for _, row in rows)
            res = stamp_resolution(col[time], None, digits)
            dt = uniform_step(col[time], res)
            if dt is None:
                raise DataError(not_uniform(str(path), f"column {time!r}", steps, res, "text"))
            clock = time
        else:
            # the records' own time column, when they carry one, must agree with dt
            clock = time if time in col else next(
                (c for c in header if c.lower() in TIME_NAMES and c not in channels), None)
            if clock is not None and len(rows) > 1 and positive_number(dt):
                step = time_contradiction(col[clock], float(dt))
                if step is not None:
                    warnings.warn(time_contradicts(str(path), "dt", float(dt), clock, step),
                                  DataWarning, stacklevel=2)
        unused = [c for c in header if c not in want and c != clock]
        if unused:
            # a record's unnamed column is most often an input the fit needs (the flap, a
            # modal displacement): without it the ROM fits the forces wrongly, with no error
            warnings.warn(f"{path}: column(s) {unused} are not used: they are not among the "
                          f"outputs y = {list(y)}, the modal inputs u = {list(u or [])} or the "
                          f"flap v = {v!r}; if one is an input of the record, name it (u=, v=; "
                          "--u/--v on the command line), else drop it from the file",
                          DataWarning, stacklevel=2)
        Y = np.column_stack([col[c] for c in y])
        U = np.column_stack([col[c] for c in u]) if u else None
        V = col[v] if v else None
        try:
            return cls((Record(Y, U, V, path.stem),), dt, output_names=tuple(y),
                       u_names=tuple(u or ()), v_name=v or "v")
        except DataError as exc:
            raise DataError(f"{path}: {exc}") from None

    @classmethod
    def from_mat(cls, path, *, y: str, u: str | None = None, v: str | None = None,
                 dt: float | str | None = None, fs: str | None = None,
                 output_names: Sequence[str] = ()) -> "IOData":
        """Load a MATLAB ``.mat`` file (``scipy.io.loadmat``, formats v4 to v7).

        Parameters
        ----------
        path : str or path
            The ``.mat`` file.
        y, u, v : str
            Variable names; matrices may be stored channels-by-samples or samples-by-channels
            (the longer axis is taken as time).
        dt : float or str, optional
            Sampling time, or the name of a variable holding it.
        fs : str, optional
            Name of a variable holding the sampling *frequency* (``dt = 1/fs``), e.g. ``"Fs"``.
        output_names : sequence of str, optional
            Names of the outputs (default ``y1, y2, ...``).

        Returns
        -------
        IOData
            One record named after the file.

        Raises
        ------
        DataError
            A missing file, a folder, a file that is not a MAT-file (or a v7.3/HDF5 one,
            which scipy does not read), no variables, a missing variable (the message lists
            the variables), a variable that is text, a cell array, a struct or more than
            2-D, a sampling time or frequency that is not one positive number, or records
            that :class:`Record` refuses.
        """
        path = _input_file(path, ".mat")
        mat = read_mat(path)
        variables = sorted(k for k in mat if not k.startswith("__"))
        if not variables:
            raise DataError(f"{path}: the MAT-file holds no variables; save y, u/v and the "
                            "sampling time (or frequency) in it")

        def get(name):
            if name not in mat:
                raise DataError(f"{path}: no variable {name!r}; variables are {variables}")
            return _mat_matrix(path, name, mat[name])

        if fs is not None:
            f = _scalar(get(fs), f"{path}: sampling frequency {fs!r}", "a frequency in Hz")
            dt = 1.0 / f
        elif isinstance(dt, str):
            dt = _scalar(get(dt), f"{path}: sampling time {dt!r}", "the sampling time in seconds")
        if dt is None:
            raise DataError(f"{path}: no sampling time: give dt= (seconds, or the name of "
                            "the variable holding them; --dt on the command line) or fs= (the "
                            "variable holding the sampling frequency; --fs)")
        Y = get(y)
        U = get(u) if u else None
        V = get(v).ravel() if v else None
        try:
            return cls((Record(Y, U, V, path.stem),), dt, output_names=tuple(output_names))
        except DataError as exc:
            raise DataError(f"{path}: {exc}") from None

    # -- access ---------------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of outputs N."""
        return self.records[0].n_outputs

    @property
    def has_u(self) -> bool:
        return self.records[0].u is not None

    @property
    def has_v(self) -> bool:
        return self.records[0].v is not None

    @property
    def n_samples(self) -> int:
        """Total number of samples over all records."""
        return sum(r.n_samples for r in self.records)

    def scales(self) -> tuple[np.ndarray, np.ndarray | None, float | None]:
        """RMS of each channel over all records (1 where a channel is identically zero).

        Returns
        -------
        sy : ndarray, shape (N,)
            Output scales.
        su : ndarray, shape (N,) or None
            Modal-input scales (None without ``u``).
        sv : float or None
            Flap-input scale (None without ``v``).
        """
        def rms(arrs):
            a = np.concatenate(arrs, axis=0)
            s = np.sqrt(np.mean(a ** 2, axis=0))
            return np.where(s > 0, s, 1.0)
        sy = rms([r.y for r in self.records])
        su = rms([r.u for r in self.records]) if self.has_u else None
        sv = float(rms([r.v for r in self.records])) if self.has_v else None
        return sy, su, sv

    def scaled(self, sy, su=None, sv=None) -> "IOData":
        """Copy with every channel divided by its scale.

        Parameters
        ----------
        sy : array_like, shape (N,)
            Output scales.
        su : array_like, shape (N,), optional
            Modal-input scales (required when the records have ``u``).
        sv : float, optional
            Flap-input scale (required when the records have ``v``).

        Returns
        -------
        IOData
            The scaled records, same names and metadata.
        """
        recs = tuple(Record(r.y / sy, None if r.u is None else r.u / su,
                            None if r.v is None else r.v / sv, r.name) for r in self.records)
        return IOData(recs, self.dt, self.output_names, self.u_names, self.v_name, self.meta)

    def window(self, start: int, stop: int | None = None) -> "IOData":
        """Samples ``start:stop`` of every record (e.g. to drop transient periods).

        Parameters
        ----------
        start : int
            First sample kept.
        stop : int, optional
            One past the last sample kept (default: the end).

        Returns
        -------
        IOData
        """
        cut = lambda x: None if x is None else x[start:stop]  # noqa: E731
        recs = tuple(Record(r.y[start:stop], cut(r.u), cut(r.v), r.name) for r in self.records)
        return IOData(recs, self.dt, self.output_names, self.u_names, self.v_name, self.meta)

    def decimated(self, factor: int) -> "IOData":
        """Every channel low-pass filtered (zero phase, ``scipy.signal.decimate``) and kept
        every ``factor``-th sample; ``dt`` grows by ``factor``.

        Parameters
        ----------
        factor : int
            Decimation factor (>= 1; 1 returns the data unchanged).

        Returns
        -------
        IOData
            The same records at ``dt * factor``.

        Raises
        ------
        DataError
            ``factor`` is not a positive integer.
        """
        from scipy.signal import decimate

        if not isinstance(factor, int) or factor < 1:
            raise DataError(f"decimation factor {factor!r} must be a positive integer")
        if factor == 1:
            return self
        dec = lambda x: None if x is None else decimate(x, factor, axis=0, zero_phase=True)  # noqa: E731
        recs = tuple(Record(dec(r.y), dec(r.u), dec(r.v), r.name) for r in self.records)
        return IOData(recs, self.dt * factor, self.output_names, self.u_names, self.v_name,
                      self.meta)

    def split(self, fraction: float) -> tuple["IOData", "IOData"]:
        """Split every record at ``fraction`` of its length into (estimation, validation).

        Parameters
        ----------
        fraction : float
            Share of each record in the first part, in (0, 1).

        Returns
        -------
        estimation, validation : IOData

        Raises
        ------
        DataError
            ``fraction`` outside (0, 1).
        """
        if not 0 < fraction < 1:
            raise DataError(f"split fraction {fraction} must be in (0, 1)")
        a, b = [], []
        for r in self.records:
            k = int(round(fraction * r.n_samples))
            cut = lambda x, s: None if x is None else x[s]  # noqa: E731
            a.append(Record(r.y[:k], cut(r.u, slice(None, k)), cut(r.v, slice(None, k)), r.name))
            b.append(Record(r.y[k:], cut(r.u, slice(k, None)), cut(r.v, slice(k, None)), r.name))
        kw = dict(output_names=self.output_names, u_names=self.u_names, v_name=self.v_name)
        return IOData(tuple(a), self.dt, **kw), IOData(tuple(b), self.dt, **kw)


# ---------------------------------------------------------------------------- file readers

def _input_file(path, suffix: str) -> Path:
    """``path`` as a Path that names an existing file (not a folder)."""
    try:
        path = Path(path)
    except TypeError:
        raise DataError(f"data file {path!r} is not a path; give a file name") from None
    if path.is_dir():
        raise DataError(f"{path} is a folder, not a {suffix} file; give the file inside it")
    if not path.exists():
        raise DataError(f"{path}: file not found; check the name and the folder")
    return path


def _scalar(value, what: str, meaning: str) -> float:
    """One finite positive number from an array, a MATLAB variable or a number."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        raise DataError(f"{what} is not a number; give {meaning}") from None
    if arr.dtype.kind not in "biuf" or isinstance(value, (bool, np.bool_)):
        raise DataError(f"{what} is not a real number (dtype {arr.dtype}); give {meaning}")
    if arr.size != 1:
        raise DataError(f"{what} must hold one number, got shape {arr.shape}; give {meaning}")
    x = float(arr.reshape(()))
    if not np.isfinite(x) or x <= 0:
        raise DataError(f"{what} = {x:g}; it must be a positive finite number ({meaning})")
    return x


def read_npz(path: Path) -> dict[str, np.ndarray]:
    """Every array of an ``.npz`` archive, or a DataError that says what the file is."""
    with open(path, "rb") as fh:
        head = fh.read(6)
    if not head:
        raise DataError(f"{path}: empty file (0 bytes); write it with np.savez(path, y=..., "
                        "u=..., dt=...)")
    if head == b"\x93NUMPY":
        raise DataError(f"{path}: a single .npy array, not an .npz archive; save the arrays "
                        "with np.savez(path, y=..., u=..., dt=...)")
    if not head.startswith(b"PK"):
        raise DataError(f"{path}: not an .npz archive (no zip signature); save the arrays "
                        "with np.savez(path, y=..., u=..., dt=...)")
    arrays: dict[str, np.ndarray] = {}
    try:
        with np.load(path, allow_pickle=False) as z:
            members = [n for n in z.zip.namelist() if n.endswith(".npy")]
            if not members:
                raise DataError(f"{path}: a zip archive without .npy arrays (members "
                                f"{z.zip.namelist()[:8]}), not an .npz; save the arrays with "
                                "np.savez(path, y=..., u=..., dt=...)")
            for key in z.files:
                if f"{key}.npy" in members or key in members:
                    arrays[key] = z[key]
    except DataError:
        raise
    except ValueError as exc:
        if "pickle" in str(exc):
            raise DataError(f"{path}: holds object (pickled) arrays, which are not read for "
                            "safety; save plain numeric arrays (np.savez with float "
                            "arrays)") from None
        raise DataError(f"{path}: cannot be read as an .npz archive ({exc}); the file may be "
                        "truncated or corrupt -- write it again with np.savez") from None
    except Exception as exc:  # noqa: BLE001 - any failure to parse the file is bad data
        raise DataError(f"{path}: cannot be read as an .npz archive ({type(exc).__name__}: "
                        f"{exc}); the file may be truncated or corrupt -- write it again "
                        "with np.savez") from None
    return arrays
