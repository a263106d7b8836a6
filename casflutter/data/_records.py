"""Input--output records for identification: modal displacements u, flap v, forces y."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import DataError

__all__ = ["Record", "IOData"]


def _check_finite(name: str, arr: np.ndarray, record: str) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise DataError(f"record {record!r}: signal {name} has {int(bad.sum())} NaN/inf "
                        f"value(s), first at sample {int(idx[0])}; remove or interpolate them")


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

    y: np.ndarray
    u: np.ndarray | None = None
    v: np.ndarray | None = None
    name: str = "record"

    def __post_init__(self):
        y = np.asarray(self.y, dtype=float)
        if y.ndim == 1:
            y = y[:, None]
        if y.ndim != 2:
            raise DataError(f"record {self.name!r}: y must be (samples, outputs), got {y.shape}")
        K = y.shape[0]
        _check_finite("y", y, self.name)
        object.__setattr__(self, "y", y)
        if self.u is not None:
            u = np.asarray(self.u, dtype=float)
            u = u[:, None] if u.ndim == 1 else u
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
            v = np.asarray(self.v, dtype=float)
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


@dataclass(frozen=True)
class IOData:
    """Several input--output records sharing sampling time and channels.

    Parameters
    ----------
    records : sequence of Record
    dt : float
        Sampling time [s].
    output_names, u_names : tuple of str, optional
    v_name : str, optional

    Examples
    --------
    >>> import numpy as np
    >>> from casflutter.data import IOData
    >>> d = IOData.from_arrays(y=np.zeros((100, 2)), u=np.ones((100, 2)), dt=0.01)
    >>> d.n_modes, d.has_u, d.has_v
    (2, True, False)
    """

    records: tuple[Record, ...]
    dt: float
    output_names: tuple[str, ...] = ()
    u_names: tuple[str, ...] = ()
    v_name: str = "v"
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        recs = tuple(self.records)
        if not recs:
            raise DataError("IOData needs at least one record")
        object.__setattr__(self, "records", recs)
        try:
            dt = float(self.dt)
        except (TypeError, ValueError):
            raise DataError(f"sampling time dt={self.dt!r} is not a number") from None
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
        """One record from arrays ``y (K, N)``, ``u (K, N)``, ``v (K,)``."""
        return cls((Record(y, u, v, name),), dt, **kw)

    @classmethod
    def from_npz(cls, path, *, dt: float | None = None) -> "IOData":
        """Load from an ``.npz`` with arrays ``y`` and optionally ``u``, ``v``, ``dt``.

        Several records: ``y_0, u_0, v_0, y_1, ...`` (suffix ``_<index>``).
        """
        path = Path(path)
        with np.load(path, allow_pickle=False) as z:
            keys = set(z.files)
            if dt is None:
                if "dt" not in keys:
                    raise DataError(f"{path}: no 'dt' array in the file; pass dt=")
                dt = float(np.asarray(z["dt"]).ravel()[0])
            if "y" in keys:
                recs = [Record(z["y"], z["u"] if "u" in keys else None,
                               z["v"] if "v" in keys else None, path.stem)]
            else:
                idx = sorted(int(k[2:]) for k in keys if k.startswith("y_") and k[2:].isdigit())
                if not idx:
                    raise DataError(f"{path}: no 'y' (or 'y_0', 'y_1', ...) array; keys are "
                                    f"{sorted(keys)}")
                recs = [Record(z[f"y_{i}"], z[f"u_{i}"] if f"u_{i}" in keys else None,
                               z[f"v_{i}"] if f"v_{i}" in keys else None, f"{path.stem}[{i}]")
                        for i in idx]
        return cls(tuple(recs), dt)

    def to_npz(self, path) -> None:
        """Write in the format read by :meth:`from_npz`."""
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
        y, u : list of str
            Column names of the outputs and modal inputs.
        v : str, optional
            Column of the flap input.
        time : str, optional
            Column of time stamps, from which ``dt`` is taken (must be uniform).
        dt : float, optional
            Sampling time when there is no time column.
        """
        path = Path(path)
        with open(path, newline="") as fh:
            reader = csv.reader(fh)
            try:
                header = [h.strip() for h in next(reader)]
            except StopIteration:
                raise DataError(f"{path}: empty file") from None
            rows = [row for row in reader if row]
        want = list(y) + list(u or []) + ([v] if v else []) + ([time] if time and dt is None else [])
        missing = [c for c in want if c not in header]
        if missing:
            raise DataError(f"{path}: column(s) {missing} not in the header {header}")
        try:
            table = np.array([[float(x) for x in row] for row in rows], dtype=float)
        except ValueError as exc:
            raise DataError(f"{path}: non-numeric entry ({exc})") from None
        col = {name: table[:, header.index(name)] for name in header}
        if dt is None:
            if not time or time not in col:
                raise DataError(f"{path}: give dt= or a time column")
            steps = np.diff(col[time])
            dt = float(np.median(steps))
            if not np.allclose(steps, dt, rtol=1e-6, atol=1e-12):
                raise DataError(f"{path}: time column {time!r} is not uniformly sampled "
                                f"(steps from {steps.min():g} to {steps.max():g}); resample first")
        Y = np.column_stack([col[c] for c in y])
        U = np.column_stack([col[c] for c in u]) if u else None
        V = col[v] if v else None
        return cls((Record(Y, U, V, path.stem),), dt, output_names=tuple(y),
                   u_names=tuple(u or ()), v_name=v or "v")

    @classmethod
    def from_mat(cls, path, *, y: str, u: str | None = None, v: str | None = None,
                 dt: float | str | None = None, fs: str | None = None,
                 output_names: Sequence[str] = ()) -> "IOData":
        """Load a MATLAB ``.mat`` file (``scipy.io.loadmat``).

        Parameters
        ----------
        y, u, v : str
            Variable names; matrices may be stored channels-by-samples or samples-by-channels
            (the longer axis is taken as time).
        dt : float or str, optional
            Sampling time, or the name of a variable holding it.
        fs : str, optional
            Name of a variable holding the sampling *frequency* (``dt = 1/fs``), e.g. ``"Fs"``.
        """
        from scipy.io import loadmat

        path = Path(path)
        try:
            mat = loadmat(path)
        except (OSError, ValueError) as exc:
            raise DataError(f"{path}: cannot read as a .mat file ({exc})") from None

        def get(name):
            if name not in mat:
                keys = sorted(k for k in mat if not k.startswith("__"))
                raise DataError(f"{path}: no variable {name!r}; variables are {keys}")
            arr = np.asarray(mat[name], dtype=float)
            if arr.ndim == 2 and arr.shape[0] < arr.shape[1]:
                arr = arr.T
            return arr

        if fs is not None:
            dt = 1.0 / float(get(fs).ravel()[0])
        elif isinstance(dt, str):
            dt = float(get(dt).ravel()[0])
        if dt is None:
            raise DataError(f"{path}: give dt= (seconds or a variable name) or fs=")
        Y = get(y)
        U = get(u) if u else None
        V = get(v).ravel() if v else None
        return cls((Record(Y, U, V, path.stem),), dt, output_names=tuple(output_names))

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
        """RMS of each channel over all records (1 where a channel is identically zero)."""
        def rms(arrs):
            a = np.concatenate(arrs, axis=0)
            s = np.sqrt(np.mean(a ** 2, axis=0))
            return np.where(s > 0, s, 1.0)
        sy = rms([r.y for r in self.records])
        su = rms([r.u for r in self.records]) if self.has_u else None
        sv = float(rms([r.v for r in self.records])) if self.has_v else None
        return sy, su, sv

    def scaled(self, sy, su=None, sv=None) -> "IOData":
        """Copy with every channel divided by its scale."""
        recs = tuple(Record(r.y / sy, None if r.u is None else r.u / su,
                            None if r.v is None else r.v / sv, r.name) for r in self.records)
        return IOData(recs, self.dt, self.output_names, self.u_names, self.v_name, self.meta)

    def window(self, start: int, stop: int | None = None) -> "IOData":
        """Samples ``start:stop`` of every record (e.g. to drop transient periods)."""
        cut = lambda x: None if x is None else x[start:stop]  # noqa: E731
        recs = tuple(Record(r.y[start:stop], cut(r.u), cut(r.v), r.name) for r in self.records)
        return IOData(recs, self.dt, self.output_names, self.u_names, self.v_name, self.meta)

    def decimated(self, factor: int) -> "IOData":
        """Every channel low-pass filtered (zero phase, ``scipy.signal.decimate``) and kept
        every ``factor``-th sample; ``dt`` grows by ``factor``."""
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
        """Split every record at ``fraction`` of its length into (estimation, validation)."""
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
