"""Settings and frozen results of the periodic-orbit continuation."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from .._format import result_repr
from ..errors import ConfigError

__all__ = ["LCOSettings", "LCOPoint", "Fold", "HopfClassification", "SettledMotion",
           "LCOBranch", "SUPERCRITICAL", "SUBCRITICAL"]

SUPERCRITICAL = "supercritical"
SUBCRITICAL = "subcritical"
_SENSOR_KINDS = ("displacement", "acceleration")


@dataclass(frozen=True)
class LCOSettings:
    """Numerical settings of the LCO branch computation.

    Every field is checked on construction; a bad value raises
    :class:`~casflutter.errors.ConfigError` naming the field and what is allowed.
    """

    #: mesh intervals of the orthogonal collocation of one period (continuous systems)
    n_intervals: int = 20
    #: Gauss--Legendre collocation points per interval (polynomial degree)
    degree: int = 4
    #: Fourier harmonics of the invariant circle (sampled-data ROM loop)
    harmonics: int = 8
    #: most branch points computed (the Hopf start included)
    max_points: int = 120
    #: first pseudo-arclength step (in the scaled norm of the branch: relative speed change
    #: plus amplitude in units of the reference amplitude)
    ds: float = 0.02
    #: smallest step before the continuation is declared failed
    ds_min: float = 1e-5
    #: largest step
    ds_max: float = 0.5
    #: largest relative speed change per step, ``|dV| / V_Hopf``
    max_dV: float = 0.02
    #: Newton tolerance on the scaled residual
    tol: float = 1e-9
    #: Newton iterations per corrector
    max_newton: int = 15
    #: relative speed offset of the first branch point from the Hopf point
    #: (the amplitude follows from the first Lyapunov coefficient)
    start_offset: float = 1e-3
    #: stop when an output amplitude exceeds this (None: no limit)
    max_amplitude: float | None = None
    #: the sensors' reading: modal displacements through the sensor rows, or accelerations
    sensor_kind: str = "displacement"
    #: bisection/secant steps to locate a fold
    fold_iterations: int = 12
    #: speed grid of the Hopf search
    n_grid: int = 121

    def __post_init__(self):
        def need(cond, name, allowed):
            if not cond:
                raise ConfigError(f"LCOSettings.{name} = {getattr(self, name)!r} is not allowed: "
                                  f"{allowed}")

        for name, lo in (("n_intervals", 4), ("degree", 1), ("harmonics", 2), ("max_points", 2),
                         ("max_newton", 2), ("fold_iterations", 0), ("n_grid", 5)):
            v = getattr(self, name)
            need(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= lo, name,
                 f"an integer >= {lo}")
        need(self.degree <= 8, "degree", "at most 8")
        for name in ("ds", "ds_min", "ds_max", "max_dV", "tol", "start_offset"):
            v = getattr(self, name)
            need(isinstance(v, (int, float)) and math.isfinite(v) and v > 0, name,
                 "a positive finite number")
        need(self.ds_min <= self.ds <= self.ds_max, "ds", "ds_min <= ds <= ds_max")
        need(self.start_offset < 0.1, "start_offset", "below 0.1 (a small offset from Hopf)")
        need(self.max_amplitude is None or (math.isfinite(self.max_amplitude)
                                            and self.max_amplitude > 0),
             "max_amplitude", "None or a positive number")
        need(self.sensor_kind in _SENSOR_KINDS, "sensor_kind", f"one of {_SENSOR_KINDS}")

    @classmethod
    def from_mapping(cls, values: dict) -> "LCOSettings":
        """Settings from a mapping (unknown keys raise ConfigError listing the valid ones).

        Parameters
        ----------
        values : mapping
            Field values by name (e.g. a configuration's ``[lco]`` table).

        Returns
        -------
        LCOSettings
        """
        valid = [f.name for f in fields(cls)]
        unknown = [k for k in values if k not in valid]
        if unknown:
            raise ConfigError(f"unknown LCO setting(s) {', '.join(map(repr, unknown))}; valid: "
                              f"{', '.join(valid)}")
        return cls(**values)


@dataclass(frozen=True)
class LCOPoint:
    """One periodic orbit (or invariant circle) of the branch.

    Attributes
    ----------
    V : float
        Speed index.
    period : float
        Period [time unit of the problem].
    freq_hz : float
        ``1 / period`` (cycles per time unit: Hz when the time unit is seconds).
    amplitude : dict
        Output name -> amplitude of the oscillation about its mean (half the peak-to-peak
        swing over one period), per mode and per sensor.
    mean : dict
        Output name -> mean over the period (non-zero with even nonlinearities).
    multipliers : numpy.ndarray
        Floquet multipliers (continuous systems; the trivial one included) or, for the
        sampled-data loop, the normal radii raised to the samples per period (the
        multipliers of one period).
    max_multiplier : float
        Largest modulus among the nontrivial multipliers.
    stable : bool
        ``max_multiplier < 1``.
    trivial_error : float
        ``|mu_trivial - 1|``: the accuracy of the computed multipliers.
    state : numpy.ndarray
        A state on the orbit (phase zero): the initial state of a simulation that starts
        on the LCO (the truth's ``[u, u', lags]``; the ROM loop's map state).
    """

    __repr__ = result_repr

    V: float
    period: float
    freq_hz: float
    amplitude: dict
    mean: dict
    multipliers: np.ndarray = field(repr=False)
    max_multiplier: float
    stable: bool
    trivial_error: float
    state: np.ndarray = field(default=None, repr=False)

    def to_dict(self, speed=float) -> dict:
        """``{"V", "freq_hz", "amplitude", "stable"}`` with the speed converted by ``speed``."""
        return {"V": float(speed(self.V)), "freq_hz": float(self.freq_hz),
                "amplitude": {k: float(v) for k, v in self.amplitude.items()},
                "stable": bool(self.stable), "max_multiplier": float(self.max_multiplier)}


@dataclass(frozen=True)
class Fold:
    """A fold (saddle-node) of cycles: the branch turns back in ``V``.

    Attributes
    ----------
    V : float
        Speed index of the fold.
    amplitude : dict
        Output amplitudes there.
    index : int
        The fold lies between branch points ``index`` and ``index + 1``.
    located : bool
        Whether the secant iteration brought the speed component of the branch tangent to
        zero (``tangent_V`` below 1e-6); otherwise the fold is the better of the bracketing
        points.
    tangent_V : float
        The speed component of the unit branch tangent at the reported point.
    max_multiplier : float
        The largest nontrivial multiplier modulus there (1 at an exact fold).
    """

    __repr__ = result_repr

    V: float
    amplitude: dict
    index: int
    located: bool
    tangent_V: float
    max_multiplier: float

    def to_dict(self, speed=float) -> dict:
        return {"V": float(speed(self.V)),
                "amplitude": {k: float(v) for k, v in self.amplitude.items()}}


@dataclass(frozen=True)
class HopfClassification:
    """The Hopf (continuous) or Neimark--Sacker (sampled-data) point and its criticality.

    Attributes
    ----------
    V : float
        Speed index where the critical pair crosses the imaginary axis (unit circle).
    omega : float
        Angular frequency of the critical pair [rad per time unit].
    freq_hz : float
        ``omega / 2 pi``.
    lyapunov : float
        First Lyapunov coefficient: ``l1`` (Kuznetsov 2004, eq. 3.20) for a flow, ``d``
        (Kuznetsov §4.7/5.4) for a map; negative means supercritical.  It is evaluated with
        the critical eigenvector normalised to ``<q, q> = 1``.
    crossing_rate : float
        ``d Re(lambda) / dV`` (flow) or ``d |mu| / dV`` (map) of the critical pair.
    kind : str
        ``"supercritical"`` or ``"subcritical"`` from the sign of ``lyapunov``.
    branch_direction : int
        ``+1`` if the computed branch leaves the Hopf point towards larger ``V``, ``-1``
        towards smaller.
    kind_from_branch : str
        The classification the branch direction implies (a supercritical branch lies on the
        side where the equilibrium is unstable).
    consistent : bool
        ``kind == kind_from_branch``.
    predicted_dV : float
        Speed offset of the first branch point predicted by the normal form,
        ``-omega l1 r^2 / crossing_rate`` (map: ``-d r^2 / crossing_rate``).
    computed_dV : float
        The offset the collocation found for the same amplitude.
    eigenvector : numpy.ndarray
        The critical right eigenvector ``q``.
    discrete : bool
        True for the sampled-data map (Neimark--Sacker).
    """

    __repr__ = result_repr

    V: float
    omega: float
    freq_hz: float
    lyapunov: float
    crossing_rate: float
    kind: str
    branch_direction: int
    kind_from_branch: str
    consistent: bool
    predicted_dV: float
    computed_dV: float
    eigenvector: np.ndarray = field(repr=False)
    discrete: bool = False

    @property
    def normal_form_agreement(self) -> float:
        """``computed_dV / predicted_dV`` (1 at small amplitude when ``lyapunov`` is right)."""
        return float(self.computed_dV / self.predicted_dV) if self.predicted_dV else float("nan")


@dataclass(frozen=True)
class SettledMotion:
    """What the motion does just above a subcritical Hopf point whose branch has no stable
    cycle: one simulation there, and the branch of the cycle it settles on, if any.

    The continuation follows only the branch through the Hopf point.  A stable limit cycle
    that is not connected to it within the range (lightly damped sections with a polynomial
    spring have one) would be missed, and "subcritical, no stable cycle" would read as "the
    motion grows without bound".  So the equilibrium, unstable there, is simulated from the
    first orbit of the branch; a cycle it settles on is solved by collocation at that speed
    and continued both ways.

    Attributes
    ----------
    V : float
        Speed index of the simulation.
    kind : str
        ``"lco"`` (settles on a cycle), ``"divergence"`` (grows without bound, or past
        ``max_amplitude``) or ``"decay"`` (returns to the equilibrium; not expected above
        flutter).
    duration : float
        Simulated time (the truth's time unit).
    freq_hz : float
        Frequency of the settled cycle (NaN unless ``kind == "lco"``).
    amplitude : dict
        Output amplitudes of the settled cycle in the simulation (half peak-to-peak).
    points : tuple of LCOPoint
        The branch through the settled cycle, ordered along the branch (empty when there is
        no cycle or its collocation did not converge).
    folds : tuple of Fold
        Folds of that branch.
    note : str
        What was found, in words (for the report).
    """

    __repr__ = result_repr

    V: float
    kind: str
    duration: float
    freq_hz: float
    amplitude: dict
    points: tuple = ()
    folds: tuple = ()
    note: str = ""

    def to_dict(self, speed=float) -> dict:
        """``V``, ``kind``, ``freq_hz``, ``amplitude``, ``branch``, ``folds``, ``note``."""
        return {"V": float(speed(self.V)), "kind": self.kind,
                "freq_hz": None if not math.isfinite(self.freq_hz) else float(self.freq_hz),
                "amplitude": {k: float(v) for k, v in self.amplitude.items()},
                "branch": [p.to_dict(speed) for p in self.points],
                "folds": [f.to_dict(speed) for f in self.folds], "note": self.note}


@dataclass(frozen=True)
class LCOBranch:
    """A branch of periodic orbits continued in the speed from a Hopf point.

    Attributes
    ----------
    problem : str
        Problem label.
    system : str
        ``"truth"`` (continuous vector field) or ``"rom_loop"`` (sampled-data map).
    hopf : HopfClassification
    points : tuple of LCOPoint
        Along the branch, starting next to the Hopf point.
    folds : tuple of Fold
    outputs : tuple of str
        Output names (keys of every ``amplitude``).
    output_units : tuple of str
        Their units ("" where the modal coordinates have none).
    speed_unit : str
        Unit of :meth:`speed` (the problem's speed: m/s, or the speed index).
    speed_scale : float
        Problem speed per speed index (``speed(V) = speed_scale V``).
    time_unit : str
        Time unit of the period (``freq_hz`` is per this unit).
    completed : bool
        True when the branch ended normally (speed range, amplitude limit or point budget);
        False when the continuation failed (the last converged point is kept).
    stop_reason : str
        Why the continuation stopped, with the speed where it did.
    vrange : tuple of float
        Speed-index range of the computation.
    timings : dict
        Wall seconds: ``hopf``, ``branch``, ``total``.
    settled : SettledMotion or None
        For a subcritical point whose branch has no stable cycle (continuous systems): what
        a simulation just above the Hopf point settles on, and that cycle's own branch.
    """

    __repr__ = result_repr

    problem: str
    system: str
    hopf: HopfClassification
    points: tuple
    folds: tuple
    outputs: tuple
    output_units: tuple
    speed_unit: str
    speed_scale: float
    time_unit: str
    completed: bool
    stop_reason: str
    vrange: tuple
    timings: dict = field(default_factory=dict)
    settled: SettledMotion | None = None

    @property
    def kind(self) -> str:
        """``"supercritical"`` or ``"subcritical"`` (the first Lyapunov coefficient's)."""
        return self.hopf.kind

    def speed(self, V):
        """Speed index -> the problem's speed unit.

        Parameters
        ----------
        V : float or array_like
            Speed index.

        Returns
        -------
        float or ndarray
            ``V`` times :attr:`speed_scale`, in :attr:`speed_unit`.
        """
        return self.speed_scale * np.asarray(V, float) if np.ndim(V) else self.speed_scale * float(V)

    @property
    def V(self) -> np.ndarray:
        """Speed indices of the branch points."""
        return np.array([p.V for p in self.points])

    @property
    def stable(self) -> np.ndarray:
        """Stability of the branch points."""
        return np.array([p.stable for p in self.points], dtype=bool)

    @property
    def freq_hz(self) -> np.ndarray:
        """Frequencies of the branch points."""
        return np.array([p.freq_hz for p in self.points])

    def amplitude(self, name: str) -> np.ndarray:
        """Amplitudes of output ``name`` along the branch.

        Parameters
        ----------
        name : str
            An output name (of :attr:`outputs`).

        Returns
        -------
        ndarray
            Peak amplitude at each branch point, in :meth:`unit_of` ``name``.
        """
        if name not in self.outputs:
            raise ConfigError(f"unknown output {name!r}; outputs: {', '.join(self.outputs)}")
        return np.array([p.amplitude[name] for p in self.points])

    def unit_of(self, name: str) -> str:
        """Unit of output ``name``.

        Parameters
        ----------
        name : str
            An output name.

        Returns
        -------
        str
        """
        return self.output_units[self.outputs.index(name)]

    def to_dict(self) -> dict:
        """The JSON document of ``casflutter lco`` (speeds in the problem's unit).

        Returns
        -------
        dict
            ``problem``, ``hopf``, ``kind``, ``branch``, ``folds``, the units and
            ``settled`` (:class:`SettledMotion`, or None).
        """
        h = self.hopf
        return {
            "problem": self.problem,
            "system": self.system,
            "hopf": {"V": float(self.speed(h.V)), "freq_hz": float(h.freq_hz),
                     "lyapunov_coefficient": float(h.lyapunov),
                     "crossing_rate": float(h.crossing_rate / self.speed_scale),
                     "branch_direction": int(h.branch_direction),
                     "kind_from_branch": h.kind_from_branch,
                     "consistent": bool(h.consistent),
                     "normal_form_agreement": h.normal_form_agreement},
            "kind": h.kind,
            "branch": [p.to_dict(self.speed) for p in self.points],
            "folds": [f.to_dict(self.speed) for f in self.folds],
            "units": {"V": self.speed_unit, "freq_hz": f"1/{self.time_unit}" if
                      self.time_unit != "s" else "Hz",
                      "amplitude": {n: u for n, u in zip(self.outputs, self.output_units)}},
            "completed": bool(self.completed),
            "stop_reason": self.stop_reason,
            "vrange": [float(self.speed(v)) for v in self.vrange],
            "timings": {k: float(v) for k, v in self.timings.items()},
            "settled": None if self.settled is None else self.settled.to_dict(self.speed),
        }
