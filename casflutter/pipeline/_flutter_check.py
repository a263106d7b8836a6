"""The flutter check of issue 4: a fixed-order controller through the flap of a truth problem,
designed on the ROM's LFT at the ROM's flutter speed and checked on the ROM *and* the truth.

Route (paper §III, §IV; :func:`flutter_check`):

1. **ROM near flutter.**  A single-speed ROM (:func:`truth_records` +
   :func:`identify_common_denominator`, ERA, Tustin, Σs: eq. 1-9) represents the truth with
   its aerodynamics frozen at the identification speed ``V0`` (see
   :mod:`._rom_flutter`): it is exact at ``V0`` only.  Identified at ``V0 = 1.8`` the
   typical section's ROM flutters at 2.259, 4.1 % above the truth's 2.170; a controller
   designed on it leaves the truth unstable at 1.1 × its flutter speed (measured: max Re
   0.0195 against 0.061 open loop).  The identification speed is therefore moved to the
   ROM's own flutter speed and the ROM identified again (``V0 <- Vf_ROM``) until the two
   agree to ``v0_rtol``: a fixed-point iteration that needs no knowledge of the truth's
   flutter speed, and at its fixed point the ROM equals the truth at the flutter speed.
2. **Design.**  The LFT of eq. 14 at the ROM's ``Vf`` (:func:`build_lft`) and the same
   ROM's LFTs at ``speed_factors × Vf`` (the multi-speed worst case of
   :func:`casflutter.design.synthesize`), fixed order (issue: 2), flap input, the problem's
   sensor rows as displacement sensors.
3. **Verification** (:func:`casflutter.verify.verify_controller`, code shared with nothing
   above): γ, the small-gain and the exact stable intervals of V on the LFT at ``Vf``
   (eq. 10-16), and a dense eigenvalue sweep of the same loop
   (:func:`casflutter.verify.speed_sweep`).
4. **Truth.**  The truth's linear state space with the flap behind a second-order actuator
   (:meth:`statespace`), closed with the controller on a dense grid of V: its open- and
   closed-loop spectral abscissae and the closed-loop stable interval around the truth's
   flutter speed (edges refined by root bracketing).
5. **Simulations** at ``sim_factor × Vf`` (above the open-loop flutter speed), open loop and
   closed loop, from a deflection of the flutter mode: the discrete ROM in the loop
   (:func:`casflutter.aeroelastic.simulate_loop`) at ``sim_factor × Vf_ROM`` and the
   sampled-data truth (:func:`closed_loop_truth`) at ``sim_factor × Vf_truth``.  Growth
   rates are envelope fits over the second half of each record, beside the spectral
   abscissa of the corresponding linear loop.

Measured on the typical section with ``problems/typical_section/flutter_check.toml``
(13 s on this machine).  ROM flutter speeds of the identifications at V0 = 1.8, 2.2589,
2.1558, 2.1728: 2.2589, 2.1558, 2.1728, 2.16981 (truth 2.17036, -0.026 %).  γ = 9.756
(``‖T_wf zf‖∞`` = 6.898); small-gain interval V ∈ (2.1461, 2.1933), exact (4.6e-5, 2.6942)
= (0, 1.2417) Vf ⊇ [0.5, 1.2] Vf.  Truth closed loop (actuator 10 rad per time unit) stable
on (0.0434, 2.6942) = (0.02, 1.2413) Vf_truth; its upper edge equals the ROM's to 1e-10:
it is a closed-loop static divergence, and the steady aerodynamics are exact under the V²
scaling.  At 1.1 Vf: ROM open loop +0.0498 (simulated +0.0469), closed -0.0428 (-0.0365);
truth open +0.0608 (+0.0608), closed -0.0288 (-0.0275).  The synthesis returns an order-2
controller whose states are decoupled (``Bk = Ck = 0``): its transfer function is the static
gain ``D`` (1.207 on h/b, -0.048 on θ); the zero start of :func:`synthesize` does not leave
``Bk = Ck = 0`` (a saddle of the bilinear coupling), and a random second start ended at a
larger γ (25.5 against 8.56 on a two-plant set).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import control
import numpy as np
from scipy.optimize import brentq

from ..aeroelastic import (AeroelasticLFT, AeroelasticSystem, FlutterResult, build_lft,
                           envelope_growth_rate, find_flutter, simulate_loop)
from .._resources import read_toml
from ..errors import CasflutterError, ConfigError
from ._rom_data import RomIdentification, identify_common_denominator, truth_records
from ._rom_flutter import RomSettings, rom_settings, rom_system, structure_of, truth_flutter
from ._suppression import closed_loop_truth

__all__ = ["FlutterCheckSettings", "flutter_check_settings", "SimulationCheck",
           "TruthLoopSweep", "FlutterCheckResult", "flutter_check", "truth_loop_matrix"]


@dataclass(frozen=True)
class FlutterCheckSettings:
    """Settings of :func:`flutter_check` (defaults: ``problems/NAME/flutter_check.toml``).

    Speeds are speed indices of the problem; times in its time unit.
    """

    V0: float = 1.8
    """First identification speed of the ROM."""
    v0_iterations: int = 4
    """Largest number of identifications (the first at ``V0``, then at the ROM's Vf)."""
    v0_rtol: float = 2e-3
    """Stop re-identifying when ``|Vf_ROM - V0| <= v0_rtol * Vf_ROM``."""
    duration: float | None = None
    """Chirp record length (``None``: the problem's ``[rom]`` setting)."""
    order: int = 2
    """Controller order."""
    speed_factors: tuple = (0.5, 1.0, 1.2)
    """Nominal speeds of the design plants, as multiples of the ROM's Vf (1.0 must be one)."""
    starts: int = 1
    """Starts of the synthesis besides given controllers (the first is the zero controller)."""
    seed: int = 0
    """Seed of the random synthesis starts."""
    max_outer: int = 6
    """Minimax solves per start."""
    nslots: int = 16
    """Frequency slots per plant in the minimax NLP."""
    polish_rank: int = 0
    """Polishing phase of the synthesis (0: off)."""
    stability_margin: float = 1e-4
    """Closed-loop decay required by the synthesis's stabilisation phase (relative)."""
    max_stab_rounds: int = 20
    """Stabilisation solves per start."""
    ipopt: dict = field(default_factory=dict)
    """Extra Ipopt options of the synthesis (its budget is counted in iterations, so the
    same settings give the same controller on any machine)."""
    required: tuple = (0.5, 1.2)
    """The verified exact stable interval must contain ``[required] * Vf``."""
    sim_factor: float = 1.1
    """Simulation speed as a multiple of the flutter speed (above it)."""
    sim_duration: float = 150.0
    """Length of each simulation."""
    sim_dt: float = 0.05
    """Sample time of the sampled-data truth loop (the ROM runs at its own dt)."""
    deflection: float = 0.01
    """Initial deflection of the flutter mode in the simulations."""
    actuator_omega: float = 10.0
    """Natural frequency of the truth's flap actuator [rad per time unit]; the ROM has none."""
    actuator_zeta: float = 0.7
    """Damping ratio of the flap actuator."""
    sweep_range: tuple = (0.02, 1.6)
    """Range of the truth's closed-loop sweep, as multiples of the truth's flutter speed."""
    n_sweep: int = 400
    """Points of the truth's closed-loop sweep."""

    def __post_init__(self):
        for name in ("speed_factors", "required", "sweep_range"):
            object.__setattr__(self, name, tuple(float(x) for x in getattr(self, name)))
        for name in ("v0_iterations", "order", "starts", "seed", "max_outer", "nslots",
                     "polish_rank", "max_stab_rounds", "n_sweep"):
            v = getattr(self, name)
            if isinstance(v, bool) or int(v) != v:
                raise ConfigError(f"{name}={v!r} must be an integer")
            object.__setattr__(self, name, int(v))
        checks = {
            "V0 > 0": self.V0 > 0, "v0_iterations >= 1": self.v0_iterations >= 1,
            "v0_rtol > 0": self.v0_rtol > 0,
            "duration None or > 0": self.duration is None or self.duration > 0,
            "order >= 0": self.order >= 0, "starts >= 1": self.starts >= 1,
            "speed_factors > 0 and containing 1.0":
                all(f > 0 for f in self.speed_factors) and 1.0 in self.speed_factors,
            "required = (lo, hi), 0 < lo < 1 < hi":
                len(self.required) == 2 and 0 < self.required[0] < 1 < self.required[1],
            "sim_factor > 1": self.sim_factor > 1,
            "sim_duration > 0 and sim_dt > 0": self.sim_duration > 0 and self.sim_dt > 0,
            "deflection != 0": self.deflection != 0,
            "actuator_omega > 0, actuator_zeta >= 0":
                self.actuator_omega > 0 and self.actuator_zeta >= 0,
            "sweep_range = (lo, hi), 0 < lo < 1 < hi":
                len(self.sweep_range) == 2 and 0 < self.sweep_range[0] < 1 < self.sweep_range[1],
            "n_sweep >= 10": self.n_sweep >= 10,
        }
        bad = [k for k, ok in checks.items() if not ok]
        if bad:
            raise ConfigError(f"invalid FlutterCheckSettings: need {'; '.join(bad)}")


def flutter_check_settings(problem: str = "typical_section", path=None,
                           **overrides) -> FlutterCheckSettings:
    """Settings from ``problems/NAME/flutter_check.toml`` (table ``[flutter_check]``), or
    the file ``path``, then ``overrides``.

    Raises
    ------
    ConfigError
        Unknown key (the message lists the valid ones) or an invalid value.
    """
    values: dict = {}
    if path is None:
        from .._resources import problems_dir
        try:
            path = problems_dir() / problem / "flutter_check.toml"
        except FileNotFoundError:
            path = None
    if path is not None and Path(path).is_file():
        values.update(read_toml(path, "flutter-check settings").get("flutter_check", {}))
    values.update(overrides)
    valid = [f.name for f in fields(FlutterCheckSettings)]
    unknown = [k for k in values if k not in valid]
    if unknown:
        raise ConfigError(f"unknown flutter-check setting(s) {', '.join(map(repr, unknown))}; "
                          f"valid: {', '.join(valid)}")
    return FlutterCheckSettings(**values)


@dataclass(frozen=True)
class SimulationCheck:
    """Open- and closed-loop simulation at one speed above flutter.

    Attributes
    ----------
    model : str
        ``"rom"`` or ``"truth"``.
    V : float
        Speed index.
    timepts : ndarray
    open_loop, closed_loop : ndarray, shape (K, m)
        Sensor records.
    open_rate, closed_rate : float
        Envelope growth rates (largest over the sensors, second half of the record)
        [1 / time unit].
    open_eig_rate, closed_eig_rate : float
        Spectral abscissae of the linear open and closed loops at ``V``.
    """

    model: str
    V: float
    timepts: np.ndarray
    open_loop: np.ndarray
    closed_loop: np.ndarray
    open_rate: float
    closed_rate: float
    open_eig_rate: float
    closed_eig_rate: float

    @property
    def grows_open_decays_closed(self) -> bool:
        """The open loop grows and the closed loop decays (rates and amplitudes)."""
        n = self.timepts.size
        amp = lambda X, sl: float(np.max(np.abs(X[sl])))  # noqa: E731
        first, last = slice(0, n // 4), slice(3 * n // 4, n)
        return bool(self.open_rate > 0 and self.closed_rate < 0
                    and amp(self.open_loop, last) > amp(self.open_loop, first)
                    and amp(self.closed_loop, last) < amp(self.closed_loop, first))


@dataclass(frozen=True)
class TruthLoopSweep:
    """The truth's linear loop with the controller over a grid of speed indices.

    Attributes
    ----------
    V : ndarray
        Speed indices.
    open_abscissa, closed_abscissa : ndarray
        Spectral abscissae of the open loop (flap at rest) and of the closed loop
        (controller + actuator).
    stable_V : tuple of float or None
        Closed-loop stable interval containing the truth's flutter speed (edges refined by
        root bracketing; a grid end is reported where the loop is still stable); ``None``
        when the closed loop is unstable there.
    """

    V: np.ndarray
    open_abscissa: np.ndarray
    closed_abscissa: np.ndarray
    stable_V: tuple | None


@dataclass(frozen=True)
class FlutterCheckResult:
    """Outcome of :func:`flutter_check` (every measured number of the check).

    Attributes
    ----------
    settings : FlutterCheckSettings
    rom_settings : RomSettings
        Route settings of the last identification (its ``V0``).
    v0_history : tuple of (float, float)
        ``(V0, Vf_ROM)`` of every identification.
    identification : RomIdentification
        The ROM used for the design.
    system : AeroelasticSystem
        Its ΣAE.
    rom_flutter, truth_flutter : FlutterResult
    lft : AeroelasticLFT
        LFT at the ROM's Vf (eq. 14).
    synthesis : casflutter.design.SynthesisResult
        With its Ipopt statuses per start and convergence flag.
    controller : control.StateSpace
        ``K`` from the sensors to the flap (``v = K zm``).
    verification : casflutter.verify.VerificationReport
    rom_sweep : casflutter.verify.SpeedSweep
        Dense eigenvalue sweep of the ROM loop over ``[0, 1.5] * Vf``.
    truth_sweep : TruthLoopSweep
    rom_simulation, truth_simulation : SimulationCheck
    timings : dict
        Seconds per stage and ``"total"``.
    """

    settings: FlutterCheckSettings
    rom_settings: RomSettings
    v0_history: tuple
    identification: RomIdentification
    system: AeroelasticSystem
    rom_flutter: FlutterResult
    truth_flutter: FlutterResult
    lft: AeroelasticLFT
    synthesis: object
    controller: control.StateSpace
    verification: object
    rom_sweep: object
    truth_sweep: TruthLoopSweep
    rom_simulation: SimulationCheck
    truth_simulation: SimulationCheck
    timings: dict = field(default_factory=dict)

    @property
    def Vf(self) -> float:
        """The ROM's flutter speed index (the LFT's nominal speed)."""
        return float(self.rom_flutter.Vf)

    @property
    def Vf_truth(self) -> float:
        return float(self.truth_flutter.Vf)

    @property
    def gamma(self) -> float:
        """Verified ``‖T_w̄z‖∞`` of the nominal loop (eq. 16)."""
        return float(self.verification.gamma)

    @property
    def required_V(self) -> tuple:
        lo, hi = self.settings.required
        return (lo * self.Vf, hi * self.Vf)

    @property
    def interval_ok(self) -> bool:
        """The verified exact stable interval contains ``required * Vf``."""
        ex = self.verification.exact_V
        lo, hi = self.required_V
        return bool(self.verification.stable and ex is not None and ex[0] <= lo and ex[1] >= hi)

    @property
    def success(self) -> bool:
        """Interval target met, and both simulations grow open loop and decay closed loop."""
        return bool(self.interval_ok and self.rom_simulation.grows_open_decays_closed
                    and self.truth_simulation.grows_open_decays_closed)

    def summary(self) -> dict:
        """The measured numbers as plain floats (JSON-ready)."""
        ver = self.verification
        pair = lambda t: None if t is None else [float(t[0]), float(t[1])]  # noqa: E731
        sims = {s.model: {"V": s.V, "open_rate": s.open_rate, "closed_rate": s.closed_rate,
                          "open_eig_rate": s.open_eig_rate,
                          "closed_eig_rate": s.closed_eig_rate}
                for s in (self.rom_simulation, self.truth_simulation)}
        return {"v0_history": [list(map(float, p)) for p in self.v0_history],
                "Vf_rom": self.Vf, "Vf_truth": self.Vf_truth, "gamma": self.gamma,
                "gamma_delta": float(ver.hinf_delta.gamma), "small_gain_V": pair(ver.small_gain_V),
                "small_gain_V_delta": pair(ver.small_gain_V_delta), "exact_V": pair(ver.exact_V),
                "required_V": pair(self.required_V), "interval_ok": self.interval_ok,
                "truth_stable_V": pair(self.truth_sweep.stable_V),
                "synthesis_gammas": [float(g) for g in self.synthesis.gammas],
                "synthesis_converged": bool(self.synthesis.converged),
                "simulations": sims, "success": self.success,
                "timings_s": {k: float(v) for k, v in self.timings.items()}}


def truth_loop_matrix(truth, K: control.StateSpace, V: float, *, actuator_omega: float,
                      actuator_zeta: float = 0.7) -> np.ndarray:
    """State matrix of the truth's linear loop with the flap command ``v_c = K zm``.

    The truth's :meth:`statespace` with the flap behind the actuator (inputs
    ``[v_c, w]``, outputs ``[u, zm]``) closed by ``K`` from the sensors ``zm`` (the problem's
    sensor rows, displacements) to ``v_c`` (positive feedback, the ``control.hinfsyn``
    convention of eq. 14).  States ``[x_truth, x_actuator, x_K]``.
    """
    G = truth.statespace(V, actuator_omega=actuator_omega, actuator_zeta=actuator_zeta)
    N = truth.n_modes
    A, B = np.asarray(G.A), np.asarray(G.B)[:, :1]
    C = np.asarray(G.C)[N:, :]
    if np.any(np.asarray(G.D)[N:, :1]):  # pragma: no cover - displacement sensors
        raise CasflutterError("the truth's sensors feed the flap command through; "
                              "truth_loop_matrix needs D = 0")
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in
                      (K.A, K.B, K.C, K.D))
    if K.nstates == 0:
        return A + B @ Dk @ C
    return np.block([[A + B @ Dk @ C, B @ Ck], [Bk @ C, Ak]])


def _abscissa(A: np.ndarray) -> float:
    return float(np.linalg.eigvals(A).real.max())


def _truth_sweep(truth, K, Vf_truth: float, s: FlutterCheckSettings) -> TruthLoopSweep:
    kw = dict(actuator_omega=s.actuator_omega, actuator_zeta=s.actuator_zeta)
    V = Vf_truth * np.linspace(*s.sweep_range, s.n_sweep)
    ol = np.array([_abscissa(truth.state_matrix(v)) for v in V])
    cl_fun = lambda v: _abscissa(truth_loop_matrix(truth, K, v, **kw))  # noqa: E731
    cl = np.array([cl_fun(v) for v in V])
    i = int(np.argmin(np.abs(V - Vf_truth)))
    stable_V = None
    if cl[i] < 0:
        lo = i
        while lo > 0 and cl[lo - 1] < 0:
            lo -= 1
        hi = i
        while hi < V.size - 1 and cl[hi + 1] < 0:
            hi += 1
        a = V[0] if lo == 0 else brentq(cl_fun, V[lo - 1], V[lo], xtol=1e-10)
        b = V[-1] if hi == V.size - 1 else brentq(cl_fun, V[hi], V[hi + 1], xtol=1e-10)
        stable_V = (float(a), float(b))
    return TruthLoopSweep(V, ol, cl, stable_V)


def _mode(res: FlutterResult) -> int:
    """The flutter mode (index of the deflected mode of the simulations), else mode 0."""
    m = res.flutter_mode
    return int(m) if m is not None and m >= 0 else 0


def _rate(timepts, X) -> float:
    """Largest envelope growth rate over the columns, second half of the record."""
    h = timepts.size // 2
    return float(max(envelope_growth_rate(timepts[h:], X[h:, j]) for j in range(X.shape[1])))


def _rom_simulation(ident, system, lft, K, V: float, mode: int,
                    s: FlutterCheckSettings) -> SimulationCheck:
    model = ident.model
    structure = system.structure
    n = int(round(s.sim_duration / model.dt))
    xs0 = np.zeros(structure.n_states)
    xs0[2 * mode] = s.deflection  # Σs state [u_1, u̇_1, u_2, u̇_2, ...]
    ol = simulate_loop(model, structure, V, n, xs0=xs0)
    cl = simulate_loop(model, structure, V, n, xs0=xs0, controller=K)
    # linear loops of the same ROM at V: the LFT closed at ΔV (eq. 15), open and with K
    G = lft.close(V ** 2 - lft.Vf ** 2)
    A_ol = np.asarray(G.A)
    Gv = control.ss(G.A, np.asarray(G.B)[:, -1:], G.C, np.asarray(G.D)[:, -1:])
    A_cl = np.asarray(control.feedback(Gv, K, sign=1).A)
    return SimulationCheck("rom", float(V), ol.timepts, ol.zm, cl.zm, _rate(ol.timepts, ol.zm),
                           _rate(cl.timepts, cl.zm), _abscissa(A_ol), _abscissa(A_cl))


def _truth_simulation(truth, K, V: float, mode: int,
                      s: FlutterCheckSettings) -> SimulationCheck:
    t = np.arange(0.0, s.sim_duration, s.sim_dt)
    x0 = np.zeros(2 * truth.n_modes)
    x0[mode] = s.deflection  # truth state [u, u']
    kw = dict(actuator_omega=s.actuator_omega, actuator_zeta=s.actuator_zeta,
              sensor="displacement")
    ol = closed_loop_truth(truth, K, V, t, x0, lambda tt: 0.0, **kw)["zm"]
    cl = closed_loop_truth(truth, K, V, t, x0, lambda tt: 1.0, **kw)["zm"]
    if not (np.all(np.isfinite(ol)) and np.all(np.isfinite(cl))):
        raise CasflutterError(f"the truth simulation at V = {V:.4f} blew up; shorten "
                              "sim_duration or lower sim_factor")
    A_cl = truth_loop_matrix(truth, K, V, actuator_omega=s.actuator_omega,
                             actuator_zeta=s.actuator_zeta)
    return SimulationCheck("truth", float(V), t, ol, cl, _rate(t, ol), _rate(t, cl),
                           _abscissa(truth.state_matrix(V)), _abscissa(A_cl))


def _identify_near_flutter(truth, s: FlutterCheckSettings, rs: RomSettings):
    """Step 1 of the module docstring: identify at V0, then at the ROM's Vf until they agree."""
    structure = structure_of(truth)
    V0, history = s.V0, []
    for _ in range(s.v0_iterations):
        r = replace(rs, V0=V0)
        data = truth_records(truth, V0, dt=r.dt, duration=r.duration, band=r.band,
                             amplitude=r.amplitude, taper=r.taper, flap=True)
        ident = identify_common_denominator(data, r.na, r.nb)
        system = rom_system(ident.model, structure, warn_unstable=False)
        fl = find_flutter(system, r.V_range, n_grid=r.n_grid)
        if fl.Vf is None:
            raise CasflutterError(f"the ROM identified at V0 = {V0:.4f} has no flutter in "
                                  f"{r.V_range}: {fl.message}")
        history.append((float(V0), float(fl.Vf)))
        if abs(fl.Vf - V0) <= s.v0_rtol * fl.Vf:
            break
        V0 = float(fl.Vf)
    return r, tuple(history), ident, system, fl


def flutter_check(truth, settings: FlutterCheckSettings | None = None, *,
                  problem: str = "typical_section",
                  route: RomSettings | None = None) -> FlutterCheckResult:
    """Design a fixed-order flutter-suppression controller on the ROM and check it (module
    docstring; issue 4, "A flutter check").

    Parameters
    ----------
    truth : casflutter.truth.AeroelasticTruth
        The full-order simulator (e.g. ``TypicalSection()``); its sensor rows are the
        measurements, its flap the control.
    settings : FlutterCheckSettings, optional
        Default :func:`flutter_check_settings` of ``problem``.
    problem : str
        Problem name for the default settings and the ROM route (:func:`rom_settings`).
    route : RomSettings, optional
        ROM route settings (default ``rom_settings(problem)``, with ``settings.duration``).

    Returns
    -------
    FlutterCheckResult
        Carries every number; ``.success`` says whether the issue's targets are met (a
        result, not an exception, so that a failed check can be reported).

    Raises
    ------
    CasflutterError
        No flutter of the ROM or of the truth in the analysis range, or a simulation that
        blew up.
    casflutter.errors.SynthesisError
        No synthesis start stabilised the design plants.
    """
    from ..design import SynthesisOptions, synthesize
    from ..verify import speed_sweep, verify_controller

    t_all = time.perf_counter()
    s = settings or flutter_check_settings(problem)
    rs = route or rom_settings(problem)
    if s.duration is not None:
        rs = replace(rs, duration=s.duration)
    timings = {}
    t0 = time.perf_counter()
    rs, history, ident, system, fl = _identify_near_flutter(truth, s, rs)
    timings["rom"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = truth_flutter(truth, rs.V_range, rs.n_grid)
    if tr.Vf is None:
        raise CasflutterError(f"the truth has no flutter in {rs.V_range}: {tr.message}")
    timings["truth_flutter"] = time.perf_counter() - t0
    Vf = float(fl.Vf)
    t0 = time.perf_counter()
    lft = build_lft(system, Vf)
    plants = [build_lft(system, f * Vf).plant_without_d22() for f in s.speed_factors]
    opts = SynthesisOptions(max_outer=s.max_outer,
                            stability_margin=s.stability_margin,
                            max_stab_rounds=s.max_stab_rounds, ipopt=dict(s.ipopt))
    syn = synthesize(plants if len(plants) > 1 else plants[0], lft.nmeas, lft.ncon, s.order,
                     starts=s.starts, seed=s.seed, options=opts)
    K = lft.physical_controller(syn.controller)
    timings["synthesis"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ver = verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta)
    rom_sw = speed_sweep(lft.P, K, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta,
                         V=np.linspace(0.0, 1.5 * Vf, 601))
    timings["verification"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    tsw = _truth_sweep(truth, K, float(tr.Vf), s)
    timings["truth_sweep"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rsim = _rom_simulation(ident, system, lft, K, s.sim_factor * Vf, _mode(fl), s)
    tsim = _truth_simulation(truth, K, s.sim_factor * float(tr.Vf), _mode(tr), s)
    timings["simulation"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_all
    return FlutterCheckResult(settings=s, rom_settings=rs, v0_history=history,
                              identification=ident, system=system, rom_flutter=fl,
                              truth_flutter=tr, lft=lft, synthesis=syn, controller=K,
                              verification=ver, rom_sweep=rom_sw, truth_sweep=tsw,
                              rom_simulation=rsim, truth_simulation=tsim, timings=timings)
