"""LCO branches of the continuous-time truths (``x' = f(x, V)``) by collocation.

The branch starts at the Hopf point of the undeflected equilibrium with the critical
(linear) mode shape: the first orbit is solved with its amplitude along that mode fixed
at the value for which the normal form predicts a speed offset of ``start_offset`` times the
Hopf speed, then it is continued in ``V`` by pseudo-arclength (:mod:`._branch`).  The
direction in which the first orbit leaves the Hopf point, and its speed offset, check the
first Lyapunov coefficient (:mod:`._normal_form`).

Only the branch through the Hopf point is continued.  Where that point is subcritical and
its branch has no stable cycle in the range, the system is simulated just above the Hopf
point (CVODES) from the branch's first orbit: a cycle it settles on is solved by collocation
and its own branch continued both ways, or the growth without bound is said
(:class:`~casflutter.lco.SettledMotion`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.interpolate import interp1d

from .._resources import problems_dir, read_toml
from ..data import analyze_response
from ..errors import ConfigError
from ..truth import problem_definition
from ._branch import BranchStart, run_from_hopf, run_from_orbit
from ._collocation import Collocation
from ._normal_form import MultilinearForms, find_hopf, lyapunov_flow
from ._results import SUBCRITICAL, LCOBranch, LCOPoint, LCOSettings, SettledMotion

log = logging.getLogger(__name__)

__all__ = ["Outputs", "truth_outputs", "speed_convention", "lco_branch", "continue_lco",
           "default_vrange"]

@dataclass(frozen=True)
class Outputs:
    """Named outputs ``y = h(x, V)`` whose amplitudes are reported (modes and sensors)."""

    names: tuple
    units: tuple
    function: ca.Function


def truth_outputs(truth, f: ca.Function, sensor_kind: str = "displacement") -> Outputs:
    """Modal displacements (by mode name) and sensors (by sensor name) of a truth.

    Sensors are ``Hs u`` (``sensor_kind = "displacement"``) or ``Hs u''`` with ``u''`` from
    the vector field (``"acceleration"``).  A truth whose coordinates are already the
    physical ones (``lco_modal_outputs = False``, the rig sections) reports its sensors only.
    """
    ms = truth.modal_structure()
    N = ms.n_modes
    nx = int(f.size1_in(0))
    x = ca.SX.sym("x", nx)
    V = ca.SX.sym("V")
    H = ca.DM(np.asarray(ms.Hs, float))
    names, units, rows = [], [], []
    sunits = truth.sensor_units()
    if getattr(truth, "lco_modal_outputs", True):
        names += list(ms.mode_names)
        units += [""] * N
        rows.append(x[:N])
    if sensor_kind == "acceleration":
        rows.append(ca.mtimes(H, f(x, V)[N:2 * N]))
        tu = ms.time_unit if ms.time_unit.isalpha() else f"({ms.time_unit})"
        units += [f"{u}/{tu}^2" if u else "" for u in sunits]
    else:
        rows.append(ca.mtimes(H, x[:N]))
        units += list(sunits)
    names += list(ms.sensor_names)
    if len(set(names)) != len(names):
        names = [f"{n} [{k}]" for k, n in enumerate(names)]
    return Outputs(tuple(names), tuple(units),
                   ca.Function("outputs", [x, V], [ca.vertcat(*rows)]))


def speed_convention(truth) -> tuple[float, str]:
    """``(shown speed per speed index, unit)`` of a problem's
    :class:`~casflutter.structure.SpeedConvention`: ``(U_ref, "m/s")`` when it has an
    airspeed scale, else ``(1, the speed index's definition)``.

    Parameters
    ----------
    truth : object
        A problem with ``modal_structure()`` (a truth or a wing file's problem).

    Returns
    -------
    tuple of (float, str)
    """
    speed = truth.modal_structure().speed
    return speed.display_scale, speed.speed_unit


class _OdeDisc:
    """Adaptor of :class:`Collocation` for the continuation engine."""

    def __init__(self, col: Collocation, outputs: Outputs):
        self.col = col
        self.iV = col.iV
        self.outputs = outputs
        self._h = outputs.function.map(col.N * 16)
        self.w2 = np.ones((col.n, 1))      # state weights of size(); set from the mode shape

    def solve(self, X0, ref, c, s):
        return self.col.solve(X0, ref, c, s)

    def jacobian(self, X, ref):
        return self.col.jacobian(X, ref)

    def reference(self, X):
        return self.col.reference(X)

    def size(self, X) -> float:
        W = self.col.nodes(X)
        return float(np.sqrt(np.mean(np.sum((W - W.mean(axis=1, keepdims=True)) ** 2 * self.w2,
                                            axis=0))))

    def evaluate(self, X) -> LCOPoint:
        col = self.col
        _, Wf = col.fine(X, 16)
        V, T = float(X[col.iV]), float(X[col.iT])
        Y = np.asarray(self._h(Wf, np.full((1, Wf.shape[1]), V)))
        amp = 0.5 * (Y.max(axis=1) - Y.min(axis=1))
        mean = Y.mean(axis=1)
        Mon = col.monodromy(X)
        mu, vecs = np.linalg.eig(Mon)
        x0 = col.nodes(X)[:, 0]
        f0 = np.asarray(col.f(x0, V)).ravel()
        f0 = f0 / max(np.linalg.norm(f0), 1e-300)
        align = np.abs(f0 @ vecs) / np.linalg.norm(vecs, axis=0)
        k = int(np.argmax(align - 1e-3 * np.abs(mu - 1)))
        others = np.delete(mu, k)
        mmax = float(np.max(np.abs(others))) if others.size else 0.0
        names = self.outputs.names
        return LCOPoint(V=V, period=T, freq_hz=1.0 / T,
                        amplitude={n: float(a) for n, a in zip(names, amp)},
                        mean={n: float(a) for n, a in zip(names, mean)},
                        multipliers=mu, max_multiplier=mmax, stable=bool(mmax < 1.0),
                        trivial_error=float(abs(mu[k] - 1.0)), state=x0.copy())


def continue_lco(f: ca.Function, outputs: Outputs, vrange, settings: LCOSettings | None = None,
                 *, problem: str = "", speed_scale: float = 1.0, speed_unit: str = "",
                 time_unit: str = "s", n_modes: int | None = None) -> LCOBranch:
    """LCO branch of ``x' = f(x, V)`` from its first Hopf point in ``vrange``.

    Parameters
    ----------
    f : casadi.Function
        ``f(x, V)`` with ``f(0, V) = 0``.
    outputs : Outputs
        The reported outputs.
    vrange : (float, float)
        Speed-index range: the Hopf point is searched and the branch kept in it.
    settings : LCOSettings, optional
    problem, speed_scale, speed_unit, time_unit :
        Labels of the result (see :class:`LCOBranch`).
    n_modes : int, optional
        Number of displacement states at the start of ``x`` (the amplitude of the first
        orbit is set on the largest of them); all states if omitted.

    Returns
    -------
    LCOBranch
        With :attr:`~LCOBranch.settled` set where the Hopf point is subcritical and its
        branch has no stable cycle in the range (module docstring).

    Raises
    ------
    ConfigError
        No Hopf point in the range (or unstable at its start), or a degenerate Hopf point
        (zero first Lyapunov coefficient: the nonlinearity does not act at third order).
    ConvergenceError
        The first orbit next to the Hopf point could not be solved.
    """
    settings = LCOSettings() if settings is None else settings
    lo, hi = (float(v) for v in vrange)
    if not 0 < lo < hi:
        raise ConfigError(f"vrange = ({lo}, {hi}) must satisfy 0 < lo < hi")
    t0 = time.perf_counter()
    forms = MultilinearForms(f)
    cp = find_hopf(forms, (lo, hi), settings.n_grid, speed_scale=speed_scale,
                   speed_unit=speed_unit)
    l1 = lyapunov_flow(forms, cp)
    omega = cp.eigenvalue.imag
    t_hopf = time.perf_counter() - t0
    if not math.isfinite(l1) or abs(l1) < 1e-14 * max(1.0, np.max(np.abs(cp.A))):
        raise ConfigError(f"the Hopf point at {cp.V * speed_scale:.6g} {speed_unit} is degenerate "
                          f"(first Lyapunov "
                          f"coefficient {l1:.3g}): the system has no nonlinearity acting at "
                          "third order (e.g. a linear truth), so no LCO branch leaves it")
    nd = int(n_modes) if n_modes else cp.q.size
    dom = int(np.argmax(np.abs(cp.q[:nd])))
    qhat = cp.q * np.exp(-1j * np.angle(cp.q[dom])) / abs(cp.q[dom])
    col = Collocation(f, settings.n_intervals, settings.degree, tol=settings.tol,
                      max_newton=settings.max_newton)
    disc = _OdeDisc(col, outputs)
    T0 = 2.0 * math.pi / omega

    def mode(tau):
        return np.real(qhat[:, None] * np.exp(2j * math.pi * tau)[None, :])

    phi = col.initial_guess(mode, 0.0, 0.0)
    phi[col.iT] = phi[col.iV] = 0.0
    start = BranchStart(
        cp=cp, lyapunov=l1, radial=omega * l1, omega=omega, freq_hz=omega / (2 * math.pi),
        discrete=False, qhat=qhat, dominant=dom,
        guess=lambda eps, V: col.initial_guess(lambda tau: eps * mode(tau), T0, V),
        phi=phi, n_points=col.npts, period0=T0, hint="try more mesh intervals",
        ref=col.reference_from(lambda tau: np.real(2j * math.pi * qhat[:, None]
                                                   * np.exp(2j * math.pi * tau)[None, :])))
    t1b = time.perf_counter()
    hopf, run = run_from_hopf(disc, start, settings, (lo, hi), speed_scale=speed_scale,
                              speed_unit=speed_unit)
    t_branch = time.perf_counter() - t1b
    settled = None
    if hopf.kind == SUBCRITICAL and run.points and not any(p.stable for p in run.points):
        t2 = time.perf_counter()
        settled = _settled_motion(f, outputs, disc, cp.V, omega, run.points[0].state,
                                  settings, (lo, hi), speed_scale, speed_unit, time_unit)
        log.info("%s", settled.note)
        t_branch += time.perf_counter() - t2
    return LCOBranch(problem=problem, system="truth", hopf=hopf, points=tuple(run.points),
                     folds=tuple(run.folds), outputs=outputs.names, output_units=outputs.units,
                     speed_unit=speed_unit, speed_scale=speed_scale, time_unit=time_unit,
                     completed=run.completed, stop_reason=run.stop_reason, vrange=(lo, hi),
                     timings={"hopf": t_hopf, "branch": t_branch,
                              "total": time.perf_counter() - t0}, settled=settled)


#: periods of the critical pair simulated just above a subcritical Hopf point
_SETTLE_PERIODS = 400


def _integrate(f: ca.Function, x0: np.ndarray, V: float, t: np.ndarray) -> np.ndarray | None:
    """States ``(n, len(t))`` of ``x' = f(x, V)`` from ``x0`` at the times ``t`` (CVODES in
    one call: the simulation runs in compiled code), or None where the integration fails
    (the state escapes)."""
    x = ca.MX.sym("x", int(f.size1_in(0)))
    F = ca.integrator("settle", "cvodes", {"x": x, "ode": f(x, V)}, float(t[0]), t[1:],
                      {"reltol": 1e-8, "abstol": 1e-12 * max(float(np.max(np.abs(x0))), 1e-300),
                       "max_num_steps": 100000})
    try:
        X = np.asarray(F(x0=x0)["xf"], float)
    except RuntimeError:
        return None
    X = np.column_stack([x0, X])
    return X if np.all(np.isfinite(X)) else None


def _settled_motion(f: ca.Function, outputs: Outputs, disc: "_OdeDisc", Vh: float,
                    omega: float, x0: np.ndarray, settings: LCOSettings, vrange: tuple,
                    speed_scale: float, speed_unit: str, time_unit: str) -> SettledMotion:
    """Simulate ``x' = f(x, V)`` just above the Hopf point from the branch's first orbit,
    classify what it settles on and continue a settled cycle's branch
    (:class:`SettledMotion`)."""
    V = min(1.02 * Vh, 0.5 * (Vh + vrange[1]))
    duration = _SETTLE_PERIODS * 2.0 * math.pi / omega
    x0 = np.asarray(x0, float)
    bound = 1e6 * max(float(np.max(np.abs(x0))), 1e-300)
    t = np.linspace(0.0, duration, 32 * _SETTLE_PERIODS + 1)
    u = f" {speed_unit}" if speed_unit and " " not in speed_unit else ""   # not a definition
    at = f"at V = {V * speed_scale:.5g}{u}, {100 * (V / Vh - 1):.2g} % above the flutter speed,"
    grows = (f"{at} the motion from the first orbit grows without bound: no stable limit "
             "cycle catches it")
    states = _integrate(f, x0, V, t)
    if states is None or float(np.max(np.abs(states))) > bound:
        return SettledMotion(V=V, kind="divergence", duration=duration, freq_hz=math.nan,
                             amplitude={}, note=grows)
    Y = np.asarray(outputs.function.map(t.size)(states, np.full((1, t.size), V)), float)
    blowup = np.inf if settings.max_amplitude is None else settings.max_amplitude
    an = analyze_response(t, Y.T, blowup=blowup)
    amp = {n: float(a) for n, a in zip(outputs.names, an.amplitude)}
    if an.kind == "divergence":
        return SettledMotion(V=V, kind="divergence", duration=duration, freq_hz=math.nan,
                             amplitude={}, note=grows)
    if an.kind != "lco":
        return SettledMotion(V=V, kind=an.kind, duration=duration, freq_hz=math.nan,
                             amplitude={}, note=f"{at} the motion from the first orbit "
                             f"does not settle on a limit cycle ({an.kind})")
    words = ", ".join(f"{n} {a:.4g}{' ' + un if un else ''}" for (n, a), un in
                      zip(amp.items(), outputs.units))
    hz = "Hz" if time_unit == "s" else f"cycles per {time_unit}"
    found = (f"{at} the motion settles on a stable limit cycle ({words}; "
             f"{an.frequency_hz:.4g} {hz}) that the branch from the Hopf point does not reach")
    col = disc.col
    T = 1.0 / an.frequency_hz
    last = t >= duration - 1.5 * T                 # the last cycle and a half, resampled
    cycle = interp1d(t[last], states[:, last], kind="cubic", axis=1)
    guess = col.initial_guess(lambda tau: cycle(duration - T + tau * T), T, V)
    W = col.nodes(guess)
    A = 0.5 * (W.max(axis=1) - W.min(axis=1))
    A = np.maximum(A, 1e-3 * A.max())
    M = np.concatenate([np.tile(1.0 / (col.npts * A ** 2), col.npts),
                        [1.0 / T ** 2, 1.0 / (0.05 * V) ** 2]])
    run = run_from_orbit(disc, guess, M, settings, vrange)
    if run is None:
        return SettledMotion(V=V, kind="lco", duration=duration, freq_hz=an.frequency_hz,
                             amplitude=amp, note=f"{found}; its collocation did not converge, "
                             "so its branch is not continued")
    speeds = [p.V * speed_scale for p in run.points]
    stable = [p.V * speed_scale for p in run.points if p.stable]
    span = (f"; its own branch spans V = {min(speeds):.5g} to {max(speeds):.5g}{u}"
            + (f", stable between {min(stable):.5g} and {max(stable):.5g}{u}" if stable
               else ""))
    return SettledMotion(V=V, kind="lco", duration=duration, freq_hz=an.frequency_hz,
                         amplitude=amp, points=tuple(run.points), folds=tuple(run.folds),
                         note=found + span)


def lco_branch(truth, vrange=None, settings: LCOSettings | None = None,
               problem: str | None = None) -> LCOBranch:
    """The LCO branch of a truth from its Hopf (flutter) point, continued in the speed.

    Parameters
    ----------
    truth : AeroelasticTruth
        Any truth with :meth:`vector_field` (typical section, rig section, Goland, seed
        wing).
    vrange : (float, float), optional
        Speed-index range (default: the ``[lco] vrange`` of the problem definition when it
        has one, else ``[rom] V_range``); the rig sections' speed index is the airspeed.
    settings : LCOSettings, optional
        Collocation mesh, continuation step and budget (defaults: ``LCOSettings()``).
    problem : str, optional
        Label (default the truth's name).

    Returns
    -------
    LCOBranch
        Speeds of the branch in the speed index (``branch.speed(V)`` converts); amplitudes
        per mode and per sensor (the rig sections: ``heave`` [m], ``pitch`` [rad]).

    Raises
    ------
    ConfigError
        No range given and none in the definition, no Hopf point in it, or a linear truth.
    ConvergenceError
        The first orbit did not converge.

    See Also
    --------
    rom_lco_branch : the same for the ROM loop.
    truth_lco : one long simulation at one speed (the independent check).

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section", ["kappa2=3"])
    >>> b = cf.lco_branch(truth, (1.5, 2.5), cf.LCOSettings(max_points=10))
    >>> b.hopf.kind, round(b.hopf.V, 3)
    ('supercritical', 2.17)
    """
    settings = LCOSettings() if settings is None else settings
    if vrange is None:
        vrange = default_vrange(truth)
    f = truth.vector_field()
    outputs = truth_outputs(truth, f, settings.sensor_kind)
    scale, unit = speed_convention(truth)
    ms = truth.modal_structure()
    return continue_lco(f, outputs, vrange, settings,
                        problem=problem or str(getattr(truth, "name", type(truth).__name__)),
                        speed_scale=scale, speed_unit=unit, time_unit=ms.time_unit,
                        n_modes=truth.n_modes)


def default_vrange(truth) -> tuple[float, float]:
    """``[lco] vrange`` of the problem's definition (problem speed unit), else its ``[rom]
    V_range`` (speed index, a problem file's ROM route), else ``flutter.V_range`` of the
    problem's ``flutter.toml`` (the ROM route of a built-in problem).

    Raises
    ------
    ConfigError
        Neither is available.
    """
    definition = getattr(truth, "definition", None)
    if definition is None:
        try:
            definition = problem_definition(getattr(truth, "name", ""))
        except ConfigError:
            definition = {}
    scale, _ = speed_convention(truth)
    lco = dict(definition.get("lco", {}))
    if "vrange" in lco:
        lo, hi = lco["vrange"]
        return float(lo) / scale, float(hi) / scale
    rom = dict(definition.get("rom", {}))
    if "V_range" in rom:
        lo, hi = rom["V_range"]
        return float(lo), float(hi)
    route = problems_dir() / str(getattr(truth, "name", "")) / "flutter.toml"
    if getattr(truth, "name", "") and route.is_file():
        lo, hi = read_toml(route, "flutter configuration").get("flutter", {})["V_range"]
        return float(lo), float(hi)
    raise ConfigError("no speed range: pass vrange (or --vrange LO HI), or add [lco] vrange to "
                      "the problem definition")
