"""The TOML configuration of ``casflutter run`` (issue: the paper's wing end to end).

Every choice of the pipeline lives in one file, validated *before* any work starts: unknown
keys, wrong types and impossible values fail with a :class:`~casflutter.errors.ConfigError`
that names the key and what is allowed.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, get_origin, get_type_hints

from .._resources import problems_dir, read_toml
from ..errors import ConfigError

__all__ = ["RunConfig", "load_config", "default_config_path", "check_sensor_rows"]


@dataclass(frozen=True)
class ProblemSection:
    """``[problem]``: which truth and its parameter overrides."""

    name: str = "seed_wing"
    #: parameter overrides, ``{name = value}`` (validated by the truth's parameter class)
    set: dict = field(default_factory=dict)


@dataclass(frozen=True)
class DataSection:
    """``[data]``: chirp records of the truth at the nominal speed (paper §IV.A)."""

    V0: float = 0.69
    dt: float = 0.002
    duration: float = 8.0
    band_hz: list = field(default_factory=lambda: [0.2, 60.0])
    #: chirp amplitude of each modal displacement / the flap [rad] (one channel per record)
    amplitude: float = 0.01
    #: samples between a motion and the force it produces in the records: 1 models the
    #: loosely coupled CFD time march (the flow of step k sees the grid of step k-1), the
    #: reason for the paper's input delay r = 1
    coupling_delay: int = 1


@dataclass(frozen=True)
class RomSection:
    """``[rom]``: HWL orders (mu, na, nb, r, p, q), stage-2 criterion, order of Σf."""

    orders: list = field(default_factory=lambda: [3, 1, 1, 1, 2, 2])
    criterion: str = "prediction"
    regularization: float = 0.0
    nf: Any = 15


@dataclass(frozen=True)
class FlutterSection:
    """``[flutter]``: speed-index range of the Hopf search."""

    vrange: list = field(default_factory=lambda: [0.05, 2.5])
    n_grid: int = 121


@dataclass(frozen=True)
class LcoSection:
    """``[lco]``: nonlinear ROM simulation at Vf (paper Fig. 9)."""

    duration: float = 20.0
    initial_deflection: float = 0.05
    #: simulate at ``speed_factor * Vf``: exactly at the Hopf point the linear damping is zero
    #: and the approach to the LCO is infinitely slow, so a few per cent above is the default
    speed_factor: float = 1.05


@dataclass(frozen=True)
class ControllerSection:
    """``[controller]``: fixed-order robust synthesis on the LFT at Vf (paper §III.C)."""

    order: int = 3
    starts: int = 4
    #: nominal speeds of the plant set, as multiples of Vf: the LFT (eq. 14) is built at each
    #: and the worst-case norm is minimised (the multi-speed design); [1.0] is the paper's
    speeds: list = field(default_factory=lambda: [1.0])
    #: speed-index interval [lo, hi] over which the ROM loop ΣAE(V) must stay stable (the
    #: interval design of casflutter.design.design_flutter_controller); [] for the paper's
    #: design on the LFT alone
    interval: list = field(default_factory=list)
    #: stability constraints spread over the interval
    n_speeds: int = 40
    #: decay rate [rad/s] required of ΣAE(V) at those speeds
    decay: float = 0.05
    #: continuation steps of the interval's upper end
    steps: int = 4
    #: Dk = 0: no algebraic loop through the accelerometers' flap feed-through at any speed
    strictly_proper: bool = False
    #: H∞ iterations per start: the deterministic budget of the synthesis
    max_outer: int = 20
    #: required closed-loop decay after the stabilisation phase, relative to the plant's
    #: largest eigenvalue modulus (the Tustin realisation has poles near 2/dt: keep it small)
    stability_margin: float = 1e-4
    #: short stabilisation solves per start
    max_stab_rounds: int = 8
    #: Ipopt iterations per minimax/stabilisation solve (with ``max_outer`` and
    #: ``max_stab_rounds`` the deterministic budget of the synthesis)
    max_iter: int = 80
    #: first start from the zero controller (``false``: every start seeded random)
    zero_start: bool = True
    #: wall-clock budget [s] for all starts, 0 for none (a time budget makes the result
    #: depend on the machine's speed: the same seed then need not give the same controller)
    time_limit: float = 0.0


@dataclass(frozen=True)
class SuppressionSection:
    """``[suppression]``: closed-loop truth simulation with the gain ramped 0 -> 1 and released
    (paper Fig. 11), at ``speed_factor`` times the truth's own flutter speed (where the wing
    itself has an LCO)."""

    speed_factor: float = 1.05
    settle: float = 10.0
    ramp: float = 5.0
    hold: float = 10.0
    release: float = 10.0


@dataclass(frozen=True)
class SensorsSection:
    """``[sensors]``: the measured outputs ``zm = Hs u''`` of the accelerometers (eq. 7).

    The rows of ``Hs`` are the sensor locations in modal coordinates (paper §IV: the mode
    shapes at each accelerometer in its measuring direction, from FEA); the seed wing's two
    tip-store accelerometers are printed there.  One set of rows is used by every stage:
    Σs in the ROM loop (eq. 6--9), the LFT's measured output (eq. 14), the truth's LCO and
    the closed-loop suppression run.
    """

    #: one row of N numbers (one per mode of the problem) per accelerometer; empty (the
    #: default): the problem's own rows (``truth.modal_structure().sensor_rows``)
    rows: list = field(default_factory=list)


@dataclass(frozen=True)
class SolverSection:
    """``[solver]``: flat Ipopt options for every NLP (``"ipopt.tol" = 1e-8``)."""

    ipopt: dict = field(default_factory=dict)


@dataclass(frozen=True)
class RunConfig:
    """The whole configuration; each field is one TOML table."""

    problem: ProblemSection = field(default_factory=ProblemSection)
    data: DataSection = field(default_factory=DataSection)
    rom: RomSection = field(default_factory=RomSection)
    flutter: FlutterSection = field(default_factory=FlutterSection)
    lco: LcoSection = field(default_factory=LcoSection)
    controller: ControllerSection = field(default_factory=ControllerSection)
    suppression: SuppressionSection = field(default_factory=SuppressionSection)
    sensors: SensorsSection = field(default_factory=SensorsSection)
    solver: SolverSection = field(default_factory=SolverSection)
    seed: int = 0

    def to_dict(self) -> dict:
        return asdict(self)


_POSITIVE = {"dt", "duration", "settle", "ramp", "hold", "release", "V0",
             "speed_factor", "amplitude"}


def _check_value(path: str, name: str, value, typ):
    origin = get_origin(typ) or typ
    if typ is Any:
        return value
    if origin is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{path}: expected a number, got {type(value).__name__} {value!r}")
        value = float(value)
        if name in _POSITIVE and not value > 0:
            raise ConfigError(f"{path} = {value}: must be > 0")
        if name == "regularization" and value < 0:
            raise ConfigError(f"{path} = {value}: must be >= 0")
        return value
    if origin is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{path}: expected true or false, got {type(value).__name__} "
                              f"{value!r}")
        return value
    if origin is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{path}: expected an integer, got {type(value).__name__} {value!r}")
        return value
    if origin is str:
        if not isinstance(value, str):
            raise ConfigError(f"{path}: expected a string, got {type(value).__name__} {value!r}")
        return value
    if origin is list:
        if not isinstance(value, list):
            raise ConfigError(f"{path}: expected a list, got {type(value).__name__} {value!r}")
        return value
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{path}: expected a table, got {type(value).__name__} {value!r}")
        return value
    return value


def _build(cls, table: dict, prefix: str):
    hints = get_type_hints(cls)
    allowed = [f.name for f in fields(cls)]
    unknown = [k for k in table if k not in allowed]
    if unknown:
        where = f"[{prefix}]" if prefix else "top level"
        raise ConfigError(f"unknown key {unknown[0]!r} in {where}; allowed: {', '.join(allowed)}")
    kwargs = {}
    for f in fields(cls):
        if f.name not in table:
            continue
        value = table[f.name]
        path = f"{prefix}.{f.name}" if prefix else f.name
        typ = hints[f.name]
        if is_dataclass(typ):
            if not isinstance(value, dict):
                raise ConfigError(f"[{path}] must be a table, got {value!r}")
            kwargs[f.name] = _build(typ, value, path)
        else:
            kwargs[f.name] = _check_value(path, f.name, value, typ)
    return cls(**kwargs)


def _semantic_checks(cfg: RunConfig) -> None:
    o = cfg.rom.orders
    if len(o) != 6 or not all(isinstance(x, int) and not isinstance(x, bool) for x in o):
        raise ConfigError(f"rom.orders = {o!r}: give six integers [mu, na, nb, r, p, q]")
    from ..ident import HWLOrders
    try:
        HWLOrders.from_tuple(o)
    except ValueError as exc:
        raise ConfigError(f"rom.orders = {o!r}: {exc}") from None
    if cfg.rom.criterion not in ("prediction", "simulation"):
        raise ConfigError(f"rom.criterion = {cfg.rom.criterion!r}: allowed 'prediction', "
                          "'simulation'")
    nf = cfg.rom.nf
    if not (nf == "auto" or (isinstance(nf, int) and not isinstance(nf, bool) and nf >= 1)):
        raise ConfigError(f"rom.nf = {nf!r}: a positive integer or \"auto\"")
    band = cfg.data.band_hz
    if len(band) != 2 or not 0 <= band[0] < band[1]:
        raise ConfigError(f"data.band_hz = {band!r}: [low, high] with 0 <= low < high")
    if band[1] >= 0.5 / cfg.data.dt:
        raise ConfigError(f"data.band_hz upper edge {band[1]} Hz is above the Nyquist frequency "
                          f"{0.5 / cfg.data.dt:g} Hz of data.dt = {cfg.data.dt}")
    if cfg.data.duration / cfg.data.dt < 200:
        raise ConfigError(f"data.duration / data.dt = {cfg.data.duration / cfg.data.dt:.0f} "
                          "samples: at least 200 are needed")
    vr = cfg.flutter.vrange
    if len(vr) != 2 or not 0 <= vr[0] < vr[1]:
        raise ConfigError(f"flutter.vrange = {vr!r}: [low, high] with 0 <= low < high")
    if cfg.controller.order < 0:
        raise ConfigError(f"controller.order = {cfg.controller.order}: must be >= 0")
    sp = cfg.controller.speeds
    if not sp or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and x > 0
                         for x in sp):
        raise ConfigError(f"controller.speeds = {sp!r}: a non-empty list of positive multiples "
                          "of Vf")
    if cfg.controller.time_limit < 0:
        raise ConfigError(f"controller.time_limit = {cfg.controller.time_limit}: >= 0 (0: none)")
    if cfg.controller.max_stab_rounds < 1:
        raise ConfigError("controller.max_stab_rounds must be >= 1")
    iv = cfg.controller.interval
    if iv and (len(iv) != 2 or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                      for x in iv) or not 0 <= iv[0] < iv[1]):
        raise ConfigError(f"controller.interval = {iv!r}: [] or [lo, hi] speed indices with "
                          "0 <= lo < hi")
    if cfg.controller.n_speeds < 2 or cfg.controller.steps < 1 or not cfg.controller.decay >= 0:
        raise ConfigError("controller.n_speeds must be >= 2, controller.steps >= 1 and "
                          "controller.decay >= 0")
    if not cfg.controller.stability_margin > 0:
        raise ConfigError(f"controller.stability_margin = {cfg.controller.stability_margin}: "
                          "must be > 0")
    if cfg.controller.max_iter < 1:
        raise ConfigError(f"controller.max_iter = {cfg.controller.max_iter}: must be >= 1")
    if cfg.controller.max_outer < 1:
        raise ConfigError(f"controller.max_outer = {cfg.controller.max_outer}: must be >= 1")
    if cfg.controller.starts < 1:
        raise ConfigError(f"controller.starts = {cfg.controller.starts}: must be >= 1")
    if cfg.data.coupling_delay < 0:
        raise ConfigError(f"data.coupling_delay = {cfg.data.coupling_delay}: must be >= 0")
    from ..truth import PROBLEMS, problem_names
    if cfg.problem.name not in problem_names():
        raise ConfigError(f"problem.name = {cfg.problem.name!r}: allowed "
                          f"{', '.join(problem_names())}")
    # the truth's own check of problem.set (names and physical values), as run_pipeline uses it
    try:
        PROBLEMS[cfg.problem.name].Params.from_sets(f"{k}={v}" for k, v in cfg.problem.set.items())
    except ConfigError as exc:
        raise ConfigError(f"problem.set: {exc}") from None
    if cfg.sensors.rows:
        from ..truth import load_problem
        n_modes = load_problem(cfg.problem.name,
                               [f"{k}={v}" for k, v in cfg.problem.set.items()]).n_modes
        check_sensor_rows(cfg.sensors.rows, n_modes, key="sensors.rows",
                          problem=cfg.problem.name)


def check_sensor_rows(rows, n_modes: int, *, key: str = "sensors.rows",
                      problem: str = "the problem") -> list[list[float]]:
    """Check sensor rows ``Hs`` (eq. 7) given as nested lists: ``(n_sensors, n_modes)``.

    Parameters
    ----------
    rows : sequence of sequences of float
        One row per sensor, one number per mode.
    n_modes : int
        Number of modes ``N`` of the problem.
    key : str
        Name of the setting, for the error message.
    problem : str
        Name of the problem, for the error message.

    Returns
    -------
    list of list of float
        The rows as floats.

    Raises
    ------
    ConfigError
        Not a non-empty list of lists, a row whose length is not ``n_modes``, an entry that
        is not a finite number, or a row of zeros (a sensor that sees no mode).
    """
    want = (f"give a list of rows, one per sensor, each a list of {n_modes} numbers (one per "
            f"mode of {problem}), e.g. {key} = [[{', '.join(['0.1'] * n_modes)}]]")
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__len__") or len(rows) == 0:
        raise ConfigError(f"{key} = {rows!r}: {want}")
    out = []
    for i, row in enumerate(rows):
        if isinstance(row, (str, bytes)) or not hasattr(row, "__len__"):
            raise ConfigError(f"{key}[{i}] = {row!r} is not a list: {want}")
        if len(row) != n_modes:
            raise ConfigError(f"{key}[{i}] has {len(row)} entries, {problem} has {n_modes} "
                              f"modes: {want}")
        vals = []
        for j, x in enumerate(row):
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                raise ConfigError(f"{key}[{i}][{j}] = {x!r}: must be a finite number")
            vals.append(float(x))
        if not any(vals):
            raise ConfigError(f"{key}[{i}] is all zeros: a sensor that sees no mode; drop the "
                              "row")
        out.append(vals)
    return out


def default_config_path() -> Path:
    """The default configuration shipped with the package (the seed wing)."""
    return problems_dir() / "seed_wing" / "run.toml"


def _apply_update(table: dict, dotted: str, value) -> None:
    """Set ``dotted`` (``"controller.order"``, ``"problem.set.zeta"``) in the raw TOML
    ``table``.  The path follows the sections of :class:`RunConfig`; inside a table-valued
    key (``problem.set``, ``solver.ipopt``) the rest of the path is one key, dots included
    (``"solver.ipopt.ipopt.tol"``).  A table value is merged key by key.  Names are not
    checked here: ``_build`` rejects unknown ones with the list of allowed keys."""
    _set_path(table, RunConfig, str(dotted).split("."), value, str(dotted))


def _set_path(node: dict, cls, parts: list, value, dotted: str) -> None:
    name, rest = parts[0], parts[1:]
    typ = get_type_hints(cls).get(name) if cls is not None else None
    section = typ is not None and is_dataclass(typ)
    mapping = typ is not None and not section and (get_origin(typ) or typ) is dict
    if not rest:
        if isinstance(value, dict) and (section or mapping):
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
    if mapping:  # problem.set / solver.ipopt: the rest of the path is one key
        sub[".".join(rest)] = value
    else:
        _set_path(sub, typ if section else None, rest, value, dotted)


def load_config(path=None, *, updates=None, **overrides) -> RunConfig:
    """Read and validate a run configuration (default: the seed wing's).

    Parameters
    ----------
    path : path, optional
        The TOML file (default :func:`default_config_path`).
    updates : mapping of str to value, optional
        Changes by dotted path applied on top of the file before validation:
        ``{"controller.order": 4, "rom.orders": [2, 1, 1, 1, 2, 2],
        "problem.set.zeta": 0.03}`` (a table value, e.g. ``{"controller": {"starts": 1}}``,
        is merged key by key).  Unknown names fail like unknown keys in the file.
    **overrides
        Replace top-level fields (e.g. ``seed=3``).
    """
    path = Path(path) if path is not None else default_config_path()
    table = read_toml(path, "configuration file")
    table.update({k: v for k, v in overrides.items() if v is not None})
    for key, value in (updates or {}).items():
        _apply_update(table, key, value)
    cfg = _build(RunConfig, table, "")
    _semantic_checks(cfg)
    return cfg
