"""The paper's ROM flutter route on the truth problems, and a parametric ROM (issue 3).

Route (paper §II.C, §III.A, §IV.A).  At one nominal speed index ``V0`` the truth is driven by
band-limited chirps on the modal displacements and the flap (:func:`truth_records`); an HWL
ROM is identified from the forces (:func:`identify_common_denominator`), linearised and
realised by ERA and Tustin's transform into Σf (eq. 5, :func:`casflutter.realize.realize`),
closed with Σs (eq. 6-7) into ΣAE(V) (eq. 8) and its flutter speed found by branch tracking
(:func:`casflutter.aeroelastic.find_flutter`).  The truth's flutter speed comes from its own
full-order state matrix.

Why the ROM flutter speed is wrong.  ΣAE feeds the structure ``alpha V^2 y`` with ``y`` the
ROM identified at ``V0``: only the dynamic pressure is scaled.  The aerodynamic operator
itself depends on V through its time scale ``b / U``: apparent-mass forces scale with
``U^0``, aerodynamic damping with ``U^1``, the Wagner lag rates ``b_j U / b`` with ``U``
(equivalently, a given frequency ``omega`` has the reduced frequency ``k = omega b / U``).
The V² scaling freezes all of them at their ``V0`` values, so the ROM's ΣAE(V) equals the
truth only at ``V = V0``.  This is *exactly* the truth with its aerodynamics frozen at
``V0`` and scaled by ``(V / V0)^2`` (:func:`frozen_aero_truth`), whose flutter speed the
ROM reproduces to the identification/discretisation error; the difference between that
and the truth's flutter speed is the V²-scaling error.  Static divergence is exact under
V² scaling: the steady aerodynamic stiffness (``omega = 0``) does not depend on the time
scale.

Parametric ROM (past the paper, whose conclusion names this as future work).  ROMs
identified at speeds ``V_1..V_m`` (Chebyshev–Lobatto nodes over the analysis range) have
the same structure; their coefficients — the common denominator ``a_m`` and the input
matrices, the latter multiplied by ``V^2`` so that the interpolated quantity is the
dimensional force operator, free of the ``1/V^2`` of the apparent mass — are interpolated in
V by the barycentric polynomial through the nodes.  The interpolated model is realised by
the block observer-canonical form (:func:`casflutter.realize.canonical_realization`), a
fixed-dimension realisation that is a continuous function of the coefficients, and Tustin's
transform; ΣAE(V) then has continuous eigenvalues and eigenvectors and
:func:`find_flutter` tracks it like any ``V -> A(V)``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
from scipy.interpolate import BarycentricInterpolator

from ..aeroelastic import AeroelasticSystem, FlutterResult, ModalStructure, find_flutter
from .._resources import read_toml
from ..errors import ConfigError, DimensionError
from ..ident import HWLModel
from ..realize import canonical_realization, lag_coefficients, realize, tustin_to_continuous
from ._rom_data import RomIdentification, identify_common_denominator, truth_records

__all__ = ["RomSettings", "rom_settings", "structure_of", "truth_flutter", "frozen_aero_truth",
           "rom_system", "ParametricROM", "RomFlutterResult", "rom_flutter"]



@dataclass(frozen=True)
class RomSettings:
    """Settings of the ROM flutter route (defaults per problem: :func:`rom_settings`).

    Attributes
    ----------
    V0 : float
        Nominal speed index of the single-speed ROM (below flutter).
    V_range : (float, float)
        Speed-index range of the flutter analysis (and of the parametric ROM's nodes).
    dt : float
        Sampling time of the chirp records [time unit of the problem].
    duration : float
        Length of each chirp record [time unit].
    band : (float, float)
        Chirp band [Hz of the problem's time unit]; below the Nyquist frequency ``1/(2 dt)``.
    amplitude : float
        Chirp amplitude (linear aerodynamics: sets the scale only).
    taper : float
        Raised-cosine taper fraction at each end of a chirp.
    na : int
        Denominator order of the ROM (2: Jones' two-lag Wagner function).
    nb : int
        Largest input lag of the ROM.
    flap : bool
        Identify the flap input ``v`` too (Σf then has inputs ``[u, v]``).
    n_speeds : int
        Number of identification speeds of the parametric ROM (Chebyshev–Lobatto nodes over
        ``V_range``).
    n_grid : int
        Points of the V grid of the flutter search.
    """

    V0: float
    V_range: tuple
    dt: float
    duration: float
    band: tuple
    amplitude: float = 0.01
    taper: float = 0.1
    na: int = 2
    nb: int = 6
    flap: bool = True
    n_speeds: int = 7
    n_grid: int = 201

    def __post_init__(self):
        vr = tuple(float(x) for x in self.V_range)
        band = tuple(float(x) for x in self.band)
        if len(vr) != 2 or not 0 < vr[0] < vr[1]:
            raise ConfigError(f"V_range={self.V_range} must be (V_low, V_high) with "
                              "0 < V_low < V_high")
        if len(band) != 2 or not 0 <= band[0] < band[1]:
            raise ConfigError(f"band={self.band} must be (f_low, f_high) with 0 <= f_low < f_high")
        if not (self.V0 > 0 and self.dt > 0 and self.duration > 10 * self.dt):
            raise ConfigError(f"need V0 > 0, dt > 0, duration > 10 dt; got V0={self.V0}, "
                              f"dt={self.dt}, duration={self.duration}")
        if band[1] >= 0.5 / self.dt:
            raise ConfigError(f"band top {band[1]} Hz is above the Nyquist frequency "
                              f"{0.5 / self.dt:g} Hz of dt={self.dt}")
        for name, lo in (("na", 1), ("nb", 1), ("n_speeds", 2), ("n_grid", 3)):
            v = getattr(self, name)
            if isinstance(v, bool) or int(v) != v or v < lo:
                raise ConfigError(f"{name}={v!r} must be an integer >= {lo}")
            object.__setattr__(self, name, int(v))
        object.__setattr__(self, "V_range", vr)
        object.__setattr__(self, "band", band)
        for name in ("V0", "dt", "duration", "amplitude", "taper"):
            object.__setattr__(self, name, float(getattr(self, name)))

    @property
    def speeds(self) -> np.ndarray:
        """Identification speeds of the parametric ROM: Chebyshev–Lobatto nodes of V_range."""
        lo, hi = self.V_range
        n = self.n_speeds
        x = np.cos(np.pi * np.arange(n)[::-1] / (n - 1))
        return lo + 0.5 * (hi - lo) * (x + 1.0)


#: Built-in route settings per problem (overridden by a ``[rom]`` table in the problem TOML).
_DEFAULTS = {
    "typical_section": dict(V0=1.8, V_range=(0.5, 3.0), dt=0.1, duration=300.0,
                            band=(0.002, 1.0)),
    "goland": dict(V0=1.38, V_range=(0.6, 2.4), dt=5e-4, duration=2.0, band=(0.5, 400.0)),
}


def rom_settings(problem: str, problems_dir=None, **overrides) -> RomSettings:
    """Route settings of a problem: built-in defaults, the ``[rom]`` table of
    ``problems/NAME/problem.toml`` when present, then ``overrides``.

    Raises
    ------
    ConfigError
        Unknown problem (without a default and a ``[rom]`` table) or unknown setting (the
        message lists the valid ones).
    """
    valid = [f.name for f in fields(RomSettings)]
    values = dict(_DEFAULTS.get(problem, {}))
    if problems_dir is None:
        from .._resources import problems_dir as _default_dir
        try:
            problems_dir = _default_dir()
        except FileNotFoundError:  # no definitions installed: built-in defaults only
            problems_dir = Path(".")
    path = Path(problems_dir) / problem / "problem.toml"
    if path.is_file():
        values.update(read_toml(path, "problem definition").get("rom", {}))
    values.update(overrides)
    unknown = [k for k in values if k not in valid]
    if unknown:
        raise ConfigError(f"unknown ROM setting(s) {', '.join(map(repr, unknown))}; valid: "
                          f"{', '.join(valid)}")
    missing = [k for k in ("V0", "V_range", "dt", "duration", "band") if k not in values]
    if missing:
        raise ConfigError(f"problem {problem!r} has no ROM settings for {', '.join(missing)}: "
                          f"add a [rom] table to {path} or pass them")
    return RomSettings(**values)


def structure_of(truth) -> ModalStructure:
    """Σs (eq. 6-7) of a truth: its in-vacuo ω, ζ, α and sensor rows (displacements)."""
    ms = truth.modal_structure()
    return ModalStructure(ms.omega, ms.zeta, ms.alpha, Hs=ms.sensor_rows, sensor="displacement")


def _truth_mode_states(truth) -> list[np.ndarray]:
    N = truth.n_modes
    return [np.array([i, N + i]) for i in range(N)]


def truth_flutter(truth, V_range, n_grid: int = 201) -> FlutterResult:
    """Flutter and divergence of the full-order truth (states ``[u, u', lags]``)."""
    return find_flutter(truth, V_range, n_grid=n_grid, mode_states=_truth_mode_states(truth),
                        omega=truth.modal_structure().omega)


def frozen_aero_truth(truth, V0: float):
    """The truth with its aerodynamics frozen at ``V0`` and scaled by ``(V / V0)^2``.

    This is what ΣAE of a ROM identified at ``V0`` represents at every V (module
    docstring); it is built from the truth's own aerodynamic matrices, independently of
    any identification.

    Returns
    -------
    AeroelasticTruth
        Same class and parameters; ``aero_matrices(V)`` is ``aero_matrices(V0)`` with every
        force matrix times ``(V / V0)^2`` and the lag rates of ``V0``.
    """
    base = type(truth)
    V0 = float(V0)

    class _Frozen(base):
        def aero_matrices(self, V):
            am = base.aero_matrices(self, V0)
            s = (float(V) / V0) ** 2
            return replace(am, Kx=s * am.Kx, Cx=s * am.Cx, Mx=s * am.Mx, Fv=s * am.Fv,
                           Fv1=s * am.Fv1, Fv2=s * am.Fv2, W=s * am.W)

    _Frozen.__name__ = f"Frozen{base.__name__}"
    return _Frozen(truth.params)


def rom_system(model: HWLModel, structure: ModalStructure, *, realization: str = "era",
               warn_unstable: bool = True) -> AeroelasticSystem:
    """ΣAE (eq. 8) of an HWL ROM: linearise, realise (ERA or canonical), Tustin, close with Σs.

    Parameters
    ----------
    model : HWLModel
    structure : ModalStructure
    realization : {"era", "canonical"}
        :func:`casflutter.realize.realize` (balanced ERA, minimal) or
        :func:`casflutter.realize.canonical_realization`.
    warn_unstable : bool
        Warn when Σf is unstable on its own (ΣAE unstable at V = 0); check
        ``.rom_stable`` of the result.

    Raises
    ------
    DimensionError
        Σf's outputs do not match Σs's modes (the message names both).
    """
    if realization == "era":
        sigma_f = realize(model).sigma_f
    elif realization == "canonical":
        sigma_f = tustin_to_continuous(canonical_realization(model))
    else:
        raise ConfigError(f"realization={realization!r}: use 'era' or 'canonical'")
    with warnings.catch_warnings():
        if not warn_unstable:
            warnings.simplefilter("ignore", RuntimeWarning)
        return AeroelasticSystem.from_parts(sigma_f, structure, warn_unstable=warn_unstable)


@dataclass(frozen=True)
class ParametricROM:
    """ROMs identified at several speeds, interpolated in V (module docstring).

    Attributes
    ----------
    speeds : ndarray
        Identification speed indices ``V_1..V_m``.
    identifications : tuple of RomIdentification
        One per speed (same orders).
    structure : ModalStructure
        Σs.
    """

    speeds: np.ndarray
    identifications: tuple
    structure: ModalStructure
    _interp: tuple = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        V = np.asarray(self.speeds, dtype=float)
        ids = tuple(self.identifications)
        if V.size != len(ids) or V.size < 2 or np.any(np.diff(V) <= 0):
            raise ConfigError("speeds must be increasing, at least 2, one per identification")
        orders = {i.model.orders for i in ids}
        if len(orders) != 1:
            raise ConfigError(f"the ROMs have different orders {orders}; identify them alike")
        N = ids[0].model.n_modes
        if N != self.structure.n_modes:
            raise DimensionError(f"the ROMs have {N} outputs but Σs has "
                                 f"{self.structure.n_modes} modes; they must be equal")
        a = np.array([i.a for i in ids])
        theta = np.array([i.model.theta for i in ids])
        object.__setattr__(self, "speeds", V)
        object.__setattr__(self, "identifications", ids)
        # interpolate a_m, and V^2 times the input coefficients (dimensional forces)
        th_scaled = theta * V[:, None] ** 2
        object.__setattr__(self, "_interp", (BarycentricInterpolator(V, a),
                                             BarycentricInterpolator(V, th_scaled)))

    @classmethod
    def identify(cls, truth, settings: RomSettings, speeds=None) -> "ParametricROM":
        """Identify ROMs of ``truth`` at ``speeds`` (default ``settings.speeds``)."""
        V = settings.speeds if speeds is None else np.asarray(speeds, dtype=float)
        ids = tuple(_identify_at(truth, float(v), settings) for v in V)
        return cls(V, ids, structure_of(truth))

    @property
    def template(self) -> HWLModel:
        return self.identifications[0].model

    def model_at(self, V: float) -> HWLModel:
        """The interpolated HWL ROM at speed index V (outside the nodes: extrapolated)."""
        ia, ith = self._interp
        V = float(V)
        a = np.atleast_1d(ia(V)).ravel()
        theta = np.atleast_1d(ith(V)).ravel() / V ** 2
        # the A blocks of theta are a_m I; set them from the interpolated scalars exactly
        tmpl = self.template
        c = tmpl.with_theta(theta).coefficients()
        c["A"] = np.array([am * np.eye(tmpl.n_modes) for am in a])
        return tmpl.with_theta(tmpl.structure.pack(c))

    def system_at(self, V: float) -> AeroelasticSystem:
        """ΣAE of the interpolated ROM at V (canonical realisation, Tustin)."""
        sigma_f = tustin_to_continuous(canonical_realization(self.model_at(V)))
        return AeroelasticSystem.from_parts(sigma_f, self.structure, warn_unstable=False)

    def sigma_f_matrices(self, V: float) -> tuple[np.ndarray, ...]:
        """``(Af, Bf, bf, Cf, Df, df)`` of Σf at V (eq. 5), computed directly in numpy.

        The same matrices as :meth:`system_at` (block observer form of the common-denominator
        model, inverse Tustin), without building ``control.StateSpace`` objects: this is
        what the flutter search evaluates thousands of times.
        """
        ia, ith = self._interp
        V = float(V)
        a = np.atleast_1d(ia(V)).ravel()
        tmpl = self.template
        Abar, Bbar = lag_coefficients(tmpl.with_theta(np.atleast_1d(ith(V)).ravel() / V ** 2))
        Abar[1:len(a) + 1] = a[:, None, None] * np.eye(tmpl.n_modes)
        L, N, m = Abar.shape[0] - 1, Bbar.shape[1], Bbar.shape[2]
        n = N * L
        Ad = np.zeros((n, n))
        Bd = np.empty((n, m))
        for i in range(1, L + 1):
            rows = slice((i - 1) * N, i * N)
            Ad[rows, :N] = -Abar[i]
            if i < L:
                Ad[rows, i * N:(i + 1) * N] = np.eye(N)
            Bd[rows] = Bbar[i] - Abar[i] @ Bbar[0]
        T = tmpl.dt
        Pinv = np.linalg.inv(Ad + np.eye(n))
        A = (2.0 / T) * (np.eye(n) - 2.0 * Pinv)
        B = 2.0 * Pinv @ Bd / T
        C = 2.0 * Pinv[:N]
        D = Bbar[0] - Pinv[:N] @ Bd
        bf = B[:, N] if m > N else np.zeros(n)
        df = D[:, N] if m > N else np.zeros(N)
        return A, B[:, :N], bf, C, D[:, :N], df

    def state_matrix(self, V: float) -> np.ndarray:
        """Â(V) of eq. 8a with Σf interpolated at the same V.

        The origin mode of a branch is judged by the nearest natural frequency
        (``structure.omega``): the canonical realisation's states are not balanced, so
        eigenvector energy fractions would be dominated by the aerodynamic states.
        """
        return AeroelasticSystem(self.structure, *self.sigma_f_matrices(V)).state_matrix(V)


def _identify_at(truth, V: float, s: RomSettings) -> RomIdentification:
    data = truth_records(truth, V, dt=s.dt, duration=s.duration, band=s.band,
                        amplitude=s.amplitude, taper=s.taper, flap=s.flap)
    return identify_common_denominator(data, s.na, s.nb)


@dataclass(frozen=True)
class RomFlutterResult:
    """Truth, single-speed ROM and parametric ROM flutter analyses of one problem.

    Attributes
    ----------
    settings : RomSettings
    truth : FlutterResult
        Full-order truth.
    rom : FlutterResult
        ΣAE of the ROM identified at ``settings.V0`` (paper's V² scaling).
    frozen : FlutterResult
        The truth with aerodynamics frozen at V0 (:func:`frozen_aero_truth`): the
        explanation of the ROM's error, computed without identification.
    parametric : FlutterResult or None
        ΣAE of the parametric ROM (None when not run).
    rom_identification : RomIdentification
    rom_stable : bool
        Σf of the single-speed ROM is stable on its own (else ΣAE is unstable at V = 0 and
        its crossings are not flutter onsets).
    parametric_rom : ParametricROM or None
    timings : dict
        Seconds per stage.
    """

    settings: RomSettings
    truth: FlutterResult
    rom: FlutterResult
    frozen: FlutterResult
    parametric: FlutterResult | None
    rom_identification: RomIdentification
    rom_stable: bool
    parametric_rom: ParametricROM | None
    timings: dict

    @staticmethod
    def _rel(a, b):
        return None if a is None or b is None else float(a / b - 1.0)

    @property
    def rom_error(self) -> float | None:
        """(Vf_rom - Vf_truth) / Vf_truth."""
        return self._rel(self.rom.Vf, self.truth.Vf)

    @property
    def scaling_error(self) -> float | None:
        """(Vf_frozen - Vf_truth) / Vf_truth: the error the V² scaling alone causes."""
        return self._rel(self.frozen.Vf, self.truth.Vf)

    @property
    def identification_error(self) -> float | None:
        """(Vf_rom - Vf_frozen) / Vf_frozen: what identification and Tustin add."""
        return self._rel(self.rom.Vf, self.frozen.Vf)

    @property
    def parametric_error(self) -> float | None:
        """(Vf_parametric - Vf_truth) / Vf_truth."""
        return None if self.parametric is None else self._rel(self.parametric.Vf, self.truth.Vf)

    def explanation(self) -> str:
        """The ROM error and its cause, in words."""
        def pct(x):
            return "n/a" if x is None else f"{100 * x:+.3f}%"
        return (f"ROM identified at V0 = {self.settings.V0:g}: Vf error {pct(self.rom_error)} vs the "
                f"truth. The V² scaling of ΣAE freezes the aerodynamic time scale (reduced "
                f"frequency, Wagner lag rates, apparent mass and damping) at V0; the truth with "
                f"its aerodynamics frozen at V0 flutters at {pct(self.scaling_error)}, so the "
                f"scaling explains the error up to {pct(self.identification_error)} from "
                f"identification and Tustin. Parametric ROM ({len(self.settings.speeds)} speeds): "
                f"{pct(self.parametric_error)}.")


def rom_flutter(truth, settings: RomSettings, *, parametric: bool = True,
                V_range=None) -> RomFlutterResult:
    """Run the ROM flutter route (and the parametric ROM) on a truth problem.

    Parameters
    ----------
    truth : casflutter.truth.AeroelasticTruth
    settings : RomSettings
        E.g. ``rom_settings("goland")``.
    parametric : bool
        Also identify and analyse the parametric ROM.
    V_range : (float, float), optional
        Analysis range (default ``settings.V_range``; the parametric nodes follow it).

    Returns
    -------
    RomFlutterResult
        Flutter results that found no crossing say so (``status == "no_crossing"``,
        ``Vf is None``); never a made-up speed.
    """
    if V_range is not None:
        settings = replace(settings, V_range=tuple(V_range))
    s = settings
    timings = {}
    t0 = time.perf_counter()
    tr = truth_flutter(truth, s.V_range, s.n_grid)
    fz = truth_flutter(frozen_aero_truth(truth, s.V0), s.V_range, s.n_grid)
    timings["truth"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ident = _identify_at(truth, s.V0, s)
    timings["identification"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    structure = structure_of(truth)
    system = rom_system(ident.model, structure, realization="era")
    rom = find_flutter(system, s.V_range, n_grid=s.n_grid)
    timings["rom_flutter"] = time.perf_counter() - t0
    pres = prom = None
    if parametric:
        t0 = time.perf_counter()
        prom = ParametricROM.identify(truth, s)
        timings["parametric_identification"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        # the delay states of the canonical form form defective (Jordan) blocks at
        # s = -2/dt whose eigenvectors cannot be matched; do not refine for them
        pres = find_flutter(prom, s.V_range, n_grid=s.n_grid, max_refine=2)
        timings["parametric_flutter"] = time.perf_counter() - t0
    return RomFlutterResult(settings=s, truth=tr, rom=rom, frozen=fz, parametric=pres,
                            rom_identification=ident, rom_stable=system.rom_stable,
                            parametric_rom=prom, timings=timings)
