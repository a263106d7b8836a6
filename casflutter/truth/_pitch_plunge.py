"""A dimensional pitch--plunge wind-tunnel rig section described by a TOML file.

The classic two-degree-of-freedom section per unit span (heave ``h`` positive down, pitch
``alpha`` nose up about the elastic axis, ``a`` semichords aft of mid-chord):

    [[m_heave,            m_wing x_alpha b], [h'']      [[c_h, 0      ], [h']
     [m_wing x_alpha b,   I_alpha         ]] [alpha''] + [0,  c_alpha]] [alpha']

      + [k_h(h) h, k_alpha(alpha) alpha] = [-L, M] + flap,

with the pitch spring moment ``k_alpha(alpha) alpha = k_1 alpha + k_2 alpha^2 + k_3 alpha^3
+ ...`` (the list ``k_alpha = [k_1, k_2, ...]``, linear term first) and the heave spring
force ``k_h(h) h`` likewise (``k_h`` a number for a linear spring, or a list for a hardening
or softening one).  Two aerodynamic models:

``aero = "wagner"``
    Theodorsen's non-circulatory (apparent-mass) terms and the circulatory lift through
    R. T. Jones' two-lag Wagner function (:mod:`._aero`, the typical section's model, here
    dimensional).  The apparent mass makes the total mass matrix
    ``[[m_heave + pi rho b^2, m_wing x_alpha b - a pi rho b^3],
    [m_wing x_alpha b - a pi rho b^3, I_alpha + pi rho b^4 (1/8 + a^2)]]``.
``aero = "quasi_steady"``
    Ko, Kurdila & Strganac (1997): ``L = rho U^2 b cl_alpha alpha_eff``,
    ``M = rho U^2 b^2 cm_alpha alpha_eff`` with ``alpha_eff = alpha + h'/U + (1/2 - a) b
    alpha'/U`` and ``cm_alpha = (1/2 + a) cl_alpha`` (lift at the quarter chord), no
    apparent mass.

An optional trailing-edge flap ``beta`` (``[flap]`` with ``cl_beta``, ``cm_beta``, moment
about the elastic axis) adds ``rho U^2 b cl_beta beta`` to the lift and
``rho U^2 b^2 cm_beta beta`` to the moment (quasi-steady); with Wagner aerodynamics its lift
enters the lagged circulation as the equivalent angle ``(cl_beta / cl_alpha) beta`` and the
rest of its moment, ``cm_beta - (1/2 + a) cl_beta``, acts directly, so that the steady flap
forces are the same in both models.

Conventions of the truth base class: physical coordinates ``x = [h, alpha]`` [m, rad]; the
equations are divided by ``m_heave`` (``Mhat = M / m_heave``); the speed index is the
airspeed itself, ``V = U`` [m/s]; time in seconds; flow constant ``alpha = rho b / m_heave``
so that ``y = Phi^T [-L, M] / (rho b U^2)``.  The physical dampers couple the in-vacuo modes:
the full modal damping matrix is used by the simulator and the coupled operator, and its
diagonal gives the modal damping ratios of :meth:`PitchPlungeSection.modal_structure` (Σs of
eq. 7 is diagonal).

TOML keys (top level): ``kind = "pitch_plunge"``, ``b`` [m], ``a``, ``rho`` [kg/m^3],
``m_heave`` [kg] (everything that moves in heave), ``m_wing`` [kg] (the pitching wing),
``x_alpha`` [semichords, centre of mass aft of the elastic axis], ``I_alpha`` [kg m^2 about the
elastic axis], ``k_h`` [N/m, or a list: N/m, N/m^2, ...], ``c_h`` [kg/s], ``c_alpha``
[kg m^2/s], ``k_alpha`` [list:
N m/rad, N m/rad^2, ...], ``aero``; optional ``cl_alpha`` [1/rad] (default ``2 pi``) and the
tables ``[flap]`` (``cl_beta``, ``cm_beta``), ``[problem]`` (``name``, ``description``,
``source``), ``[reference]``, ``[rom]`` (settings of ``casflutter flutter``) and ``[lco]``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from ..errors import ConfigError
from ..structure import AirspeedMixin, SpeedConvention
from ._aero import JONES_B, strip_coefficients
from ._base import AeroelasticTruth, AeroMatrices

__all__ = ["PitchPlungeParams", "FlapCoefficients", "PitchPlungeSection", "PITCH_PLUNGE_KIND"]

#: value of the ``kind`` key of a rig-section TOML file
PITCH_PLUNGE_KIND = "pitch_plunge"
_AERO = ("wagner", "quasi_steady")
#: tables a rig file may carry besides its parameters
_TABLES = ("flap", "problem", "reference", "rom", "lco")


def _p(unit, doc, **kw):
    return field(metadata={"unit": unit, "doc": doc}, **kw)


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"rig key {key!r} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ConfigError(f"rig key {key!r} must be finite, got {value!r}")
    return v


def _check_lco_table(table: Mapping[str, Any], source: str) -> None:
    """``[lco]`` of a rig file: only ``vrange = [lo, hi]`` (m/s, ``0 <= lo < hi``)."""
    unknown = sorted(k for k in table if k != "vrange")
    if unknown:
        raise ConfigError(f"{source}: unknown key(s) {', '.join(map(repr, unknown))} in [lco]; "
                          "allowed: vrange (the default speed range of `casflutter lco`)")
    if "vrange" in table:
        vr = table["vrange"]
        if not (isinstance(vr, (list, tuple)) and len(vr) == 2):
            raise ConfigError(f"{source}: [lco] vrange = {vr!r}: give [low, high] in m/s, e.g. "
                              "vrange = [4.0, 16.0]")
        lo, hi = (_number(f"[lco] vrange[{i}]", v) for i, v in enumerate(vr))
        if not 0 <= lo < hi:
            raise ConfigError(f"{source}: [lco] vrange = {list(vr)!r}: need 0 <= low < high")


@dataclass(frozen=True)
class FlapCoefficients:
    """Steady trailing-edge flap coefficients (per radian of flap, moment about the elastic
    axis, positive trailing edge down)."""

    cl_beta: float
    cm_beta: float


@dataclass(frozen=True)
class PitchPlungeParams:
    """Parameters of a dimensional pitch--plunge rig section (module docstring).

    Built from a TOML mapping with :meth:`from_mapping`; every value is checked on
    construction and a fault raises :class:`~casflutter.errors.ConfigError` naming the key.
    """

    b: float = _p("m", "semichord")
    a: float = _p("semichords", "elastic axis aft of mid-chord")
    rho: float = _p("kg/m^3", "air density")
    m_heave: float = _p("kg", "mass moving in heave (wing, mount and carriage)")
    m_wing: float = _p("kg", "mass of the pitching wing")
    x_alpha: float = _p("semichords", "centre of mass of the wing aft of the elastic axis")
    I_alpha: float = _p("kg m^2", "pitch inertia of the wing about the elastic axis")
    k_h: tuple = _p("N/m^j", "heave spring force k_1 h + k_2 h^2 + ... (linear term first; "
                    "a number: linear)")
    c_h: float = _p("kg/s", "heave damper")
    c_alpha: float = _p("kg m^2/s", "pitch damper")
    k_alpha: tuple = _p("N m/rad^j", "pitch spring moment k_1 alpha + k_2 alpha^2 + ... "
                        "(linear term first)")
    aero: str = _p("-", "aerodynamics: 'wagner' (Theodorsen + Jones lags) or 'quasi_steady'")
    cl_alpha: float = _p("1/rad", "lift-curve slope", default=2.0 * np.pi)
    flap: FlapCoefficients | None = _p("-", "trailing-edge flap coefficients", default=None)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            if f.name in ("k_alpha", "k_h", "aero", "flap"):
                continue
            object.__setattr__(self, f.name, _number(f.name, getattr(self, f.name)))
        for key in ("k_alpha", "k_h"):
            k = getattr(self, key)
            if isinstance(k, (int, float)) and not isinstance(k, bool):
                k = (k,)
            if not isinstance(k, (list, tuple)) or not k:
                raise ConfigError(f"rig key {key!r} must be a number or a non-empty list of "
                                  f"numbers (linear term first), got {getattr(self, key)!r}")
            object.__setattr__(self, key,
                               tuple(_number(f"{key}[{i}]", v) for i, v in enumerate(k)))
        if self.aero not in _AERO:
            raise ConfigError(f"rig key 'aero' = {self.aero!r} is not allowed; choose one of "
                              f"{', '.join(map(repr, _AERO))}")
        if self.flap is not None and not isinstance(self.flap, FlapCoefficients):
            raise ConfigError("rig key 'flap' must be a table with cl_beta and cm_beta")
        self._validate()

    def _validate(self) -> None:
        def need(cond, key, msg):
            if not cond:
                raise ConfigError(f"rig key {key!r} = {getattr(self, key)!r}: {msg}")

        for key in ("b", "rho", "m_heave", "m_wing", "I_alpha", "cl_alpha"):
            need(getattr(self, key) > 0, key, "must be positive")
        need(self.k_h[0] > 0, "k_h", "the linear heave stiffness k_h[0] must be positive")
        need(-1 < self.a < 1, "a", "must lie in (-1, 1) (semichords aft of mid-chord)")
        need(self.c_h >= 0, "c_h", "must be >= 0")
        need(self.c_alpha >= 0, "c_alpha", "must be >= 0")
        need(self.m_wing <= self.m_heave, "m_wing",
             f"must not exceed m_heave = {self.m_heave} (the wing moves in heave too)")
        need(self.k_alpha[0] > 0, "k_alpha",
             "the linear pitch stiffness k_alpha[0] must be positive")
        # I_alpha = I_cg + m_wing (x_alpha b)^2 about the elastic axis (parallel axes); with
        # m_wing <= m_heave it also makes the mass matrix positive definite
        xb = self.x_alpha * self.b
        offset = self.m_wing * xb * xb         # (not **: a huge value gives inf, not an error)
        need(self.I_alpha > offset, "I_alpha",
             f"below m_wing (x_alpha b)^2 = {offset:g} kg m^2, the inertia of the wing's mass "
             f"about the elastic axis alone (parallel axes, x_alpha = {self.x_alpha:g}, b = "
             f"{self.b:g}): check I_alpha, x_alpha and b")

    # ---- construction --------------------------------------------------------------
    @classmethod
    def parameter_names(cls) -> list[str]:
        """Keys of the parameters, in declaration order."""
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], source: str = "rig file") -> "PitchPlungeParams":
        """Parameters from the tables of a rig TOML file (module docstring for the keys).

        Raises
        ------
        ConfigError
            Wrong ``kind``, a missing or unknown key (named, with the allowed ones), or a
            non-physical value.
        """
        kind = data.get("kind")
        if kind != PITCH_PLUNGE_KIND:
            raise ConfigError(f"{source}: key 'kind' must be {PITCH_PLUNGE_KIND!r}, got {kind!r}")
        fields = {f.name: f for f in dataclasses.fields(cls)}
        allowed = set(fields) | {"kind"} | set(_TABLES)
        unknown = sorted(k for k in data if k not in allowed)
        if unknown:
            raise ConfigError(f"{source}: unknown key(s) {', '.join(map(repr, unknown))}; "
                              f"allowed: kind, {', '.join(fields)}, and the tables "
                              f"[{'], ['.join(_TABLES)}]")
        required = [n for n, f in fields.items()
                    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
        missing = [k for k in required if k not in data]
        if missing:
            raise ConfigError(f"{source}: missing key(s) {', '.join(map(repr, missing))} of a "
                              f"{PITCH_PLUNGE_KIND} section")
        for t in _TABLES:
            if t in data and not isinstance(data[t], Mapping):
                raise ConfigError(f"{source}: {t!r} must be a table ([{t}])")
        _check_lco_table(data.get("lco", {}), source)
        kw = {k: data[k] for k in fields if k in data and k != "flap"}
        if "flap" in data:
            kw["flap"] = _flap_from(data["flap"], source)
        return cls(**kw)

    def with_updates(self, **changes) -> "PitchPlungeParams":
        """A copy with some parameters changed (``flap`` as ``{"cl_beta": ..,
        "cm_beta": ..}``); unknown names raise :class:`ConfigError` listing the valid ones."""
        valid = self.parameter_names()
        unknown = [k for k in changes if k not in valid]
        if unknown:
            raise ConfigError(f"unknown parameter(s) {', '.join(map(repr, unknown))} for a "
                              f"pitch-plunge section; valid names: {', '.join(valid)}")
        if "flap" in changes and not isinstance(changes["flap"], (FlapCoefficients, type(None))):
            changes["flap"] = _flap_from(changes["flap"], "flap")
        return dataclasses.replace(self, **changes)

    def with_sets(self, sets: Iterable[str] = ()) -> "PitchPlungeParams":
        """Apply ``["name=value", ...]`` (the CLI's ``--set``): numbers; ``k_alpha`` as a
        comma-separated list (``k_alpha=2.82,-62.3``, ``k_h`` likewise); ``aero=quasi_steady``;
        ``flap.cl_beta=3.4`` / ``flap.cm_beta=-0.6``.

        Raises
        ------
        ConfigError
            Malformed item, unknown name or non-physical value.
        """
        changes: dict[str, Any] = {}
        flap = None if self.flap is None else dataclasses.asdict(self.flap)
        for item in sets:
            name, sep, value = str(item).partition("=")
            name, value = name.strip(), value.strip()
            if not sep or not name:
                raise ConfigError(f"--set item {item!r} is not of the form name=value")
            if name.startswith("flap."):
                key = name[5:]
                if key not in ("cl_beta", "cm_beta"):
                    raise ConfigError(f"unknown flap key {key!r}; valid: cl_beta, cm_beta")
                flap = dict(flap or {})
                flap[key] = _parse_number(name, value)
                continue
            if name in ("k_alpha", "k_h"):
                parts = [v for v in value.strip("[]").split(",") if v.strip()]
                changes[name] = tuple(_parse_number(f"{name}[{i}]", v)
                                      for i, v in enumerate(parts))
            elif name == "aero":
                changes[name] = value.strip("'\"")
            elif name in self.parameter_names() and name != "flap":
                changes[name] = _parse_number(name, value)
            else:
                raise ConfigError(f"unknown parameter {name!r} for a pitch-plunge section; valid "
                                  f"names: {', '.join(self.parameter_names())} (flap.cl_beta, "
                                  "flap.cm_beta)")
        if flap is not None and flap != (None if self.flap is None else dataclasses.asdict(self.flap)):
            changes["flap"] = _flap_from(flap, "--set flap")
        return self.with_updates(**changes)

    def describe(self) -> list[tuple[str, Any, str, str]]:
        """``(name, value, unit, doc)`` for every parameter."""
        out = []
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, FlapCoefficients):
                v = dataclasses.asdict(v)
            out.append((f.name, v, f.metadata.get("unit", ""), f.metadata.get("doc", "")))
        return out

    def as_dict(self) -> dict[str, Any]:
        """Parameters as a plain dict (the ``flap`` as a dict or None)."""
        return {name: value for name, value, _, _ in self.describe()}

    # ---- derived --------------------------------------------------------------------
    @property
    def cm_alpha(self) -> float:
        """Moment-curve slope about the elastic axis, ``(1/2 + a) cl_alpha``."""
        return (0.5 + self.a) * self.cl_alpha


def _higher_terms(k: tuple, z):
    """``k_2 z^2 + k_3 z^3 + ...`` of a spring polynomial (linear term first; zero when it
    has none), by Horner's rule (``z`` a number or a CasADi symbol)."""
    if len(k) < 2:
        return 0.0 * z
    acc = k[-1]
    for c in reversed(k[1:-1]):
        acc = c + z * acc
    return z * z * acc


def _parse_number(name: str, value: str) -> float:
    try:
        v = float(value)
    except ValueError:
        raise ConfigError(f"--set {name}={value!r}: value must be a number") from None
    if not math.isfinite(v):
        raise ConfigError(f"--set {name}={value!r}: value must be finite")
    return v


def _flap_from(table: Any, source: str) -> FlapCoefficients:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{source}: 'flap' must be a table with cl_beta and cm_beta")
    unknown = sorted(k for k in table if k not in ("cl_beta", "cm_beta"))
    if unknown:
        raise ConfigError(f"{source}: unknown key(s) {', '.join(map(repr, unknown))} in [flap]; "
                          "allowed: cl_beta, cm_beta")
    missing = [k for k in ("cl_beta", "cm_beta") if k not in table]
    if missing:
        raise ConfigError(f"{source}: missing key(s) {', '.join(map(repr, missing))} in [flap]")
    return FlapCoefficients(_number("flap.cl_beta", table["cl_beta"]),
                            _number("flap.cm_beta", table["cm_beta"]))


class PitchPlungeSection(AirspeedMixin, AeroelasticTruth):
    """Full-order truth of a dimensional pitch--plunge rig section (module docstring).

    Parameters
    ----------
    params : PitchPlungeParams
    name : str
        Problem name (from the file's ``[problem]`` table or its folder).
    definition : dict, optional
        The TOML tables the section was read from (reference values, ``[rom]``, ``[lco]``).

    Notes
    -----
    Physical coordinates ``x = [h, alpha]``; speed index ``V = U`` [m/s].  The LCO
    amplitudes of :mod:`casflutter.lco` are reported for ``heave`` [m] and ``pitch`` [rad]
    (the sensor rows are the mode shapes, ``x = Phi u``).
    """

    Params = PitchPlungeParams
    #: LCO outputs are the physical heave and pitch, not the in-vacuo modes
    lco_modal_outputs = False
    _V_NODES = (5.0, 10.0, 20.0)

    def __init__(self, params: PitchPlungeParams, name: str = "pitch_plunge",
                 definition: Mapping[str, Any] | None = None) -> None:
        if not isinstance(params, PitchPlungeParams):
            raise ConfigError("PitchPlungeSection needs PitchPlungeParams (see "
                              "PitchPlungeParams.from_mapping)")
        self.name = str(name)
        self.definition = dict(definition or {})
        super().__init__(params)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], name: str | None = None,
                     source: str = "rig file", sets: Iterable[str] = ()) -> "PitchPlungeSection":
        """The section from the tables of a rig TOML file, with ``--set`` items applied."""
        params = PitchPlungeParams.from_mapping(data, source).with_sets(sets)
        label = name or dict(data.get("problem", {})).get("name") or "pitch_plunge"
        return cls(params, label, data)

    @classmethod
    def from_sets(cls, sets=()):  # pragma: no cover - a rig has no built-in defaults
        raise ConfigError("a pitch-plunge section has no built-in parameters: load it from a "
                          "TOML file (casflutter.truth.load_problem(path))")

    def with_updates(self, **changes):
        """The same rig with some parameters changed (unknown names raise ConfigError)."""
        return type(self)(self.params.with_updates(**changes), self.name, self.definition)

    def with_sets(self, sets=()):
        """The same rig with ``--set`` items applied (see :meth:`PitchPlungeParams.with_sets`)."""
        return type(self)(self.params.with_sets(sets), self.name, self.definition)

    # ---- conventions -----------------------------------------------------------------
    @property
    def speed(self) -> SpeedConvention:
        """The speed index is the airspeed ``U`` [m/s] (``U_ref = 1``); time in seconds;
        dynamic pressure from ``rho``."""
        return SpeedConvention("U [m/s] (the speed index is the airspeed)", "s", U_ref=1.0,
                               rho=self.params.rho)

    @property
    def alpha(self) -> float:
        """Flow constant of eq. (6): ``rho b / m_heave`` [1/m]."""
        p = self.params
        return p.rho * p.b / p.m_heave

    # ---- model -------------------------------------------------------------------------
    def _structure_matrices(self):
        p = self.params
        S = p.m_wing * p.x_alpha * p.b
        M = np.array([[p.m_heave, S], [S, p.I_alpha]]) / p.m_heave
        K = np.diag([p.k_h[0], p.k_alpha[0]]) / p.m_heave
        return M, K

    def damping_matrix(self) -> np.ndarray:
        """Physical damping ``diag(c_h, c_alpha)`` [kg/s, kg m^2/s]."""
        return np.diag([self.params.c_h, self.params.c_alpha])

    def _modal_damping(self) -> np.ndarray:
        Phi = self._Phi
        return Phi.T @ (self.damping_matrix() / self.params.m_heave) @ Phi

    def _zeta(self) -> np.ndarray:
        # diagonal of the modal damping (the modes are coupled by the dampers)
        return np.diag(self._modal_damping()) / (2.0 * self._omega)

    def _nonlinear_force(self, x):
        p = self.params
        if not any(p.k_alpha[1:]) and not any(p.k_h[1:]):
            return None
        return np.array([_higher_terms(p.k_h, x[0]), _higher_terms(p.k_alpha, x[1])]) \
            / p.m_heave

    def aero_matrices(self, V: float) -> AeroMatrices:
        """Per-unit-span aerodynamics at airspeed ``U = V`` divided by ``m_heave``."""
        p = self.params
        U = self._check_V(V)
        m = p.m_heave
        fl = p.flap
        Z2 = np.zeros((2, 2))
        lams = tuple(bj * U / p.b for bj in JONES_B)
        if p.aero == "quasi_steady":
            rb, rb2 = p.rho * p.b, p.rho * p.b * p.b
            cl, cm, arm = p.cl_alpha, p.cm_alpha, (0.5 - p.a) * p.b
            # alpha_eff U^2 = U^2 alpha + U h' + U (1/2 - a) b alpha'; f = [-L, M]
            Kx = np.array([[0.0, -rb * cl * U * U], [0.0, rb2 * cm * U * U]])
            Cx = np.array([[-rb * cl * U, -rb * cl * U * arm], [rb2 * cm * U, rb2 * cm * U * arm]])
            Fv = np.zeros(2) if fl is None else np.array([-rb * fl.cl_beta * U * U,
                                                          rb2 * fl.cm_beta * U * U])
            return AeroMatrices(Kx=Kx / m, Cx=Cx / m, Mx=Z2.copy(), Fv=Fv / m, Fv1=np.zeros(2),
                                Fv2=np.zeros(2), W=np.zeros((2, 0)), Gx=np.zeros((0, 2)),
                                Gx1=np.zeros((0, 2)), Gv=np.zeros(0), Gv1=np.zeros(0),
                                lams=lams)
        sc = strip_coefficients(rho=p.rho, b=p.b, U=U, a=p.a, c=0.5, lift_slope=p.cl_alpha)
        Fv, Gv = np.zeros(2), np.zeros(1)
        if fl is not None:
            # lift (and its moment arm) through the lagged circulation, the rest direct
            Gv = np.array([U * fl.cl_beta / p.cl_alpha])
            Fv = np.array([0.0, p.rho * U * U * p.b ** 2 * (fl.cm_beta - (0.5 + p.a) * fl.cl_beta)])
        return AeroMatrices(
            Kx=Z2.copy(),
            Cx=np.array([[0.0, -sc.La1], [0.0, sc.Ma1]]) / m,
            Mx=np.array([[-sc.Lh2, -sc.La2], [sc.Mh2, sc.Ma2]]) / m,
            Fv=Fv / m, Fv1=np.zeros(2), Fv2=np.zeros(2),
            W=np.array([[-sc.Lc], [sc.Mc]]) / m,
            Gx=np.array([[0.0, sc.Qa0]]), Gx1=np.array([[sc.Qh1, sc.Qa1]]),
            Gv=Gv, Gv1=np.zeros(1), lams=lams)

    def total_mass_matrix(self) -> np.ndarray:
        """Structural plus apparent mass [kg, kg m, kg m^2] (the apparent mass only with
        Wagner aerodynamics)."""
        p = self.params
        S = p.m_wing * p.x_alpha * p.b
        M = np.array([[p.m_heave, S], [S, p.I_alpha]])
        if p.aero == "wagner":
            pr = np.pi * p.rho
            M = M + np.array([[pr * p.b ** 2, -p.a * pr * p.b ** 3],
                              [-p.a * pr * p.b ** 3, pr * p.b ** 4 * (0.125 + p.a ** 2)]])
        return M

    def _names(self) -> dict:
        p = self.params
        Phi = self._Phi
        # kinetic-energy share of heave vs pitch in each mode
        share = np.array([p.m_heave * Phi[0] ** 2, p.I_alpha * Phi[1] ** 2])
        kinds = ["heave" if share[0, i] >= share[1, i] else "pitch" for i in range(2)]
        return {"mode_names": [f"mode {i + 1} ({k})" for i, k in enumerate(kinds)],
                "coordinate_names": ("heave [m]", "pitch [rad]"),
                "sensor_rows": Phi.copy(), "sensor_names": ("heave", "pitch"),
                "sensor_units": ("m", "rad")}
