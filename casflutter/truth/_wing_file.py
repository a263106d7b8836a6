"""A wing brought by its user: modal data with records (``kind = "wing"``) or with a table of
frequency-domain aerodynamics ``Q(ik)`` (``kind = "gaf"``), read from a TOML file.

Neither is a truth simulator: a wing file holds what an aeroelastician has -- the in-vacuo
modes (eq. 6), the sensors (eq. 7), the speed scale and either input--output records of the
generalised forces (the paper's route, identified by :mod:`casflutter.ident`) or ``Q(ik)``
(fitted by a rational-function approximation, :mod:`casflutter.realize`).  The stages that
need a simulator (the truth's flutter, LCO, closed loop and suppression) are skipped by the
driver.  Every key is checked when the file is read, before any work; a bad key, a wrong
shape, a missing record file, an unknown channel or a non-finite number raises a
:class:`~casflutter.errors.ConfigError` (the file's keys) or a
:class:`~casflutter.errors.DataError` (the record files) naming the key and the fix.  The
records' sampling is checked against the modes: the highest modal frequency must lie below
the records' Nyquist frequency ``1 / (2 dt)`` (time stamps in milliseconds are refused, with
the sampling time they would give in seconds).  A time channel is uniform up to the rounding
of its stamps as stored (a float32 channel is); a channel of the record files that
``[records]`` does not name, and a ``t`` or ``time`` channel that contradicts
``records.dt``, are a :class:`~casflutter.errors.DataWarning`.

Layout (paths are relative to the file's folder)::

    kind = "wing"                  # or "gaf"

    [problem]                      # optional: name, description, source
    name = "my_wing"

    [modes]                        # eq. 6, one entry per mode
    names = ["bending 1", "torsion 1"]       # optional
    frequencies_hz = [2.19, 10.07]           # in-vacuo natural frequencies [Hz]
    damping = [0.02, 0.02]                   # damping ratios zeta
    alpha = 14670.7                          # flow constant: u'' + ... = alpha V^2 y

    [speed]                        # the speed index V of eq. 6-8
    U_ref = 28.9                   # m/s per unit speed index: U = V U_ref
    rho = 1.225                    # kg/m^3: dynamic pressure q = rho (V U_ref)^2 / 2

    [sensors]                      # eq. 7: zm = Hs u'' (or u', u)
    kind = "acceleration"          # "acceleration", "velocity" or "displacement"
    names = ["Acc1", "Acc2"]
    units = ["m/s^2", "m/s^2"]
    rows = [[0.13, -0.29], [-0.002, 0.014]]  # one row of N mode-shape values per sensor

    [records]                      # kind = "wing": one record per file
    V0 = 0.69                      # speed index of the records (or U0 [m/s])
    files = ["records/chirp_1.csv", "records/chirp_2.npz", "records/chirp_3.mat"]
    time = "t"                     # channel of the time stamps [s] (or dt = 0.002 [s],
                                   #   which overrides a time channel)
    displacements = ["u1", "u2"]   # channels of the modal displacements, in mode order
    flap = "flap"                  # channel of the flap [rad] (optional)
    forces = ["Q1", "Q2"]          # channels of the generalised forces y, in mode order
                                   #   (eq. 6 normalisation: the modal force is alpha V0^2 y)

    [reference]                    # optional, free-form: published values for the record

    [gaf]                          # kind = "gaf"
    file = "q.npz"                 # Q(ik) table (casflutter.data.load_gaf: NPZ, CSV, .mat)
    U_range = [60.0, 200.0]        # airspeeds [m/s] of the flutter search
    method = "roger"               # RFA (casflutter.realize.RFASettings): method, n_lags,
    n_lags = 4                     #   poly_order, k_max, max_iter

A channel is a column of a CSV file (header row; :meth:`casflutter.data.IOData.from_csv`), a
1-D array of an NPZ archive or a vector variable of a MATLAB file; each file holds every
channel named.  The speed index of a GAF file is ``U / U_ref`` too; the table's own ``U_ref``,
when it has one, must agree.
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np

from ..data import GAFTable, IOData, Record, load_gaf
from ..data._matfile import read_mat
from ..data._records import read_npz
from ..data._sampling import (TIME_NAMES, not_uniform, stamp_resolution, time_contradiction,
                              time_contradicts, uniform_step)
from ..errors import ConfigError, DataError, DataWarning
from ..structure import (SENSOR_KINDS, AirspeedMixin, ModalStructure, SpeedConvention,
                         check_sensor_rows)

__all__ = ["WING_KIND", "GAF_KIND", "WingProblem", "GAFProblem"]

log = logging.getLogger("casflutter.truth.wing_file")

WING_KIND = "wing"
GAF_KIND = "gaf"

_TOP = {"kind", "problem", "modes", "speed", "sensors", "reference"}
_MODES = {"names", "frequencies_hz", "damping", "alpha"}
_SPEED = {"U_ref", "rho"}
_SENSORS = {"kind", "names", "units", "rows"}
_RECORDS = {"V0", "U0", "files", "time", "dt", "displacements", "flap", "forces"}
_RFA_KEYS = {"method", "n_lags", "poly_order", "k_max", "max_iter"}
_GAF = {"file", "U_range", "n_grid"} | _RFA_KEYS


def _table(data: Mapping, key: str, source: str, allowed: set, required=True) -> dict:
    if key not in data:
        if required:
            raise ConfigError(f"{source}: missing table [{key}]; add it (see the layout in "
                              "casflutter.truth.WingProblem)")
        return {}
    t = data[key]
    if not isinstance(t, Mapping):
        raise ConfigError(f"{source}: {key!r} must be a table ([{key}]), got {t!r}")
    unknown = sorted(k for k in t if k not in allowed)
    if unknown:
        raise ConfigError(f"{source}: unknown key {key}.{unknown[0]}; allowed in [{key}]: "
                          f"{', '.join(sorted(allowed))}")
    return dict(t)


def _need(t: dict, table: str, key: str, source: str, what: str):
    if key not in t:
        raise ConfigError(f"{source}: missing key {table}.{key}; give {what}")
    return t[key]


def _number(value, key: str, source: str, *, positive=True, allow_zero=False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{source}: {key} = {value!r} must be a finite number")
    x = float(value)
    if positive and not (x > 0 or (allow_zero and x == 0)):
        raise ConfigError(f"{source}: {key} = {x!r} must be {'>= 0' if allow_zero else '> 0'}")
    return x


def _numbers(value, key: str, source: str, n: int | None, *, allow_zero=False) -> np.ndarray:
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise ConfigError(f"{source}: {key} = {value!r} must be a list of numbers")
    if n is not None and len(value) != n:
        raise ConfigError(f"{source}: {key} has {len(value)} entries for {n} modes; give one "
                          "per mode")
    if not value:
        raise ConfigError(f"{source}: {key} is empty; give one number per mode")
    return np.array([_number(x, f"{key}[{i}]", source, allow_zero=allow_zero)
                     for i, x in enumerate(value)])


def _names(value, key: str, source: str, n: int, distinct: bool = True) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, (list, tuple)) \
            or not all(isinstance(s, str) and s.strip() for s in value):
        raise ConfigError(f"{source}: {key} = {value!r} must be a list of non-empty strings")
    if len(value) != n:
        raise ConfigError(f"{source}: {key} has {len(value)} names for {n} entries; give one "
                          "per entry")
    if distinct and len(set(value)) != len(value):
        raise ConfigError(f"{source}: {key} repeats a name; the names must be distinct")
    return tuple(s.strip() for s in value)


@dataclass(frozen=True)
class _Wing(AirspeedMixin):
    """What both kinds share: the modes, the sensors, the speed scale."""

    name: str
    structure: ModalStructure
    U_ref: float
    rho: float | None
    sensor_units: tuple[str, ...]
    path: Path
    definition: dict = field(repr=False, compare=False)

    @property
    def n_modes(self) -> int:
        """Number of modes N."""
        return self.structure.n_modes

    def modal_structure(self) -> ModalStructure:
        """Σs of eq. 6-7: the file's modes and sensors.

        Returns
        -------
        ModalStructure
        """
        return self.structure

    @property
    def params(self) -> "_Wing":
        """The wing itself (its :meth:`describe` lists the file's values)."""
        return self

    def describe(self) -> list[tuple]:
        """``(name, value, unit, meaning)`` of the file's scalars and modes (for listings).

        Returns
        -------
        list of tuple
        """
        s = self.structure
        rows = [("alpha", s.alpha, "-", "flow constant of eq. 6"),
                ("U_ref", self.U_ref, "m/s", "airspeed per unit speed index"),
                ("rho", self.rho if self.rho is not None else "-", "kg/m^3", "air density")]
        for name, w, z in zip(s.mode_names, s.omega, s.zeta):
            rows.append((f"f[{name}]", float(w / (2 * np.pi)), "Hz",
                         f"in-vacuo frequency, damping ratio {z:g}"))
        for name, unit in zip(s.sensor_names, self.sensor_units):
            rows.append((f"sensor[{name}]", s.sensor, unit or "-", "row of Hs"))
        return rows

    @property
    def speed(self) -> SpeedConvention:
        """The file's speed convention: ``V = U / U_ref``, time in seconds, ``rho`` when
        given (``structure.speed``)."""
        return self.structure.speed

    def dynamic_pressure(self, V) -> float:
        """Dynamic pressure ``q = rho (V U_ref)^2 / 2`` [Pa] at speed index ``V``.

        Raises
        ------
        ConfigError
            The file gives no ``speed.rho``.
        """
        if self.rho is None:
            raise ConfigError(f"{self.path}: no speed.rho; give the air density [kg/m^3] for "
                              "the dynamic pressure")
        return self.speed.dynamic_pressure(V)

    @staticmethod
    def _common(data: Mapping, path: Path, kind: str, extra: set) -> dict:
        source = f"wing file {path}"
        unknown = sorted(k for k in data if k not in _TOP | extra)
        if unknown:
            raise ConfigError(f"{source}: unknown key or table {unknown[0]!r} for 'kind' = "
                              f"{kind!r}; allowed: {', '.join(sorted(_TOP | extra))}")
        info = _table(data, "problem", source, {"name", "description", "source"}, False)
        modes = _table(data, "modes", source, _MODES)
        f = _numbers(_need(modes, "modes", "frequencies_hz", source,
                           "the in-vacuo natural frequencies [Hz], one per mode"),
                     "modes.frequencies_hz", source, None)
        n = f.size
        zeta = _numbers(_need(modes, "modes", "damping", source,
                              "the damping ratios, one per mode"), "modes.damping", source, n,
                        allow_zero=True)
        alpha = _number(_need(modes, "modes", "alpha", source,
                              "the flow constant alpha of eq. 6 (u'' + ... = alpha V^2 y)"),
                        "modes.alpha", source)
        mode_names = (_names(modes["names"], "modes.names", source, n) if "names" in modes
                      else tuple(f"mode {i + 1}" for i in range(n)))
        speed = _table(data, "speed", source, _SPEED)
        U_ref = _number(_need(speed, "speed", "U_ref", source,
                              "the airspeed per unit speed index [m/s] (U = V U_ref)"),
                        "speed.U_ref", source)
        rho = _number(speed["rho"], "speed.rho", source) if "rho" in speed else None
        sens = _table(data, "sensors", source, _SENSORS)
        rows = check_sensor_rows(_need(sens, "sensors", "rows", source,
                                       f"the sensor rows Hs, one list of {n} numbers per "
                                       "sensor"), n, key=f"{source}: sensors.rows",
                                 problem=f"[modes] ({n} frequencies)")
        m = len(rows)
        kind_s = sens.get("kind", "acceleration")
        if kind_s not in SENSOR_KINDS[:3]:
            raise ConfigError(f"{source}: sensors.kind = {kind_s!r}; allowed "
                              f"{', '.join(map(repr, SENSOR_KINDS[:3]))}")
        snames = (_names(sens["names"], "sensors.names", source, m) if "names" in sens
                  else tuple(f"zm[{j}]" for j in range(m)))
        units = (_names(sens["units"], "sensors.units", source, m, False) if "units" in sens
                 else ("",) * m)
        label = str(info.get("name") or (path.parent.name if path.name == "problem.toml"
                                          else path.stem))
        structure = ModalStructure(
            2 * np.pi * f, zeta, alpha, np.array(rows), kind_s, mode_names=mode_names,
            sensor_names=snames,
            speed=SpeedConvention(f"V = U / U_ref, U_ref = {U_ref:g} m/s", "s", U_ref, rho))
        return dict(name=label, structure=structure, U_ref=U_ref, rho=rho,
                    sensor_units=units, path=path, definition=dict(data))


def _no_sets(sets, path: Path, kind: str) -> None:
    sets = list(sets.items()) if isinstance(sets, Mapping) else list(sets or ())
    if sets:
        raise ConfigError(f"wing file {path}: a {kind} file has no parameters to change "
                          f"(got {sets[0]!r}); edit the file, or remove problem.set / --set")


def _channels(path: Path, names: list[str], time: str | None, dt: float | None = None
              ) -> tuple[dict, float | None, list[str], tuple | None]:
    """The named 1-D channels of an NPZ or MATLAB file, dt from the time channel, the
    file's other channels (vectors as long as the named ones, which the fit does not use),
    and, with ``dt`` given instead of a time channel, ``(name, step)`` of a time channel
    (``t`` or ``time``) the file carries anyway and that contradicts ``dt`` (else None)."""
    if path.suffix.lower() == ".npz":
        arrays, what = read_npz(path), "array"
    else:
        arrays = {k: v for k, v in read_mat(path).items() if not k.startswith("__")}
        what = "variable"
    missing = [c for c in names + ([time] if time else []) if c not in arrays]
    if missing:
        raise DataError(f"{path}: no {what} {missing[0]!r} (the file holds "
                        f"{sorted(arrays)}); fix the channel name in [records] or the file")
    out = {}
    for c in names + ([time] if time else []):
        a = np.asarray(arrays[c])
        if a.dtype.kind not in "biuf":
            raise DataError(f"{path}: {what} {c!r} has dtype {a.dtype}, not real numbers")
        if a.ndim > 2 or (a.ndim == 2 and 1 not in a.shape) or a.size < 2:
            raise DataError(f"{path}: {what} {c!r} has shape {a.shape}; a channel is one "
                            "vector of samples")
        out[c] = a.astype(float).ravel()
    n_samples = out[names[0]].size if names else 0

    def vector(a):
        a = np.asarray(a)
        return (a.dtype.kind in "biuf" and a.size == n_samples and n_samples > 1
                and (a.ndim == 1 or (a.ndim == 2 and 1 in a.shape)))

    clock, dt_file, clash = time, None, None
    if time:
        steps = np.diff(out[time])
        if not np.all(np.isfinite(steps)) or not float(np.median(steps)) > 0:
            raise DataError(f"{path}: time channel {time!r} is not increasing")
        stored = np.asarray(arrays[time]).dtype
        res = stamp_resolution(out[time], stored)
        dt_file = uniform_step(out[time], res)
        if dt_file is None:
            raise DataError(not_uniform(
                str(path), f"channel {time!r}", steps, res, str(stored),
                "give records.dt = {dt} instead of records.time (the time channel is then "
                "not read)"))
    else:
        clock = next((k for k in arrays if k.lower() in TIME_NAMES and k not in names
                      and vector(arrays[k])), None)
        if clock is not None and dt is not None:
            step = time_contradiction(np.asarray(arrays[clock], dtype=float).ravel(), dt)
            if step is not None:
                clash = (clock, step)
    unused = [k for k in arrays if k not in names and k != clock and vector(arrays[k])]
    return out, dt_file, unused, clash


def _read_record(path: Path, forces, disp, flap, time, dt
                 ) -> tuple[IOData, list[str], tuple | None]:
    """One record file as IOData, its channels that [records] does not name and a time
    channel that contradicts ``dt`` (NPZ and MAT files, :func:`_channels`; a CSV file's are
    DataWarnings of :meth:`IOData.from_csv`)."""
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return IOData.from_csv(path, y=forces, u=disp, v=flap, time=time, dt=dt), [], None
    if suffix not in (".npz", ".mat"):
        raise DataError(f"{path}: unknown suffix {path.suffix!r}; records are .csv, .npz or "
                        ".mat files")
    if not path.is_file():
        raise DataError(f"{path}: record file not found; check records.files")
    names = list(forces) + list(disp or []) + ([flap] if flap else [])
    ch, dt_file, unused, clash = _channels(path, names, time, dt)
    lengths = {c: ch[c].size for c in names}
    if len(set(lengths.values())) != 1:
        raise DataError(f"{path}: channels of different lengths {lengths}; trim them to a "
                        "common length")
    Y = np.column_stack([ch[c] for c in forces])
    U = np.column_stack([ch[c] for c in disp]) if disp else None
    Vf = ch[flap] if flap else None
    try:
        return IOData((Record(Y, U, Vf, path.stem),), dt_file if dt is None else dt,
                      output_names=tuple(forces), u_names=tuple(disp or ()),
                      v_name=flap or "v"), unused, clash
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None


def _check_sampling(structure: ModalStructure, dt: float, src: str, time: str | None
                    ) -> None:
    """Refuse records whose Nyquist frequency is not above the highest modal frequency.

    A record sampled at ``dt`` holds frequencies below ``1 / (2 dt)`` only; a mode above it
    is aliased to a wrong frequency and the ROM identified from the records is meaningless
    (most often the time stamps are in milliseconds, not seconds).
    """
    f = structure.omega / (2 * np.pi)
    i = int(np.argmax(f))
    nyquist = 0.5 / dt
    if f[i] < nyquist:
        return
    source = f"the time channel {time!r}" if time else "records.dt"
    if f[i] < nyquist * 1e3:   # in seconds, the time read as milliseconds would do
        fix = (f"Is the time in milliseconds? Then dt = {dt / 1e3:g} s (Nyquist "
               f"{nyquist * 1e3:g} Hz): " + (
                   f"give the time channel in seconds, or records.dt = {dt / 1e3:g} instead "
                   "of records.time" if time else f"give records.dt = {dt / 1e3:g} (seconds)"))
    else:
        fix = ("Give the sampling time in seconds" + (" (the time channel in seconds, or "
               "records.dt instead of records.time)" if time else " (records.dt)")
               + "; records sampled this coarsely cannot identify these modes")
    raise (DataError if time else ConfigError)(
        f"{src}: the records are sampled at dt = {dt:g} s (from {source}): their Nyquist "
        f"frequency {nyquist:g} Hz is not above mode {structure.mode_names[i]!r} at "
        f"{f[i]:g} Hz, so they cannot show the modes' motion. {fix}")


@dataclass(frozen=True)
class WingProblem(_Wing):
    """A wing definition file with records (``kind = "wing"``; module docstring).

    Attributes
    ----------
    name : str
        ``[problem] name`` (default: the folder of a ``problem.toml``, else the file stem).
    structure : ModalStructure
        Σs of eq. 6-7 (frequencies in rad/s, the file's sensors).
    U_ref, rho : float
        The speed scale: ``U = V U_ref`` [m/s], ``q = rho U^2 / 2``.
    sensor_units : tuple of str
        A unit per sensor.
    records : IOData
        The records (one per file), forces ``y`` and inputs ``u``, ``v``.
    V0 : float
        Speed index of the records.
    """

    records: IOData | None = None
    V0: float = 0.0

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, path, sets: Iterable[str] = ()
                     ) -> "WingProblem":
        """The wing of a ``kind = "wing"`` file's tables; record paths relative to ``path``.

        Parameters
        ----------
        data : mapping
            The file's tables.
        path : str or Path
            The file (named in the messages; its folder resolves the record paths).
        sets : iterable
            Must be empty: a wing file has no parameters to change.

        Returns
        -------
        WingProblem

        Raises
        ------
        ConfigError
            A missing, unknown or malformed key (named, with the fix).
        DataError
            A missing or unreadable record file, an unknown channel, non-finite samples, a
            time channel that is not uniform, records sampled too coarsely for the modes
            (Nyquist frequency not above the highest; a ConfigError when ``records.dt`` is
            the cause).

        Warns
        -----
        DataWarning
            A channel of the NPZ or MAT record files that ``[records]`` does not name (an
            input left out makes the fit wrong without an error), or a ``t``/``time``
            channel that contradicts ``records.dt``.
        """
        path = Path(path)
        _no_sets(sets, path, WING_KIND)
        common = cls._common(data, path, WING_KIND, {"records"})
        src = f"wing file {path}"
        n = common["structure"].n_modes
        rec = _table(data, "records", src, _RECORDS)
        if ("V0" in rec) == ("U0" in rec):
            raise ConfigError(f"{src}: give one of records.V0 (speed index) or records.U0 "
                              "(airspeed [m/s]) of the records")
        V0 = (_number(rec["V0"], "records.V0", src) if "V0" in rec
              else _number(rec["U0"], "records.U0", src) / common["U_ref"])
        files = _need(rec, "records", "files", src, "the list of record files (.csv, .npz, "
                      ".mat), one record per file")
        if isinstance(files, str):
            files = [files]
        if not isinstance(files, list) or not files or not all(isinstance(f, str)
                                                               for f in files):
            raise ConfigError(f"{src}: records.files = {files!r} must be a list of file names")
        if ("time" in rec) == ("dt" in rec):
            raise ConfigError(f"{src}: give one of records.time (the time channel) or "
                              "records.dt (the sampling time [s])")
        time = rec.get("time")
        if time is not None and not isinstance(time, str):
            raise ConfigError(f"{src}: records.time = {time!r} must be a channel name")
        dt = _number(rec["dt"], "records.dt", src) if "dt" in rec else None
        if dt is not None:   # before any record is read
            _check_sampling(common["structure"], dt, src, None)
        forces = _names(_need(rec, "records", "forces", src, f"the {n} channels of the "
                              "generalised forces, in mode order"), "records.forces", src, n)
        disp = (_names(rec["displacements"], "records.displacements", src, n)
                if "displacements" in rec else None)
        flap = rec.get("flap")
        if flap is not None and (not isinstance(flap, str) or not flap.strip()):
            raise ConfigError(f"{src}: records.flap = {flap!r} must be a channel name")
        if disp is None and flap is None:
            raise ConfigError(f"{src}: the records need inputs: give records.displacements "
                              "and/or records.flap")
        datas, unused, clashes = [], {}, []
        for f in files:
            fp = (path.parent / f) if not Path(f).is_absolute() else Path(f)
            if not fp.is_file():
                raise DataError(f"{src}: record file {f!r} not found ({fp}); fix "
                                "records.files (paths are relative to the wing file)")
            data, extra, clash = _read_record(fp, forces, disp, flap, None if dt else time,
                                              dt)
            datas.append(data)
            for c in extra:
                unused.setdefault(c, []).append(f)
            if clash is not None:
                clashes.append((f, *clash))
        if clashes:   # one warning for the files, not one per file
            f, clock, step = clashes[0]
            where = f"{src}: record file {f}" + (f" (and {len(clashes) - 1} more)"
                                                 if len(clashes) > 1 else "")
            warnings.warn(time_contradicts(where, "records.dt", dt, clock, step),
                          DataWarning, stacklevel=2)
        # equal to 1e-6, as the steps within a file (a single-precision time channel gives
        # its sampling time to the stamps' rounding over the record)
        dts = sorted({round(d.dt, 12) for d in datas})
        if dts[-1] > dts[0] * (1 + 1e-6):
            raise DataError(f"{src}: the record files have different sampling times "
                            f"{dts}; resample them to one")
        if dt is None:
            _check_sampling(common["structure"], datas[0].dt, src, time)
        if unused:
            # an input the records carry but [records] does not name is most often one the
            # fit needs (the flap): without it the ROM fits the forces wrongly, with no error
            warnings.warn(f"{src}: channel(s) {sorted(unused)} of the record files (e.g. "
                          f"{unused[sorted(unused)[0]][0]}) are not used: they are not among "
                          f"records.forces {list(forces)}, records.displacements "
                          f"{list(disp or [])} or records.flap ({flap!r}); if one is an "
                          "input of the records, name it in [records], else drop it from "
                          "the files", DataWarning, stacklevel=2)
        log.debug("%s: %d record files, dt = %g s", path, len(files), datas[0].dt)
        records = IOData(tuple(r for d in datas for r in d.records), datas[0].dt,
                         output_names=tuple(forces), u_names=tuple(disp or ()),
                         v_name=flap or "v", meta={"V": V0, "source": str(path)})
        return cls(**common, records=records, V0=V0)

    def __repr__(self) -> str:
        return (f"WingProblem({self.name!r}, {self.n_modes} modes, "
                f"{len(self.records.records)} records at V0 = {self.V0:g})")


@dataclass(frozen=True)
class GAFProblem(_Wing):
    """Modal data with a ``Q(ik)`` table (``kind = "gaf"``; module docstring).

    Attributes
    ----------
    table : GAFTable
        ``Q(ik)`` in the eq. 6 normalisation.
    U_range : tuple of float
        Airspeeds [m/s] of the flutter search.
    n_grid : int
        Points of its grid.
    rfa : dict
        Settings of the RFA (:class:`casflutter.realize.RFASettings` fields).
    """

    table: GAFTable | None = None
    U_range: tuple = ()
    n_grid: int = 141
    rfa: dict = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, path, sets: Iterable[str] = ()
                     ) -> "GAFProblem":
        """The wing of a ``kind = "gaf"`` file's tables; the table path relative to ``path``.

        Parameters
        ----------
        data : mapping
            The file's tables.
        path : str or Path
            The file (its folder resolves ``gaf.file``).
        sets : iterable
            Must be empty: a GAF file has no parameters to change.

        Returns
        -------
        GAFProblem

        Raises
        ------
        ConfigError
            A missing, unknown or malformed key.
        DataError
            A missing or malformed ``Q(ik)`` file, or one whose modes or ``U_ref`` do not
            match the modal data.
        """
        path = Path(path)
        _no_sets(sets, path, GAF_KIND)
        common = cls._common(data, path, GAF_KIND, {"gaf"})
        src = f"wing file {path}"
        n = common["structure"].n_modes
        g = _table(data, "gaf", src, _GAF)
        f = _need(g, "gaf", "file", src, "the Q(ik) table file (.npz, .csv or .mat)")
        if not isinstance(f, str):
            raise ConfigError(f"{src}: gaf.file = {f!r} must be a file name")
        fp = (path.parent / f) if not Path(f).is_absolute() else Path(f)
        if not fp.is_file():
            raise DataError(f"{src}: Q(ik) file {f!r} not found ({fp}); fix gaf.file (paths "
                            "are relative to the wing file)")
        table = load_gaf(fp)
        if table.n_modes != n:
            raise DataError(f"{src}: the Q(ik) table {f} has {table.n_modes} modes but [modes] "
                            f"has {n}; use the same modes for Q(ik) and the modal data")
        if table.U_ref is not None and abs(table.U_ref / common["U_ref"] - 1) > 1e-6:
            raise DataError(f"{src}: the Q(ik) table has U_ref = {table.U_ref:g} m/s but "
                            f"speed.U_ref = {common['U_ref']:g}; make them agree")
        ur = _need(g, "gaf", "U_range", src, "[low, high] airspeeds [m/s] of the flutter "
                   "search")
        ur = _numbers(ur, "gaf.U_range", src, 2)
        if not ur[0] < ur[1]:
            raise ConfigError(f"{src}: gaf.U_range = {list(ur)} must be [low, high], low < high")
        n_grid = g.get("n_grid", 141)
        if isinstance(n_grid, bool) or not isinstance(n_grid, int) or n_grid < 3:
            raise ConfigError(f"{src}: gaf.n_grid = {n_grid!r} must be an integer >= 3")
        rfa = {k: g[k] for k in _RFA_KEYS if k in g}
        return cls(**common, table=table, U_range=(float(ur[0]), float(ur[1])),
                   n_grid=n_grid, rfa=rfa)

    def __repr__(self) -> str:
        return (f"GAFProblem({self.name!r}, {self.n_modes} modes, {self.table.k.size} "
                f"reduced frequencies)")
