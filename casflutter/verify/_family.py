"""Verification of one controller on a plant family over a speed range.

:func:`verify_family` answers the two questions an engineer asks of a flutter-suppression
controller, on any :class:`casflutter.aeroelastic.PlantFamily` (the paper's loop ΣAE(V),
eq. 8-9, a truth's linearisation, a grid of state-space models from a file):

* the **absolute flutter speed**: the lowest speed above the range's start at which the
  closed loop loses stability, from the *certified* stable interval
  (:func:`casflutter.verify._family_interval.certified_interval`: eigenvalue-inclusion
  chains and guardian maps on the family's polynomial pieces, never a grid scan);
* the **robust flutter speed**: the lowest speed at which a stability margin falls below its
  threshold (6 dB / 45° by default): the classical loop-at-a-time gain and phase margins at
  the plant inputs and at the plant outputs, each loop broken while the others stay closed
  (:mod:`casflutter.verify._margins`), and optionally the multi-loop disk margin.  The
  margins are computed at a list of speeds (the family's grid speeds by default), and the
  first violation is located by bisection between the last speed that meets the thresholds
  and the first that does not; a dip of a margin between two listed speeds that comes back
  above the threshold at both is not seen (list more speeds to look closer).  The robust
  flutter speed is never above the absolute one.

It also lists every crossing of the imaginary axis by the closed loop's eigenvalues in the
range (where the number of unstable closed-loop eigenvalues changes, located by bisection)
and keeps the closed-loop eigenvalues along the range for the damping-versus-speed figure.  Shares no code with :mod:`casflutter.design`.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ._common import spectral_abscissa, ssdata
from ._family_controller import FamilyController, match_controller
from ._family_interval import CertifiedInterval, _ClosedLoop, certified_interval
from ._margins import MarginTable, disk_margin, loop_margins, margin_table

__all__ = ["ClosedLoopCrossing", "FamilyVerification", "verify_family"]

_log = logging.getLogger(__name__)

#: margin speeds when the family has no grid of its own
_N_MARGIN_SPEEDS = 41
#: relative width to which the robust flutter speed is located between margin speeds
_ROBUST_TOL = 1e-7
#: tracking points per interval between margin speeds (for the closed-loop crossings)
_TRACK_PER_INTERVAL = 4


@dataclass(frozen=True)
class ClosedLoopCrossing:
    """One crossing of the imaginary axis by a closed-loop eigenvalue.

    Attributes
    ----------
    speed : float
        Speed (family's unit).
    omega : float
        Frequency ``|Im λ|`` (rad per time unit; 0 for a real eigenvalue).
    direction : str
        ``"destabilizing"`` or ``"stabilizing"`` as the speed increases.
    kind : str
        ``"flutter"`` (complex pair) or ``"divergence"`` (real eigenvalue).
    """

    __repr__ = result_repr

    speed: float
    omega: float
    direction: str
    kind: str


@dataclass(frozen=True)
class FamilyVerification:
    """What :func:`verify_family` found (module docstring).

    Attributes
    ----------
    family : str
        The family's name.
    speed_unit, time_unit : str
        Units of speed and time (frequencies are in rad per time unit).
    speed_range : tuple of float
        The range verified.
    controller : FamilyController
        The controller and the signals it was matched to.
    interval : CertifiedInterval
        The certified stable interval from the range's start (with its certificate).
    absolute_flutter_speed : float or None
        The lowest speed above the range's start at which the closed loop is not stable
        (the range's start when it is not stable just above it); ``None`` when it holds the
        whole range.
    absolute_flutter_omega : float or None
        Frequency of the eigenvalue crossing there.
    robust_flutter_speed : float or None
        The lowest speed at which a margin falls below its threshold (or the loop is not
        stable); ``None`` when every margin holds over the whole range at the margin
        speeds.
    robust_reason : str
        Which margin of which loop fails there.
    gain_margin_db, phase_margin_deg : float
        The thresholds.
    disk : bool
        Whether the multi-loop disk margins were computed and held to the thresholds.
    inputs, outputs : MarginTable
        Loop-at-a-time margins at the plant inputs (controls) and outputs (measurements).
    crossings : tuple of ClosedLoopCrossing
        Every closed-loop crossing in the range, lowest speed first.
    branch_speeds : ndarray
        Speeds at which the closed-loop eigenvalues were computed.
    branch_eigenvalues : ndarray, shape (speeds, n)
        The closed-loop eigenvalues there, by increasing frequency (the damping figure).
    wall_time : dict
        Seconds per stage: ``interval``, ``margins``, ``crossings``, ``total``.
    """

    __repr__ = result_repr

    family: str
    speed_unit: str
    time_unit: str
    speed_range: tuple
    controller: FamilyController
    interval: CertifiedInterval
    absolute_flutter_speed: float | None
    absolute_flutter_omega: float | None
    robust_flutter_speed: float | None
    robust_reason: str
    gain_margin_db: float
    phase_margin_deg: float
    disk: bool
    inputs: MarginTable
    outputs: MarginTable
    crossings: tuple
    branch_speeds: np.ndarray
    branch_eigenvalues: np.ndarray
    wall_time: dict

    @property
    def stable_interval(self) -> tuple | None:
        """``(lower, upper)`` of the certified interval, or None."""
        iv = self.interval
        return None if iv.lower is None else (iv.lower, iv.upper)

    def covers(self, lo: float, hi: float) -> bool:
        """True when the certified interval covers ``[lo, hi]``.

        Parameters
        ----------
        lo, hi : float
            The ends of the speed range asked about, in :attr:`speed_unit`.

        Returns
        -------
        bool
        """
        return self.interval.covers(lo, hi)

    def robust_over(self, lo: float, hi: float) -> bool:
        """True when the certified interval covers ``[lo, hi]`` and every margin holds its
        threshold from the start of the verified range up to ``hi`` (the robust flutter
        speed, the first violation located between the margin speeds, lies above ``hi``):
        a loop without margins just below ``lo`` is not called robust.

        Parameters
        ----------
        lo, hi : float
            As :meth:`covers`.

        Returns
        -------
        bool
        """
        return bool(self.covers(lo, hi) and (self.robust_flutter_speed is None
                                              or self.robust_flutter_speed > hi))

    def to_dict(self) -> dict:
        """A JSON-ready dict (non-finite numbers stay floats; ``print_json`` writes null).

        Returns
        -------
        dict
        """
        iv, fc = self.interval, self.controller
        f_unit = f"rad/{self.time_unit}"
        return {
            "family": self.family, "speed_unit": self.speed_unit,
            "frequency_unit": f_unit, "speed_range": list(self.speed_range),
            "controller": {"order": int(fc.K.nstates), "controls": list(fc.controls),
                           "measurements": list(fc.measurements), "feedback": fc.feedback,
                           "notes": list(fc.notes)},
            "stable_interval": None if iv.lower is None else {
                "lower": iv.lower, "upper": iv.upper,
                "lower_included": iv.stable_at_start, "upper_included": iv.holds_range,
                "certificate": [{"lower": p.lower, "upper": p.upper, "method": p.method,
                                 "certified_to": p.certified_to, "steps": p.steps,
                                 "pencil_order": p.pencil_order} for p in iv.pieces]},
            "absolute_flutter_speed": self.absolute_flutter_speed,
            "absolute_flutter_omega": self.absolute_flutter_omega,
            "absolute_flutter_crossing": iv.crossing,
            "robust_flutter_speed": self.robust_flutter_speed,
            "robust_flutter_reason": self.robust_reason,
            "thresholds": {"gain_margin_db": self.gain_margin_db,
                           "phase_margin_deg": self.phase_margin_deg, "disk": self.disk},
            "margins": {"input": self.inputs.to_dict(), "output": self.outputs.to_dict()},
            "crossings": [{"speed": c.speed, "omega": c.omega,
                           "freq_hz": c.omega / (2 * math.pi), "direction": c.direction,
                           "kind": c.kind} for c in self.crossings],
            "wall_time": dict(self.wall_time)}

    def format(self) -> str:
        """A few lines for a terminal.

        Returns
        -------
        str
        """
        u, iv, fc = self.speed_unit, self.interval, self.controller
        f_unit = f"rad/{self.time_unit}"
        lines = [f"{self.family}: controller of order {fc.K.nstates}, {fc.feedback} feedback, "
                 f"controls {list(fc.controls)}, measurements {list(fc.measurements)}"]
        lines += [f"  note: {n}" for n in fc.notes]
        lines.append(f"  speed range [{self.speed_range[0]:.6g}, {self.speed_range[1]:.6g}] {u}")
        if iv.lower is None:
            lines.append("  stable_interval: none (the closed loop is not stable just above "
                         "the range's start)")
        else:
            lb = "[" if iv.stable_at_start else "("
            rb = "]" if iv.holds_range else ")"
            methods = sorted({p.method for p in iv.pieces})
            lines.append(f"  stable_interval: {lb}{iv.lower:.8g}, {iv.upper:.8g}{rb} {u} "
                         f"(certified: {', '.join(methods)}, {len(iv.pieces)} pieces)")
        if self.absolute_flutter_speed is None:
            lines.append("  absolute_flutter_speed: none in the range")
        else:
            lines.append(f"  absolute_flutter_speed: {self.absolute_flutter_speed:.8g} {u} "
                         f"({iv.crossing}, {self.absolute_flutter_omega:.6g} {f_unit})")
        thr = f"{self.gain_margin_db:g} dB / {self.phase_margin_deg:g} deg"
        if self.robust_flutter_speed is None:
            lines.append(f"  robust_flutter_speed: none in the range ({thr} held)")
        elif self.robust_flutter_speed <= self.speed_range[0]:
            lines.append(f"  robust_flutter_speed: {self.robust_flutter_speed:.6g} {u}, the "
                         f"range's start: the margins ({thr}) fail already there "
                         f"({self.robust_reason})")
        else:
            lines.append(f"  robust_flutter_speed: {self.robust_flutter_speed:.6g} {u} "
                         f"({thr}: {self.robust_reason})")
        for t in (self.inputs, self.outputs):
            ok = t.stable
            if not ok.any():
                continue
            worst_g = np.nanmin(np.where(ok[:, None], t.gain_db, np.nan), axis=0)
            worst_p = np.nanmin(np.where(ok[:, None], t.phase_deg, np.nan), axis=0)
            parts = [f"{name} {g:.3g} dB/{p:.3g} deg" for name, g, p in
                     zip(t.loops, worst_g, worst_p)]
            lines.append(f"  smallest {t.side} margins (stable speeds): " + ", ".join(parts))
        if self.crossings:
            lines.append("  closed-loop crossings: " + "; ".join(
                f"{c.speed:.8g} {u} at {c.omega:.6g} {f_unit} ({c.direction})"
                for c in self.crossings))
        else:
            lines.append("  closed-loop crossings: none in the range")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.format()


def _margin_speeds(family, lo: float, hi: float, speeds) -> np.ndarray:
    if speeds is None:
        inner = [b for b in family.breakpoints if lo < b < hi]
        if inner:
            return np.unique(np.concatenate([[lo], inner, [hi]]))
        return family.speed_grid(_N_MARGIN_SPEEDS, lo, hi)
    if isinstance(speeds, (int, np.integer)) and not isinstance(speeds, bool):
        return family.speed_grid(int(speeds), lo, hi)
    try:
        v = np.unique(np.asarray(speeds, dtype=float).ravel())
    except (TypeError, ValueError):
        raise ConfigError(f"margin_speeds = {speeds!r}: give a number of speeds or a list "
                          "of speeds") from None
    if v.size == 0 or not np.all(np.isfinite(v)) or v[0] < lo or v[-1] > hi:
        raise ConfigError(f"margin_speeds must be finite speeds inside [{lo:g}, {hi:g}]; "
                          f"got {v.tolist()[:6]}")
    return v


class _Margins:
    """Margins at one speed, for the bisection of the robust flutter speed."""

    def __init__(self, family, fc: FamilyController, gm_db: float, pm_deg: float, disk: bool):
        self.family, self.fc, self.gm, self.pm, self.disk = family, fc, gm_db, pm_deg, disk
        self.loop = _ClosedLoop(family, fc.K, fc.controls, fc.measurements, fc.sign)

    def stable(self, P) -> bool:
        At = self.loop.matrix(*ssdata(P))
        return At is not None and spectral_abscissa(At) < 0

    def at(self, V: float, only=None) -> dict:
        """``{"stable", side: {loop: LoopMargins}, "disk_" + side: (α, dB, deg)}`` at V, for
        every loop or for the ``(side, loop)`` pairs of ``only``."""
        P = self.family.control_plant(V, self.fc.controls, self.fc.measurements)
        out = {"stable": self.stable(P)}
        if not out["stable"]:
            return out
        names = {"input": self.fc.controls, "output": self.fc.measurements}
        for side in ("input", "output"):
            want = [j for j, name in enumerate(names[side])
                    if only is None or (side, name) in only]
            if want:
                lms = loop_margins(P, self.fc.K, self.fc.sign, side, want)
                out[side] = {names[side][j]: lm for j, lm in zip(want, lms)}
            if self.disk and (only is None or (side, "disk") in only):
                out["disk_" + side] = disk_margin(P, self.fc.K, self.fc.sign, side)
        return out

    def failures(self, m: dict) -> list[tuple]:
        """``(side, loop, what, value, threshold)`` for each threshold the margins ``m`` fail
        (empty when they hold); ``what`` is ``"gain"`` (dB), ``"phase"`` (deg), ``"disk"``
        or ``"stability"``."""
        if not m["stable"]:
            return [("", "", "stability", math.nan, math.nan)]
        out = []
        for side in ("input", "output"):
            for name, lm in m.get(side, {}).items():
                if lm.gain_db < self.gm:
                    out.append((side, name, "gain", lm.gain_db, self.gm))
                if lm.phase < self.pm:
                    out.append((side, name, "phase", lm.phase, self.pm))
            if "disk_" + side in m:
                _, dgm, dpm = m["disk_" + side]
                if dgm < self.gm or dpm < self.pm:
                    out.append((side, "disk", "disk", (dgm, dpm), (self.gm, self.pm)))
        return out


def _why(fails: list, located: bool) -> str:
    """One sentence per failing threshold (``located``: at a speed found by bisection, where
    the margin has just crossed its threshold)."""
    units = {"gain": "dB", "phase": "deg"}
    out = []
    for side, name, what, value, thr in fails:
        if what == "stability":
            out.append("the closed loop is not stable")
        elif what == "disk":
            out.append(f"{side} disk margin {value[0]:.3g} dB / {value[1]:.3g} deg "
                       f"{'falls' if located else 'is'} below {thr[0]:g} dB / {thr[1]:g} deg")
        elif located:
            out.append(f"{side} {name!r}: {what} margin falls below {thr:g} {units[what]}")
        else:
            out.append(f"{side} {name!r}: {what} margin {value:.3g} {units[what]} < "
                       f"{thr:g} {units[what]}")
    return "; ".join(out)


def verify_family(family, controller, *, speed_range=None, margins=(6.0, 45.0),
                  disk: bool = False, margin_speeds=None, feedback: str | None = None,
                  degree: int | None = None, method: str = "auto",
                  xtol: float = 1e-9) -> FamilyVerification:
    """Certified stable interval, absolute and robust flutter speeds of a controller on a
    plant family (module docstring).

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The plant family (a loop family such as :class:`casflutter.aeroelastic.TruthLoop`,
        a :class:`casflutter.aeroelastic.GriddedFamily`, ...).
    controller : dict, str, path-like, control.StateSpace or FamilyController
        The controller, matched to the family's measurements and controls by name
        (:func:`casflutter.verify.match_controller`).
    speed_range : (float, float), optional
        The range to verify (default the family's; needed when that is unbounded).
    margins : (float, float)
        Gain-margin (dB) and phase-margin (degrees) thresholds of the robust flutter speed.
    disk : bool
        Also compute the multi-loop disk margins at both sides and hold their disk-based
        gain and phase margins to the same thresholds (slower: a μ bound at every frequency
        of a grid).
    margin_speeds : int or sequence of float, optional
        The speeds of the margin tables: a number of evenly spaced speeds, or a list inside
        the range (default: the family's grid speeds, i.e. its breakpoints and the range's
        ends, or 41 evenly spaced speeds).
    feedback : {"positive", "negative"}, optional
        The convention ``u = ±K y``, overriding the controller file's and the family's.
    degree : int, optional
        Degree in V of the family's matrices between breakpoints (default
        ``family.speed_degree``).
    method : {"auto", "guardian"}
        The certificate (:func:`casflutter.verify._family_interval.certified_interval`).
    xtol : float
        Fraction of a piece to which the end of the certified interval is located.

    Returns
    -------
    FamilyVerification

    Raises
    ------
    ConfigError
        An unbounded range without ``speed_range``, a range outside the family's, bad
        thresholds or margin speeds, a controller that does not match (names, sizes,
        discrete time, feedback), or a family without a known degree in V.
    """
    t_all = time.perf_counter()
    fc = match_controller(family, controller, feedback=feedback)
    rng = family.speed_range if speed_range is None else speed_range
    try:
        lo, hi = (float(v) for v in rng)
    except (TypeError, ValueError):
        raise ConfigError(f"speed_range = {speed_range!r}: give (lo, hi)") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ConfigError(f"{family.name}: the speed range [{lo:g}, {hi:g}] {family.speed_unit} "
                          "is not a finite interval; pass speed_range=(lo, hi)")
    lo, hi = family.check_speed(lo, "lo"), family.check_speed(hi, "hi")
    try:
        gm_db, pm_deg = (float(x) for x in margins)
    except (TypeError, ValueError):
        raise ConfigError(f"margins = {margins!r}: give (gain margin dB, phase margin deg)") \
            from None
    if not (0 <= gm_db < math.inf and 0 <= pm_deg <= 180):
        raise ConfigError(f"margins = {margins!r}: a gain margin >= 0 dB and a phase margin "
                          "in [0, 180] degrees")
    speeds = _margin_speeds(family, lo, hi, margin_speeds)
    if (family.speed_degree if degree is None else degree) is None:
        raise ConfigError(f"{family.name}: speed_degree is None: a certificate needs the "
                          "family's matrices to be polynomials in V between breakpoints; "
                          "pass degree=D when they are")

    t0 = time.perf_counter()
    interval = certified_interval(family, fc.K, fc.controls, fc.measurements, fc.sign,
                                  (lo, hi), degree=degree, method=method, xtol=xtol)
    t_interval = time.perf_counter() - t0

    t0 = time.perf_counter()
    mm = _Margins(family, fc, gm_db, pm_deg, disk)
    # where the certificate found the start not stable (a loop family's V = 0, where a truth
    # is not even defined) the margins are not evaluated there
    skip_start = not interval.stable_at_start
    table = [{"stable": False, "skipped": True} if skip_start and V == lo else mm.at(float(V))
             for V in speeds]
    robust, reason = _robust(mm, speeds, table)
    if interval.loss is not None and (robust is None or interval.loss < robust):
        robust, reason = interval.loss, "the closed loop loses stability (absolute flutter)"
    if interval.lower is None:
        robust, reason = lo, "the closed loop is not stable at the range's start"
    stable = [m["stable"] for m in table]
    names = {"input": fc.controls, "output": fc.measurements}
    tables = {side: margin_table(side, names[side], speeds, stable,
                                 [[m[side][n] for n in names[side]] if side in m else None
                                  for m in table],
                                 [m.get("disk_" + side) for m in table] if disk else None)
              for side in ("input", "output")}
    t_margins = time.perf_counter() - t0

    t0 = time.perf_counter()
    crossings, b_speeds, b_eigs = _crossings(mm.loop, speeds, skip_start)
    t_cross = time.perf_counter() - t0
    absolute = interval.loss if interval.lower is not None else lo
    return FamilyVerification(
        family=family.name, speed_unit=family.speed_unit, time_unit=family.time_unit,
        speed_range=(lo, hi), controller=fc, interval=interval,
        absolute_flutter_speed=absolute,
        absolute_flutter_omega=None if absolute is None else interval.omega,
        robust_flutter_speed=robust, robust_reason=reason, gain_margin_db=gm_db,
        phase_margin_deg=pm_deg, disk=bool(disk), inputs=tables["input"],
        outputs=tables["output"], crossings=crossings, branch_speeds=b_speeds,
        branch_eigenvalues=b_eigs,
        wall_time={"interval": t_interval, "margins": t_margins, "crossings": t_cross,
                   "total": time.perf_counter() - t_all})


def _robust(mm: _Margins, speeds: np.ndarray, table: list):
    """The lowest speed at which a margin fails, and why: the first failing margin speed,
    then bisection from the speed before it on the loops that fail there (all loops when the
    loop is unstable there).  A marginally stable start that was not evaluated counts as
    neither failing nor holding: the bisection then starts from it."""
    fails = [[] if m.get("skipped") else mm.failures(m) for m in table]
    k = next((i for i, f in enumerate(fails) if f), None)
    if k is None:
        return None, "every margin holds its threshold"
    if k == 0:
        return float(speeds[0]), _why(fails[0], located=False)
    a, b = float(speeds[k - 1]), float(speeds[k])
    only = {(f[0], f[1]) for f in fails[k]} if table[k]["stable"] else None
    why = fails[k]
    for _ in range(60):
        mid = 0.5 * (a + b)
        if b - a <= _ROBUST_TOL * max(1.0, abs(b)) or mid in (a, b):
            break
        f = mm.failures(mm.at(mid, only))
        if f:
            b, why = mid, f
        else:
            a = mid
    return b, _why(why, located=True)


def _crossings(loop: _ClosedLoop, speeds: np.ndarray, skip_start: bool):
    """Closed-loop crossings in the range, and the eigenvalues on the tracking grid.

    The number of closed-loop eigenvalues in the right half-plane is counted on the margin
    speeds and :data:`_TRACK_PER_INTERVAL` points between each two; where it changes, the
    change is located by bisection to rounding, and the eigenvalue nearest the imaginary axis
    there gives the frequency.  Two crossings that cancel inside one grid interval (a mode
    that goes unstable and back, or one that stabilises as another destabilises) are not
    seen: the certified interval does not rely on this list.  With ``skip_start`` the range's
    start (found not stable by the certificate) is left out.
    """
    grid = [float(speeds[0])]
    for a, b in zip(speeds[:-1], speeds[1:]):
        grid.extend(float(v) for v in np.linspace(a, b, _TRACK_PER_INTERVAL + 1)[1:])
    grid = np.asarray(grid[1:] if skip_start else grid)

    def eigs(V):
        At = loop.matrix(*loop.plant(float(V)))
        return None if At is None else np.linalg.eigvals(At)

    def unstable(lam):
        return -1 if lam is None else int(np.sum(lam.real > 0))

    lams = [eigs(V) for V in grid]
    counts = [unstable(lam) for lam in lams]
    out = []
    for i in range(len(grid) - 1):
        a, b, ca = grid[i], grid[i + 1], counts[i]
        while ca != counts[i + 1]:
            lo, hi = a, b                  # the first change of the count after a
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if mid in (lo, hi):
                    break
                lo, hi = (lo, mid) if unstable(eigs(mid)) != ca else (mid, hi)
            lam = eigs(hi)
            c_hi = unstable(lam)
            if lam is None:
                out.append(ClosedLoopCrossing(float(hi), math.nan, "ill-posed", "ill-posed"))
            else:
                near = lam[np.argmin(np.abs(lam.real))]
                out.append(ClosedLoopCrossing(
                    float(hi), float(abs(near.imag)),
                    "destabilizing" if c_hi > ca else "stabilizing",
                    "flutter" if abs(near.imag) > 1e-9 * max(1.0, abs(near)) else
                    "divergence"))
            a, ca = hi, c_hi
            if hi >= b:
                break
    width = max(lam.size for lam in lams if lam is not None) if any(
        lam is not None for lam in lams) else 0
    table = np.full((grid.size, width), np.nan + 0j)
    for i, lam in enumerate(lams):
        if lam is not None:
            table[i, :lam.size] = lam[np.argsort(np.abs(lam.imag), kind="stable")]
    return tuple(out), grid, table
