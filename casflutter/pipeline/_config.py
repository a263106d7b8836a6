"""The configuration of a study run: one TOML file, one table per stage.

Each table is the stage's own settings class, so a field a stage adds is a key at once:

============== ==============================================================================
table          settings
============== ==============================================================================
``[problem]``  the truth: a problem name and parameter changes (:func:`casflutter.truth.load_problem`)
``[data]``     the chirp records (:class:`casflutter.truth.RecordSettings`)
``[rom]``      the identification (:class:`casflutter.ident.IdentificationSettings`, the HWL
               orders or the common-denominator orders), the order of Σf and the iteration
               of the identification speed to the ROM's own flutter speed
``[flutter]``  the Hopf search (:func:`casflutter.aeroelastic.find_flutter`)
``[lco]``      the nonlinear ROM and truth simulations above flutter (paper Fig. 9)
``[controller]`` the synthesis (:class:`casflutter.design.SynthesisOptions`) with the order,
               the starts and the design speeds
``[verify]``   targets and sweeps of the verification
``[closed_loop]`` simulations and a truth sweep of the closed loops above flutter
``[suppression]`` the gain-ramp runs on the truth, one per speed, in turbulence
               (:class:`casflutter.truth.SuppressionSettings`)
``[parametric]`` the parametric ROM (ROMs at several speeds, interpolated in V)
``[sensors]``  the sensor rows ``Hs`` (eq. 7) and their kind
``[solver]``   flat Ipopt options for every NLP
============== ==============================================================================

The defaults of every key are the paper's study on the seed wing,
``problems/seed_wing/run_paper.toml``: an empty configuration runs that study (a test keeps
the two equal).  The default configuration, ``problems/seed_wing/run.toml``
(:func:`default_config_path`), changes the controller (designed over speed on the ROM that
follows the wing) and the tunnel of the suppression runs.

``stages`` lists the optional stages to run after the flutter search; the records, the ROM,
Σf, ΣAE and the flutter speeds of the ROM and the truth always run.  Every value is checked
before any work (:func:`casflutter._settings.build_settings`): unknown keys, wrong types and
impossible values fail with a :class:`~casflutter.errors.ConfigError` naming the key.
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import ClassVar

from .._nlp import check_solver_options
from .._resources import problems_dir, read_toml
from .._settings import build_settings, finite_numbers, set_dotted
from ..design import SynthesisOptions
from ..errors import CasflutterError, ConfigError
from ..ident import HWLOrders, IdentificationSettings
from ..structure import SENSOR_KINDS, check_sensor_rows
from ..truth import (AeroelasticTruth, RecordSettings, SuppressionSettings, file_problem_names,
                     load_problem, problem_definition, problem_names)
from ..truth._registry import FILE_KINDS
from ..verify import load_controller

__all__ = ["RunConfig", "ProblemSection", "DataSection", "RomSection", "FlutterSection",
           "LcoSection", "ControllerSettings", "VerifySection", "ClosedLoopSection",
           "SuppressionSection", "ParametricSection", "SensorsSection", "SolverSection", "STAGES", "load_config",
           "default_config_path", "config_path", "flutter_config", "problem_route_settings"]

#: Optional stages, in the order they run (``RunConfig.stages``).
STAGES = ("frozen", "parametric", "lco", "controller", "closed_loop", "suppression")

#: Keys that were renamed: old dotted name -> new one.
_RENAMED = {"data.band_hz": "data.band", "flutter.vrange": "flutter.V_range",
            "controller.speed_factors": "controller.speeds",
            "suppression.speed_factor": "suppression.speed_factors"}


def _positive(name: str, value) -> None:
    if not value > 0:
        raise ConfigError(f"{name} = {value!r}: must be > 0")


def _integer(name: str, value, low: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise ConfigError(f"{name} = {value!r}: must be an integer >= {low}")


@dataclass(frozen=True)
class ProblemSection:
    """``[problem]``: which truth, and its parameter changes."""

    name: str = "seed_wing"
    """A problem name (``casflutter problems``) or the path of a problem TOML file: a rig
    section, or a wing file without a simulator (``kind = "wing"`` with records, ``"gaf"``
    with ``Q(ik)``; :class:`casflutter.truth.WingProblem`); a relative path is looked up
    beside the configuration file first."""
    set: dict = field(default_factory=dict)
    """Parameter changes ``{name = value}``, checked by the truth's parameter class."""

    #: what a key that is not one of the table's was probably meant as
    key_hints: ClassVar[dict] = dict.fromkeys(
        ("file", "path", "problem", "family"),
        'a problem file is named by name: name = "FILE.toml", looked up beside this '
        "configuration")

    def __post_init__(self):
        try:
            load_problem(self.name)
        except ConfigError as exc:
            if not str(exc).startswith("unknown problem"):
                raise ConfigError(f"name = {self.name!r}: {exc}") from None
            raise ConfigError(f"name = {self.name!r}: allowed "
                              f"{', '.join(problem_names() + file_problem_names())}, or a "
                              "problem TOML file") from None
        try:
            load_problem(self.name, self.set)
        except ConfigError as exc:
            raise ConfigError(f"set: {exc}") from None

    def load(self):
        """The truth simulator (:func:`casflutter.truth.load_problem`).

        Returns
        -------
        AeroelasticTruth
        """
        return load_problem(self.name, self.set)


@dataclass(frozen=True)
class DataSection(RecordSettings):
    """``[data]``: the chirp records of the truth (:class:`casflutter.truth.RecordSettings`).

    The run's records model the loosely coupled CFD time march of the paper (the force of
    step k is computed on the grid of step k-1), hence a default coupling delay of one
    sample.
    """

    coupling_delay: int = 1


@dataclass(frozen=True)
class RomSection(IdentificationSettings):
    """``[rom]``: the identified ROM (:class:`casflutter.ident.IdentificationSettings`), its
    orders, the order of Σf and the iteration of the identification speed."""

    orders: list = field(default_factory=lambda: [3, 1, 1, 1, 2, 2])
    """HWL orders ``[mu, na, nb, r, p, q]`` (``method = "hwl"``; paper Table I)."""
    regularization: float = 1e-6
    """Tikhonov weight of stage 2 (:class:`casflutter.ident.IdentificationSettings`); the
    seed wing's study keeps stage 2 converging on its weakly excited nonlinear terms."""
    nf: int | str = 15
    """Order of Σf (ERA, eq. 5), or ``"auto"`` for the exact (minimal) order."""
    method: str = "hwl"
    """``"hwl"``: :func:`casflutter.ident.identify` (two stages, Ipopt);
    ``"common_denominator"``: :func:`casflutter.ident.identify_common_denominator` (the linear
    ROM with one scalar denominator, exact for linear Wagner aerodynamics)."""
    na: int = 2
    """Denominator order of the common-denominator ROM (2: Jones' two-lag Wagner function)."""
    nb: int = 6
    """Largest input lag of the common-denominator ROM."""
    v0_iterations: int = 1
    """Identifications at most: the first at ``data.V0``, each further one at the previous
    ROM's flutter speed (``V0 <- Vf``), until the two agree to ``v0_rtol``; at the fixed point
    the ROM equals the truth at its flutter speed."""
    v0_rtol: float = 2e-3
    """Stop when ``|Vf - V0| <= v0_rtol Vf``."""
    convective: bool = False
    """Scale Σf's time with the speed, ``Σf(s; V) = Σf(s V0 / V)``
    (:class:`casflutter.aeroelastic.AeroelasticSystem` ``convective_V0``): the aerodynamics of
    strip theory depend on the reduced frequency, so one ROM identified at ``V0`` holds at
    every speed.  ``false`` is eq. 8 as the paper writes it (Σf frozen at ``V0``, forces
    scaled by V²).  With the ``controller`` stage the design is made on the LFT frozen at Vf
    (exact there) and the ROM's exact stable interval is certified on the scaled loop with
    the flap behind the servo (``RunResult.rom_interval``); the stages that simulate the
    ROM's sampled loop (``lco``, ``closed_loop``, ``suppression``) take Σf frozen and are
    refused."""

    def __post_init__(self):
        super().__post_init__()
        if not isinstance(self.convective, bool):
            raise ConfigError(f"convective = {self.convective!r}: true or false")
        if self.method not in ("hwl", "common_denominator"):
            raise ConfigError(f"method = {self.method!r}: allowed 'hwl', 'common_denominator'")
        o = self.orders
        if len(o) != 6 or not all(isinstance(x, int) and not isinstance(x, bool) for x in o):
            raise ConfigError(f"orders = {o!r}: give six integers [mu, na, nb, r, p, q]")
        try:
            HWLOrders.from_tuple(o)
        except ValueError as exc:
            raise ConfigError(f"orders = {o!r}: {exc}") from None
        nf = self.nf
        if not (nf == "auto" or (isinstance(nf, int) and not isinstance(nf, bool) and nf >= 1)):
            raise ConfigError(f"nf = {nf!r}: a positive integer or \"auto\"")
        _integer("na", self.na, 1)
        _integer("nb", self.nb, 1)
        _integer("v0_iterations", self.v0_iterations, 1)
        _positive("v0_rtol", self.v0_rtol)
        object.__setattr__(self, "ipopt_options",
                           check_solver_options(self.ipopt_options, "ipopt_options"))


@dataclass(frozen=True)
class FlutterSection:
    """``[flutter]``: the Hopf search of :func:`casflutter.aeroelastic.find_flutter` on the
    ROM and the truth."""

    V_range: tuple = (0.3, 2.5)
    """Speed-index range ``[low, high]``."""
    n_grid: int = 111
    """Points of the uniform V grid."""
    max_refine: int = 3
    """Largest number of grid refinements of the eigenvalue tracking (identical strips give
    repeated lag eigenvalues whose eigenvector matching stays ambiguous however fine the
    grid, without changing any crossing)."""

    def __post_init__(self):
        vr = finite_numbers("V_range", self.V_range, 2, what="[low, high]")
        if not 0 <= vr[0] < vr[1]:
            raise ConfigError(f"V_range = {list(vr)!r}: [low, high] with 0 <= low < high")
        object.__setattr__(self, "V_range", vr)
        _integer("n_grid", self.n_grid, 3)
        _integer("max_refine", self.max_refine, 0)


@dataclass(frozen=True)
class LcoSection:
    """``[lco]``: the nonlinear ROM in the loop and the truth above their flutter speeds
    (paper Fig. 9), from a deflected flutter mode."""

    duration: float = 10.0
    """Length of the simulations."""
    initial_deflection: float = 0.01
    """Initial deflection of the flutter mode (also the tap of the suppression run)."""
    speed_factor: float = 1.05
    """Simulate at ``speed_factor`` times each model's own Hopf speed: exactly at the Hopf
    point the linear damping is zero and the approach to the LCO is infinitely slow."""
    branch_points: int = 20
    """Points of the ROM loop's and the truth's LCO branches from their flutter points
    (:mod:`casflutter.lco`, the bifurcation diagrams of the report); 0: none."""
    speed_following_factors: tuple = (1.05, 1.2)
    """Multiples of the truth's flutter speed at which the LCO of the ROM that follows the
    wing over speed (:func:`casflutter.lco.compare_lco`) is put beside the truth's, when the
    run has both; ``[]``: none."""
    workers: int = 0
    """Processes for the stage's independent computations (the truth's simulations and each
    LCO branch): 0, up to the machine's cores; 1, all in this process.  The numbers do not
    depend on it."""

    def __post_init__(self):
        for name in ("duration", "initial_deflection", "speed_factor"):
            _positive(name, getattr(self, name))
        factors = finite_numbers("speed_following_factors", self.speed_following_factors,
                                 what="multiples of the truth's flutter speed")
        if not all(f > 0 for f in factors):
            raise ConfigError(f"speed_following_factors = {list(factors)!r}: every factor "
                              "must be > 0")
        object.__setattr__(self, "speed_following_factors", tuple(factors))
        _integer("branch_points", self.branch_points, 0)
        _integer("lco.workers", self.workers, 0)
        if 0 < self.branch_points < 3:
            raise ConfigError(f"branch_points = {self.branch_points}: give 0 (no branches) or "
                              "at least 3")


@dataclass(frozen=True)
class ControllerSettings(SynthesisOptions):
    """``[controller]``: the fixed-order controller and its design (paper §III.C), with the
    H∞ settings of :class:`casflutter.design.SynthesisOptions`."""

    method: str = "auto"
    """``"multispeed"``: one controller that keeps the run's loop family decaying over
    ``interval`` with the smallest worst H∞ objective over the speeds
    (:func:`casflutter.design.design_over_speeds`).  ``"paper"``: the paper's design, γ of
    the LFT at Vf (eq. 14-16) with the flap-rate weight, its interval only measured.
    ``"auto"``: ``"multispeed"`` on a plant family and on a ROM whose time follows the
    speed (``rom.convective``), ``"paper"`` on the paper's frozen ROM of eq. 8.  On the HWL
    ROM (``rom.method = "hwl"``) ``"multispeed"`` designs on the ROM made to follow the wing
    over speed (:attr:`casflutter.pipeline.ModelStage.speed_following`), not on the frozen
    loop of eq. 8, which misplaces the flutter mode's control reversal; the paper's γ (the
    LFT at the frozen loop's Vf) stays its H∞ objective (``hinf_objective = "auto"``)."""
    order: int = 3
    """Controller order (the paper's 3)."""
    interval: tuple = (0.05, 2.4)
    """``[lo, hi]`` over which the loop must decay (``method = "multispeed"``), in the
    family's speed unit (the speed index for a ROM loop)."""
    interval_decay: float | None = None
    """Decay rate [rad per time unit] required of the closed loop at every speed of
    ``interval``; left out: 0.05, or half the rate of the open loop's slowest decaying mode
    at the interval's low end, or of the family's slowest mode that no controller moves,
    where that is slower (:class:`casflutter.design.MultiSpeedSettings`)."""
    n_speeds: int = 16
    """Speeds of the stability objective on each interval the design tries (its dense
    check uses 8x as many)."""
    hinf_speeds: int = 5
    """Speeds of the multi-speed H∞ objective (each speed's disturbance-to-sensor channels
    with the flap-rate weight); 0: stability only."""
    hinf_objective: str = "auto"
    """H∞ objective of the multi-speed design once the interval is held: ``"lft"`` the
    paper's, γ of the LFTs at ``speeds`` x Vf (eq. 14-16) with the flap-rate weight, so its
    γ compares with the paper's design; ``"sensors"`` each of ``hinf_speeds`` speeds'
    disturbance-to-sensor channels; ``"sensitivity"`` each of those speeds' output and
    input sensitivities, which bound every loop-at-a-time margin (sensors and controls);
    ``"auto"``: ``"lft"`` where the run has a ROM loop with a flutter speed, else
    ``"sensors"`` where the family names disturbance inputs, else ``"sensitivity"``."""
    random_starts: int = 2
    """Seeded random starts of the multi-speed design at the target order."""
    full_order: bool = False
    """When no start at the target order holds the interval: continue a full-order LQG
    controller down from the top and lower its order (minutes, not seconds)."""
    reduction_orders: tuple = (20, 14, 10, 8, 6)
    """Intermediate orders of that order continuation (those between ``order`` and the full
    order are used, highest first)."""
    speeds: tuple = (1.0,)
    """The paper's design (``method = "paper"``): the speeds of its design plants as
    multiples of Vf, containing 1.0 (the plant the verification checks); the LFT (eq. 14) is
    built at each and the worst-case norm minimised.  ``[1.0]`` is the paper's design."""
    servo_omega: float = 251.3
    """Natural frequency [rad per time unit] of the flap servo in front of a ROM loop and of
    the truth's linearisation in the design and the verification (the seed wing's 40 Hz);
    0: the flap is ideal."""
    margins: tuple = (6.0, 45.0)
    """Gain (dB) and phase (degrees) margins of the robust flutter speed
    (:func:`casflutter.verify.verify_family`)."""
    starts: int = 4
    """Starts of the paper's synthesis (the first is the zero controller unless
    ``zero_start`` is false, the others seeded random)."""
    strictly_proper: bool = True
    """``Dk = 0`` (:class:`casflutter.design.SynthesisOptions`): the seed wing's
    accelerometers see the flap directly, and any ``Dk`` makes its loop algebraically
    singular at some speed above Vf."""
    zero_start: bool = False
    """The first start of the paper's synthesis is the zero controller (otherwise every start
    is seeded random)."""
    max_outer: int = 80
    """H∞ iterations per start (:class:`casflutter.design.SynthesisOptions`)."""
    extra_outer: int = 320
    """Further H∞ iterations, spent only while γ still falls by more than 1 % in thirty
    (:class:`casflutter.design.SynthesisOptions`): on two aircraft-like families whose held
    controller leaves a sensitivity in the hundreds, the worst sensitivity then fell to a
    median of 1.5-1.7 where 80 iterations left 4.7-5.5 (docs/theory.rst)."""
    max_stab_rounds: int = 300
    """Stabilisation rounds per start (:class:`casflutter.design.SynthesisOptions`)."""
    flap_rate_weight: float = 0.003
    """Weight ``w`` of the flap rate in the H∞ plants (per rad/s of flap rate); 0: none.  The
    seed wing's servo saturates at 300°/s; without the weight a controller asks far more to
    hold the established LCO."""
    flap_rate_bandwidth: float = 251.3
    """Bandwidth of the flap-rate filter [rad per time unit] (the seed wing's 40 Hz servo)."""
    start: str = ""
    """A controller file to start the design from (empty: none): a run's
    ``controller.json``, or ``A, B, C, D`` in JSON with optional ``inputs``, ``outputs`` and
    ``feedback`` (:func:`casflutter.verify.match_controller`), of order at most ``order``
    (padded with decoupled stable states).  It is matched to the design family's
    measurements and controls by name and turned into the family's convention; the
    multi-speed design continues it first (its record says ``"given"``), the paper's
    synthesis starts from it.  A relative path is looked up beside the configuration file
    first.  What to start from when a model is updated: the controller of the last design."""

    def __post_init__(self):
        super().__post_init__()
        _integer("order", self.order, 0)
        if not isinstance(self.start, str):
            raise ConfigError(f"controller.start = {self.start!r}: the path of a controller "
                              "file (a string), or \"\" for none")
        if self.start:
            _check_start(self.start, self.order)
        for key in ("flap_rate_weight", "flap_rate_bandwidth", "servo_omega"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isfinite(value) and value >= 0):
                raise ConfigError(f"controller.{key} = {value!r}: a finite number >= 0")
        if self.flap_rate_weight > 0 and not self.flap_rate_bandwidth > 0:
            raise ConfigError(f"controller.flap_rate_bandwidth = {self.flap_rate_bandwidth!r}: "
                              "> 0 when flap_rate_weight > 0")
        _integer("starts", self.starts, 1)
        _integer("random_starts", self.random_starts, 0)
        sp = finite_numbers("speeds", self.speeds, what="a non-empty list of positive "
                            "multiples of Vf, containing 1.0")
        if not sp or not all(x > 0 for x in sp) or 1.0 not in sp:
            raise ConfigError(f"speeds = {list(sp)!r}: a non-empty list of positive multiples "
                              "of Vf, containing 1.0 (the nominal plant)")
        object.__setattr__(self, "speeds", sp)
        _integer("hinf_speeds", self.hinf_speeds, 0)
        iv = finite_numbers("interval", self.interval, what="[lo, hi] speeds")
        if len(iv) != 2 or not 0 <= iv[0] < iv[1]:
            raise ConfigError(f"controller.interval = {list(iv)!r}: [lo, hi] speeds with "
                              "0 <= lo < hi")
        object.__setattr__(self, "interval", iv)
        _integer("n_speeds", self.n_speeds, 2)
        if self.hinf_objective not in ("auto", "lft", "sensors", "sensitivity"):
            raise ConfigError(f"controller.hinf_objective = {self.hinf_objective!r}: allowed "
                              "'auto', 'lft', 'sensors', 'sensitivity'")
        if self.method not in ("auto", "multispeed", "paper"):
            raise ConfigError(f"controller.method = {self.method!r}: allowed 'auto', "
                              "'multispeed', 'paper'")
        if self.strictly_proper and self.order < 1:
            raise ConfigError(f"controller.order = {self.order!r} with strictly_proper = true "
                              "(the default) leaves no controller (D = 0 and no states): for "
                              "a static gain set strictly_proper = false, or give order >= 1")
        ro = self.reduction_orders
        if isinstance(ro, (str, bytes)) or not all(
                isinstance(o, int) and not isinstance(o, bool) and o >= 1 for o in ro):
            raise ConfigError(f"controller.reduction_orders = {ro!r}: a list of integers >= 1")
        object.__setattr__(self, "reduction_orders", tuple(ro))
        if self.interval_decay is not None and not (
                isinstance(self.interval_decay, (int, float))
                and not isinstance(self.interval_decay, bool)
                and math.isfinite(self.interval_decay) and self.interval_decay >= 0):
            raise ConfigError(f"interval_decay = {self.interval_decay!r}: a number >= 0 (or "
                              "leave it out to have it chosen)")
        mg = finite_numbers("margins", self.margins, 2, what="[gain margin dB, phase margin deg]")
        if not (mg[0] >= 0 and 0 <= mg[1] <= 180):
            raise ConfigError(f"controller.margins = {list(mg)!r}: a gain margin >= 0 dB and a "
                              "phase margin in [0, 180] degrees")
        object.__setattr__(self, "margins", mg)
        object.__setattr__(self, "ipopt", check_solver_options(self.ipopt, "ipopt"))


@dataclass(frozen=True)
class VerifySection:
    """``[verify]``: targets and sweeps of the independent verification (eq. 10-16)."""

    required: tuple = ()
    """``[lo, hi]``: the verified exact stable interval must contain ``[lo, hi] Vf``
    (``RunResult.interval_ok``); empty: no target."""
    sweep: tuple = ()
    """``[lo, hi]``: also a dense eigenvalue sweep of the ROM loop over ``[lo, hi] Vf``
    (:func:`casflutter.verify.speed_sweep`); empty: none."""
    n_sweep: int = 601
    """Points of that sweep."""
    require_margins: bool = False
    """Whether the controller's loop-at-a-time margins (``controller.margins``) must also
    hold over the required interval for the run's checks to pass, as ``casflutter verify
    --require-v`` asks (``RunResult.robust_ok``); false: they are reported beside the
    certified interval, not required."""

    def __post_init__(self):
        if not isinstance(self.require_margins, bool):
            raise ConfigError(f"require_margins = {self.require_margins!r}: true or false")
        for name in ("required", "sweep"):
            v = getattr(self, name)
            if len(v):
                v = finite_numbers(name, v, 2, what="[lo, hi] multiples of Vf")
                if not 0 <= v[0] < v[1]:
                    raise ConfigError(f"{name} = {list(v)!r}: [lo, hi] with 0 <= lo < hi")
            object.__setattr__(self, name, tuple(v))
        if self.required and not self.required[0] < 1 < self.required[1]:
            raise ConfigError(f"required = {list(self.required)!r}: lo < 1 < hi")
        _integer("n_sweep", self.n_sweep, 10)


@dataclass(frozen=True)
class ClosedLoopSection:
    """``[closed_loop]``: the loops above flutter, open and closed with the controller: the
    discrete ROM in the loop and the sampled-data truth with a flap actuator, simulated at
    ``speed_factor`` times each model's flutter speed from a deflection of its flutter mode,
    and the truth's linear closed loop swept over speed."""

    speed_factor: float = 1.1
    """Simulation speed as a multiple of the flutter speed (above it)."""
    duration: float = 150.0
    """Length of each simulation."""
    dt: float = 0.05
    """Sample time of the sampled-data truth loop (the ROM runs at its own dt)."""
    deflection: float = 0.01
    """Initial deflection of the flutter mode."""
    actuator_omega: float = 10.0
    """Natural frequency of the truth's flap actuator [rad per time unit]; the ROM has none."""
    actuator_zeta: float = 0.7
    """Damping ratio of the flap actuator."""
    sweep_range: tuple = (0.02, 1.6)
    """Range of the truth's closed-loop sweep, as multiples of its flutter speed."""
    n_sweep: int = 400
    """Points of that sweep."""

    def __post_init__(self):
        if not self.speed_factor > 1:
            raise ConfigError(f"speed_factor = {self.speed_factor!r}: must be > 1 (above "
                              "flutter)")
        for name in ("duration", "dt", "actuator_omega"):
            _positive(name, getattr(self, name))
        if self.deflection == 0:
            raise ConfigError("deflection = 0: a loop at rest stays at rest; give a deflection")
        if self.actuator_zeta < 0:
            raise ConfigError(f"actuator_zeta = {self.actuator_zeta!r}: must be >= 0")
        sr = finite_numbers("sweep_range", self.sweep_range, 2, what="[lo, hi] multiples of "
                            "the flutter speed")
        if not 0 < sr[0] < 1 < sr[1]:
            raise ConfigError(f"sweep_range = {list(sr)!r}: [lo, hi] with 0 < lo < 1 < hi")
        object.__setattr__(self, "sweep_range", sr)
        _integer("n_sweep", self.n_sweep, 10)


@dataclass(frozen=True)
class ParametricSection:
    """``[parametric]``: the parametric ROM (:class:`casflutter.realize.ParametricROM`):
    common-denominator ROMs identified at Chebyshev–Lobatto speeds over ``flutter.V_range``
    with the records of ``[data]``, interpolated in V."""

    n_speeds: int = 7
    """Number of identification speeds."""
    max_refine: int = 2
    """Grid refinements of its flutter search (the delay states of the canonical form make
    defective blocks at ``s = -2/dt`` whose eigenvectors cannot be matched)."""

    def __post_init__(self):
        _integer("n_speeds", self.n_speeds, 2)
        _integer("max_refine", self.max_refine, 0)


@dataclass(frozen=True)
class SensorsSection:
    """``[sensors]``: the measured outputs ``zm`` (eq. 7), used by every stage: Σs in the ROM
    loop, the LFT's measured output (eq. 14), the truth's LCO and the closed-loop runs."""

    rows: list = field(default_factory=list)
    """``Hs``: one row of N numbers (the mode shapes at the sensor, in its measuring
    direction) per sensor; empty: the problem's own rows."""
    kind: str = "acceleration"
    """``"acceleration"`` (``zm = Hs u''``, the paper's accelerometers), ``"velocity"`` or
    ``"displacement"``."""

    def __post_init__(self):
        if self.kind not in SENSOR_KINDS[:3]:
            raise ConfigError(f"kind = {self.kind!r}: allowed "
                              f"{', '.join(map(repr, SENSOR_KINDS[:3]))}")


@dataclass(frozen=True)
class SolverSection:
    """``[solver]``: flat Ipopt options for every NLP (``"ipopt.tol" = 1e-8``), under each
    stage's own (``rom.ipopt_options``, ``controller.ipopt``)."""

    ipopt: dict = field(default_factory=dict)
    """Options by CasADi name: ``ipopt.NAME`` is checked against the installed Ipopt's own
    option list (name, type, range, settings), the others are CasADi's ``nlpsol`` options."""

    def __post_init__(self):
        object.__setattr__(self, "ipopt", check_solver_options(self.ipopt, "ipopt"))


@dataclass(frozen=True)
class SuppressionSection(SuppressionSettings):
    """``[suppression]``: the gain-ramp runs on the truth
    (:class:`casflutter.truth.SuppressionSettings`, one per entry of ``speed_factors``) with
    the seed wing's study phases, the flap servo of a wind-tunnel model (±15 deg,
    300 deg/s), and a tunnel's turbulence and sensor noise."""

    speed_factors: tuple = (1.05, 1.2)
    """Multiples of the truth's own flutter speed, one run at each, each from the truth's
    established LCO there."""
    settle: float = 6.0
    """Open-loop time before the ramp."""
    ramp: float = 3.0
    """Length of the gain ramp 0 -> 1."""
    hold: float = 6.0
    """Closed-loop time at full gain."""
    release: float = 25.0
    """Longest open-loop time after the release: long enough for the LCO to grow back from
    the tap to half its RMS at 1.05 Vf, where it grows slowly (a run ends as soon as it is
    back)."""
    flap_limit: float | None = 0.2618
    """Flap position limit [rad] (15 deg); from Python ``None`` for no limit."""
    flap_rate_limit: float | None = 5.236
    """Flap rate limit [rad/s] (300 deg/s); from Python ``None`` for no limit."""
    gust_intensity: float = 0.005
    """Turbulence intensity ``σ_w / U`` of the vertical gust (0.5 %, a low-speed tunnel with
    screens); 0 for none."""
    gust_scale: float = 0.1
    """Integral scale ``L_w`` of the turbulence [m]."""
    noise: float = 0.1
    """Rms of each sensor's noise [sensor unit: m/s² for the seed wing's accelerometers]."""
    workers: int = 0
    """Processes for the runs: 0, one per speed factor up to the machine's cores; 1, every
    run in this process.  Each run is seeded on its own, so the numbers do not depend on
    it."""

    def __post_init__(self):
        super().__post_init__()
        _integer("suppression.workers", self.workers, 0)


@dataclass(frozen=True)
class RunConfig:
    """The whole configuration of a run; each field is one TOML table (module docstring).

    Attributes
    ----------
    problem : ProblemSection
        ``[problem]``: the truth or problem file and its parameter changes.
    data : DataSection
        ``[data]``: the identification records.
    rom : RomSection
        ``[rom]``: the identification of the ROM and its realisation.
    flutter : FlutterSection
        ``[flutter]``: the flutter search.
    lco : LcoSection
        ``[lco]``: the LCO simulations and branches.
    controller : ControllerSettings
        ``[controller]``: the robust synthesis.
    verify : VerifySection
        ``[verify]``: the verification's speed grid.
    closed_loop : ClosedLoopSection
        ``[closed_loop]``: the closed-loop simulations on the ROM and the truth.
    suppression : SuppressionSettings
        ``[suppression]``: the gain ramp on the truth (paper Fig. 11).
    parametric : ParametricSection
        ``[parametric]``: the ROM interpolated in the speed.
    sensors : SensorsSection
        ``[sensors]``: the sensor rows and kind.
    solver : SolverSection
        ``[solver]``: Ipopt options.
    seed : int
        Seed of every random choice of the run.
    stages : tuple of str
        The optional stages to run (``"lco"``, ``"controller"``, ``"suppression"``, ...).
    """

    problem: ProblemSection = field(default_factory=ProblemSection)
    data: DataSection = field(default_factory=DataSection)
    rom: RomSection = field(default_factory=RomSection)
    flutter: FlutterSection = field(default_factory=FlutterSection)
    lco: LcoSection = field(default_factory=LcoSection)
    controller: ControllerSettings = field(default_factory=ControllerSettings)
    verify: VerifySection = field(default_factory=VerifySection)
    closed_loop: ClosedLoopSection = field(default_factory=ClosedLoopSection)
    suppression: SuppressionSection = field(default_factory=SuppressionSection)
    parametric: ParametricSection = field(default_factory=ParametricSection)
    sensors: SensorsSection = field(default_factory=SensorsSection)
    solver: SolverSection = field(default_factory=SolverSection)
    seed: int = 0
    stages: tuple = ("lco", "controller", "suppression")

    def __post_init__(self):
        _integer("seed", self.seed, 0)
        stages = tuple(self.stages)
        bad = [s for s in stages if s not in STAGES]
        if bad:
            raise ConfigError(f"stages: unknown stage {bad[0]!r}; allowed {', '.join(STAGES)}")
        for later in ("closed_loop", "suppression"):
            if later in stages and "controller" not in stages:
                raise ConfigError(f"stages: {later!r} needs the 'controller' stage")
        if "parametric" in stages and self.rom.method != "common_denominator":
            raise ConfigError("stages: 'parametric' interpolates common-denominator ROMs; set "
                              "rom.method = \"common_denominator\"")
        frozen_only = [s for s in ("lco", "closed_loop", "suppression") if s in stages]
        if self.rom.convective and frozen_only:
            raise ConfigError(f"rom.convective = true scales Σf's time with V, but stage "
                              f"{frozen_only[0]!r} simulates the sampled ROM loop, whose "
                              "time is frozen at V0; set rom.convective = false or leave "
                              f"{', '.join(map(repr, frozen_only))} out of stages")
        problem = self.problem.load()
        n_modes = getattr(problem, "n_modes", None)    # None: a plant family, no ROM
        if self.controller.method == "auto":
            method = "multispeed" if n_modes is None or self.rom.convective else "paper"
            object.__setattr__(self, "controller", replace(self.controller, method=method))
        multispeed_rom = (self.controller.method == "multispeed" and "controller" in stages
                          and n_modes is not None and not self.rom.convective)
        if multispeed_rom and self.rom.method != "hwl":
            raise ConfigError("controller.method = \"multispeed\" designs on the ROM loop with "
                              "the flap behind the servo at every speed of the interval, which "
                              "the ROM of eq. 8 (Σf frozen at V0) does not stand for: set "
                              "rom.convective = true, or identify the HWL ROM (rom.method = "
                              "\"hwl\"), whose speed-following loop the design then uses")
        if (multispeed_rom and isinstance(problem, AeroelasticTruth)
                and self.rom.orders[3] < self.data.coupling_delay):
            raise ConfigError(f"controller.method = \"multispeed\" designs on the HWL ROM made "
                              f"to follow the wing over speed, which removes the records' "
                              f"coupling delay ({self.data.coupling_delay} sample"
                              f"{'s' if self.data.coupling_delay != 1 else ''}) from the "
                              f"ROM's input delay r = {self.rom.orders[3]}: identify with r >= "
                              f"{self.data.coupling_delay} (rom.orders[3])")
        if self.rom.convective and "controller" in stages and self.verify.sweep:
            raise ConfigError("verify.sweep sweeps the LFT frozen at Vf; with rom.convective "
                              "= true the run certifies the scaled loop itself at every "
                              "speed: leave verify.sweep empty")
        if "closed_loop" in stages and self.sensors.kind != "displacement":
            raise ConfigError("stages: 'closed_loop' sweeps the truth's linear loop read by "
                              "displacement sensors; set sensors.kind = \"displacement\"")
        if "suppression" in stages and self.sensors.kind == "velocity":
            raise ConfigError("stages: 'suppression' reads acceleration or displacement "
                              "sensors; set sensors.kind accordingly")
        object.__setattr__(self, "stages", tuple(s for s in STAGES if s in stages))
        if n_modes is None:
            return
        if self.sensors.rows:
            check_sensor_rows(self.sensors.rows, n_modes, key="sensors.rows",
                              problem=self.problem.name)
        if self.rom.nf != "auto":
            self._check_nf(n_modes)

    def _check_nf(self, n_modes: int) -> None:
        """``rom.nf`` at most the exact order of the ROM's linear part: N modes times its
        largest lag (:func:`casflutter.realize.realize`); a larger Σf is not minimal."""
        r = self.rom
        if r.method == "hwl":
            lag, of = HWLOrders.from_tuple(r.orders).max_lag, f"orders {list(r.orders)}"
        else:  # common denominator: lags na of the outputs, nb of the inputs
            lag, of = max(r.na, r.nb), f"na = {r.na}, nb = {r.nb}"
        bound = n_modes * lag
        if r.nf > bound:
            raise ConfigError(
                f"rom.nf = {r.nf}: at most {bound} here (the linear part of a ROM with {of} "
                f"on the {n_modes} modes of {self.problem.name!r} has at most {n_modes} x "
                f"{lag} = {bound} states: modes x largest lag); give 1..{bound} or \"auto\"")

    def to_dict(self) -> dict:
        """The configuration as nested plain values (``config.json``).

        Returns
        -------
        dict
        """
        return asdict(self)


def config_path(problem: str, name: str = "run") -> Path:
    """The configuration ``problems/PROBLEM/NAME.toml`` shipped with the package.

    Parameters
    ----------
    problem : str
        Problem name.
    name : str
        ``"run"`` (the study), ``"flutter"`` (the ROM route of ``casflutter flutter``),
        ``"flutter_check"`` ...

    Returns
    -------
    Path

    Raises
    ------
    ConfigError
        No such file.
    """
    path = problems_dir() / problem / f"{name}.toml"
    if not path.is_file():
        raise ConfigError(f"problem {problem!r} has no {name} configuration: {path} not found; "
                          "write one (the tables of casflutter.pipeline.RunConfig) or pass a "
                          "configuration file")
    return path


#: The ROM route of ``casflutter flutter`` on a problem without a ``flutter.toml``: the
#: settings every ROM route shares (a problem file's ``[rom]`` table adds its own).
_ROUTE = {"stages": ["frozen", "parametric"], "rom.method": "common_denominator",
          "rom.nf": "auto", "data.coupling_delay": 0, "flutter.max_refine": 8,
          "flutter.n_grid": 201, "sensors.kind": "displacement"}
#: the keys of a problem file's ``[rom]`` table and the configuration keys they set
_ROUTE_KEYS = {"V0": "data.V0", "dt": "data.dt", "duration": "data.duration",
               "band": "data.band", "amplitude": "data.amplitude", "taper": "data.taper",
               "flap": "data.flap", "na": "rom.na", "nb": "rom.nb",
               "V_range": "flutter.V_range", "n_grid": "flutter.n_grid",
               "n_speeds": "parametric.n_speeds"}
#: the ``[rom]`` keys a problem file's ROM route cannot do without
_ROUTE_REQUIRED = ("V0", "V_range", "dt", "duration", "band")
#: the run's keys whose defaults are the seed wing's, in its units (speed index, seconds of
#: its time march) and with its CFD march's coupling delay: on a simulator's problem file
#: (a rig section) its ``[rom]`` table gives them or the run configuration sets them; the
#: coupling delay only the configuration (0 for a simulator's records, as ``casflutter
#: flutter`` takes; 1 for the paper's loosely coupled march, which the input delay r = 1 of
#: the HWL orders of Table I expects)
_PROBLEM_UNIT_KEYS = (*(_ROUTE_KEYS[k] for k in _ROUTE_REQUIRED), "data.coupling_delay")


def problem_route_settings(problem: str) -> dict:
    """The run settings a problem file gives in its own units: its ``[rom]`` table (the keys
    of ``casflutter flutter``'s ROM route).

    The one mapping from a problem file to the run's keys, shared by :func:`flutter_config`
    and :func:`load_config` (which takes each of them that the run configuration leaves
    out).

    Parameters
    ----------
    problem : str
        Problem name or problem file.

    Returns
    -------
    dict
        ``{dotted run key: value}``; empty for a built-in problem and for a problem file
        without a ``[rom]`` table.

    Raises
    ------
    ConfigError
        An unknown key in the ``[rom]`` table (named), or an unknown problem.
    """
    if problem in problem_names():
        return {}
    table = problem_definition(problem).get("rom")
    if not isinstance(table, dict):
        return {}
    unknown = [k for k in table if k not in _ROUTE_KEYS]
    if unknown:
        raise ConfigError(f"unknown key {unknown[0]!r} in the [rom] table of {problem}; "
                          f"allowed: {', '.join(_ROUTE_KEYS)}")
    return {_ROUTE_KEYS[k]: v for k, v in table.items()}


def flutter_config(problem: str, *, updates=None) -> RunConfig:
    """The ROM-route configuration of ``casflutter flutter PROBLEM``.

    ``problems/PROBLEM/flutter.toml`` when the problem has one; otherwise (a problem file,
    e.g. a rig section) the shared route settings with the ``[rom]`` table of the problem's
    definition (``V0``, ``V_range``, ``dt``, ``duration``, ``band`` and optionally
    ``amplitude``, ``taper``, ``flap``, ``na``, ``nb``, ``n_grid``, ``n_speeds``).

    Parameters
    ----------
    problem : str
        Problem name or problem file.
    updates : mapping, optional
        Changes by dotted path (as :func:`load_config`).

    Returns
    -------
    RunConfig
        Validated; its run gives the command's flutter speeds.

    Raises
    ------
    ConfigError
        No route settings for the problem, or an invalid key or value (named).
    """
    if problem in problem_names():
        return load_config(config_path(problem, "flutter"), updates=updates)
    settings = problem_route_settings(problem)
    missing = [k for k in _ROUTE_REQUIRED if _ROUTE_KEYS[k] not in settings]
    if missing:
        raise ConfigError(f"problem {problem} has no ROM-route settings for "
                          f"{', '.join(missing)}: add them to its [rom] table")
    route = {**_ROUTE, **settings, "problem.name": str(problem), **(updates or {})}
    table = {}
    for key, value in route.items():
        set_dotted(table, RunConfig, key, value)
    return build_settings(RunConfig, table)


def default_config_path() -> Path:
    """The default configuration shipped with the package: the seed wing's study, with its
    controller designed over speed (``problems/seed_wing/run.toml``).

    Returns
    -------
    Path
    """
    return config_path("seed_wing", "run")


def _check_start(start: str, order: int) -> None:
    """``controller.start``, read before any work: a controller file of order <= ``order``
    (its names and convention are matched to the design family at the controller stage)."""
    try:
        K = load_controller(start)
    except CasflutterError as exc:
        raise ConfigError(f"controller.start = {start!r}: {exc}; give a controller file (a "
                          "run's controller.json, or A, B, C, D in JSON), absolute or "
                          "relative to the configuration file") from None
    if K.nstates > order:
        raise ConfigError(f"controller.start = {start!r} has order {K.nstates} > "
                          f"controller.order = {order}: start from a controller of that "
                          "order or lower, or raise the order")


def _relative_path(table: dict, section: str, key: str, path: Path) -> None:
    """``[section] key``, a file path relative to the configuration file's folder, becomes
    that path (when it is not a file from the working folder)."""
    sec = table.get(section)
    name = sec.get(key) if isinstance(sec, dict) else None
    if not isinstance(name, str) or not name or Path(name).is_absolute() \
            or Path(name).exists():
        return
    near = path.parent / name
    if near.is_file():
        sec[key] = str(near)


def _relative_problem(table: dict, path: Path) -> None:
    """A ``[problem] name`` that is a path relative to the configuration file's folder (a
    wing file beside its run configuration) becomes that path."""
    prob = table.get("problem")
    name = prob.get("name") if isinstance(prob, dict) else None
    if not isinstance(name, str) or Path(name).is_absolute() or Path(name).exists():
        return
    near = path.parent / name
    if near.is_file() or (near / "problem.toml").is_file():
        prob["name"] = str(near)


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

    Returns
    -------
    RunConfig

    Raises
    ------
    ConfigError
        A missing or malformed file, or any unknown or invalid key (named).

    See Also
    --------
    run : runs the configuration.

    Examples
    --------
    >>> import casflutter as cf
    >>> cfg = cf.load_config(updates={"controller.order": 2}, seed=3)
    >>> cfg.controller.order, cfg.seed, cfg.problem.name
    (2, 3, 'seed_wing')
    """
    path = Path(path) if path is not None else default_config_path()
    table = read_toml(path, "configuration file")
    if table.get("kind") is not None:
        raise ConfigError(f"{path} is a problem file (kind = {table['kind']!r}), not a run "
                          "configuration: write a run configuration whose [problem] name is "
                          f"this file (e.g. problems/example_wing/run.toml), or pass it as "
                          "problem.name")
    _relative_problem(table, path)
    _relative_path(table, "controller", "start", path)
    prob = table.get("problem")
    file_problem = prob.get("name") if isinstance(prob, dict) else None
    table.update({k: v for k, v in overrides.items() if v is not None})
    changed: dict = {}                  # what the updates alone set
    for key, value in (updates or {}).items():
        set_dotted(table, RunConfig, key, value)
        set_dotted(changed, RunConfig, key, value)
    for old, new in _RENAMED.items():
        section, key = old.split(".")
        if isinstance(table.get(section), dict) and key in table[section]:
            raise ConfigError(f"{old} was renamed {new}: rename the key in {path}")
    # a file written for a built-in problem that it names (the seed wing's default file)
    # whose problem the updates change: its values in that problem's units are not the
    # new problem's
    _from_problem_file(table, changed if file_problem in problem_names() else None,
                       file_problem)
    return build_settings(RunConfig, table)


def _given(table: dict, dotted: str) -> bool:
    """Whether the raw configuration ``table`` sets ``dotted`` (``"data.V0"``)."""
    node = table
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return False
        node = node[part]
    return True


def _from_problem_file(table: dict, changed: dict | None = None,
                       file_problem: str | None = None) -> None:
    """A simulator's problem file (a rig section) in its own units: each key of its
    ``[rom]`` table (:func:`problem_route_settings`) that the configuration leaves out is
    taken from the file, as ``casflutter flutter`` takes it; a key of
    :data:`_PROBLEM_UNIT_KEYS` that neither gives is refused, named, before any work (its
    default is the seed wing's, in the seed wing's units).  Nothing changes for a built-in
    problem, a wing file or a family file.  With ``changed`` (the configuration file was
    written for the built-in ``file_problem`` and the updates name the rig), only the
    updates count as setting those keys: the file's values are in the built-in's units."""
    prob = table.get("problem")
    name = prob.get("name") if isinstance(prob, dict) else None
    if not isinstance(name, str) or name in problem_names():
        return
    try:
        kind = problem_definition(name).get("kind")
    except ConfigError:
        return                  # an unknown or unreadable problem: [problem] names it
    if kind not in FILE_KINDS:
        return                  # a wing or family file: its records or models give these
    own = table if changed is None else changed

    def given(key):
        return _given(own, key)

    taken = {k: v for k, v in problem_route_settings(name).items() if not given(k)}
    missing = [k for k in _PROBLEM_UNIT_KEYS if not given(k) and k not in taken]
    if missing:
        data, flutter = DataSection(), FlutterSection()
        defaults = {"data.V0": data.V0, "data.dt": data.dt, "data.duration": data.duration,
                    "data.band": list(data.band), "flutter.V_range": list(flutter.V_range),
                    "data.coupling_delay": data.coupling_delay}
        for key in defaults:            # the values the run would take: the file's, if any
            section, field_name = key.split(".")
            if _given(table, key):
                defaults[key] = table[section][field_name]
        seed = ", ".join(f"{k} = {defaults[k]!r}" for k in missing)
        rom = [k for k, v in _ROUTE_KEYS.items() if v in missing]
        whose = ("the seed wing's" if changed is None else
                 f"those of {file_problem}, for which the configuration file was written")
        raise ConfigError(
            f"problem {name} is a {kind} file in its own units, and the run's values of "
            f"{', '.join(missing)} are {whose} ({seed}): set "
            f"{', '.join(missing)} in the run configuration"
            + (f" (or give {name} a [rom] table with {', '.join(rom)}: the settings of "
               f"casflutter flutter {name}, which the run then takes)" if rom else "")
            + ("; data.coupling_delay is 0 for a simulator's records (as casflutter flutter "
               "takes them), 1 for the paper's loosely coupled CFD march, which the HWL "
               "orders' input delay r = 1 (Table I) expects"
               if "data.coupling_delay" in missing else ""))
    for key, value in taken.items():
        set_dotted(table, RunConfig, key, value)
    if taken:
        logging.getLogger("casflutter.pipeline").info(
            "from the [rom] table of %s (%s): %s", name,
            "not set in the run configuration" if changed is None else
            f"the configuration file's values are {file_problem}'s",
            ", ".join(f"{k} = {v!r}" for k, v in taken.items()))
