"""Time response of a loop whose speed changes, closed by controllers switched with the speed.

A frozen-speed certificate (:func:`~casflutter.verify.speed_family_interval`) says that a
controller holds the loop at every *fixed* speed of its interval.  Two controllers whose
certified intervals overlap, switched at a speed in the overlap, then hold every fixed speed of
the union.  While the speed changes (a wind-tunnel ramp) the loop is time-varying: a stable
frozen loop stays stable if the speed changes slowly enough, and the switch itself (the
incoming controller takes over with its own state while the plant carries the old
controller's transient) excites the loop.  Neither is covered by the frozen certificate; this module measures both by
simulating the linear loop along a speed profile.

The simulation is exact for the loop frozen over each time step: the closed loop at the step's
middle speed (rounded to a grid of ``dV``) is discretised with the matrix exponential, the
disturbance held over the step.  The closed loops come from :func:`lft_closed_loop`, so this
shares no code with :mod:`casflutter.design`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.signal

from .._format import result_repr
from .._settings import finite_numbers
from ..errors import ConfigError
from ._common import as_statespace, ssdata
from ._lft import lft_closed_loop

__all__ = ["ScheduledResponse", "scheduled_response"]


@dataclass(frozen=True)
class ScheduledResponse:
    """The loop's response along a speed profile, with the controller in use at each time.

    Attributes
    ----------
    t : numpy.ndarray
        Times [s], shape ``(nt,)``, from 0 in steps of ``dt``; cut at the divergence, if any.
    V : numpy.ndarray
        The speed index at each time, shape ``(nt,)``.
    controller : numpy.ndarray
        Index (into ``controllers``) of the controller in use at each time, shape ``(nt,)``.
    measurements : numpy.ndarray
        The plant's outputs ``y`` (the sensors ``zm`` of eq. 9), shape ``(nt, nmeas)``.
    control : numpy.ndarray
        The controls ``u = K y`` (the flap command ``v``), shape ``(nt, ncon)``.
    switches : tuple of (float, float, int, int)
        ``(t, V, from, to)`` of every switch, in order.
    stopped_at : float or None
        The time the plant's state norm passed ``state_limit`` (the run stops there, to keep
        the numbers finite; by then the loop has long been unstable); None if it did not.
    """

    __repr__ = result_repr

    t: np.ndarray
    V: np.ndarray
    controller: np.ndarray
    measurements: np.ndarray
    control: np.ndarray
    switches: tuple
    stopped_at: float | None

    def peak(self, t0: float = 0.0, t1: float = np.inf) -> float:
        """The largest 2-norm of the measurements over ``t0 <= t <= t1``.

        Parameters
        ----------
        t0, t1 : float
            The time window [s].

        Returns
        -------
        float
        """
        sel = (self.t >= t0) & (self.t <= t1)
        if not np.any(sel):
            raise ConfigError(f"no sample in the window [{t0:g}, {t1:g}] s of a run over "
                              f"[0, {self.t[-1]:g}] s")
        return float(np.max(np.linalg.norm(self.measurements[sel], axis=1)))


def _check_profile(times, speeds) -> tuple[np.ndarray, np.ndarray]:
    t = np.array(finite_numbers("times", times), dtype=float)
    V = np.array(finite_numbers("speeds", speeds), dtype=float)
    if t.size < 2 or t.size != V.size:
        raise ConfigError(f"times and speeds: two or more breakpoints of equal number, got "
                          f"{t.size} times and {V.size} speeds")
    if t[0] != 0.0 or np.any(np.diff(t) <= 0):
        raise ConfigError(f"times must start at 0 and increase, got {t.tolist()}")
    if np.any(V < 0):
        raise ConfigError(f"speeds must be >= 0, got {V.tolist()}")
    return t, V


def _check_switches(switch_speeds, n_controllers: int, hysteresis: float) -> np.ndarray:
    s = np.array(finite_numbers("switch_speeds", switch_speeds), dtype=float)
    if n_controllers < 1:
        raise ConfigError("controllers: give at least one")
    if s.size != n_controllers - 1:
        raise ConfigError(f"switch_speeds: {n_controllers} controllers need "
                          f"{n_controllers - 1} switch speeds (controller i in use between "
                          f"switch speeds i-1 and i), got {s.size}")
    if np.any(np.diff(s) <= 0):
        raise ConfigError(f"switch_speeds must increase, got {s.tolist()}")
    if not (np.isfinite(hysteresis) and hysteresis >= 0):
        raise ConfigError(f"hysteresis = {hysteresis!r} must be a number >= 0")
    if s.size > 1 and hysteresis >= np.min(np.diff(s)):
        raise ConfigError(f"hysteresis = {hysteresis:g} must be less than the smallest gap "
                          f"between switch speeds ({np.min(np.diff(s)):g})")
    return s


def _augmented(P, nw: int, ncon: int):
    """``P`` with the controls appended to its outputs: ``[y; u; y]``, so that the lower LFT
    returns the measurements and the controls, and ``y`` again for the controller."""
    import control  # noqa: PLC0415

    A, B, C, D = ssdata(P)
    Cu = np.zeros((ncon, A.shape[0]))
    Du = np.hstack([np.zeros((ncon, nw)), np.eye(ncon)])
    return control.ss(A, B, np.vstack([C, Cu, C]), np.vstack([D, Du, D]))


def scheduled_response(plant: Callable[[float], object], controllers, switch_speeds, times,
                       speeds, *, ncon: int = 1, disturbance=None, x0=None,
                       hysteresis: float = 0.0, transfer: str = "rest", dt: float = 1e-3,
                       dV: float = 1e-3, state_limit: float = 1e50) -> ScheduledResponse:
    """Simulate ``plant(V(t))`` closed by the controller scheduled on ``V(t)`` (``u = K y``).

    Controller ``i`` is in use while ``V`` lies between ``switch_speeds[i-1]`` and
    ``switch_speeds[i]``.  With a ``hysteresis`` ``h``, the switch up past ``s`` happens at
    ``s + h/2`` and the switch down at ``s − h/2``, so a speed that hovers at ``s`` does not
    make the controllers chatter.  The plant's state carries on through a switch; the
    incoming controller starts from rest, or (``transfer="output"``) from the smallest state
    whose command, for the last measurements, repeats the outgoing controller's last command,
    so that the flap command does not jump.

    Parameters
    ----------
    plant : callable
        ``plant(V)``: the open loop at speed index ``V`` as a continuous
        ``control.StateSpace`` with inputs ``[w; u]`` (the last ``ncon`` are the controls, the
        rest the disturbances) and outputs ``y``, the measurements, e.g.
        ``lambda V: family.loop(V).statespace()`` of a ROM loop (inputs ``w_1..w_N, v``,
        outputs ``zm``, eq. 9).  The same state dimension at every speed.
    controllers : sequence of control.StateSpace
        Controllers from the measurements to the controls, in the order of increasing speed.
    switch_speeds : sequence of float
        ``len(controllers) - 1`` increasing speed indices.
    times, speeds : sequence of float
        Breakpoints of the piecewise-linear profile ``V(t)`` (``numpy.interp``); ``times``
        start at 0 and increase; the run ends at ``times[-1]``.
    ncon : int
        Number of controls (the last inputs of ``plant(V)``).
    disturbance : array_like, optional
        ``w`` at the times ``0, dt, 2 dt, …``, shape ``(nt, nw)``, held over each step; zero
        if omitted.
    x0 : array_like, optional
        The plant's initial state; zero if omitted.
    hysteresis : float
        Width of the band around each switch speed (>= 0, below the gaps between switch
        speeds).
    transfer : {"rest", "output"}
        The incoming controller's state at a switch: zero, or the least-squares state that
        repeats the outgoing controller's last command.
    dt : float
        Time step [s] (> 0).  The discretisation is exact for the loop frozen over a step.
    dV : float
        Speed grid to which the step's middle speed is rounded (> 0): each closed loop is
        formed and discretised once per grid speed.
    state_limit : float
        The run stops when the plant's state norm exceeds this (> 0): an unstable loop's
        numbers are kept finite.

    Returns
    -------
    ScheduledResponse

    Raises
    ------
    ConfigError
        A bad profile, switch speeds, hysteresis, transfer, step, grid or disturbance shape; a
        plant or controller that does not fit (named), or no excitation at all (``x0`` and
        ``disturbance`` both zero).
    """
    t_bp, V_bp = _check_profile(times, speeds)
    K = [as_statespace(k, f"controllers[{i}]") for i, k in enumerate(controllers)]
    try:
        hysteresis = float(hysteresis)
    except (TypeError, ValueError):
        raise ConfigError(f"hysteresis = {hysteresis!r} must be a number >= 0") from None
    s = _check_switches(switch_speeds, len(K), hysteresis)
    _check_stepping(transfer, dt, dV, state_limit, float(t_bp[-1]))
    n_steps = int(np.floor(t_bp[-1] / dt + 1e-9))
    t = dt * np.arange(n_steps + 1)
    P0 = as_statespace(plant(float(V_bp[0])), "plant(V)")
    n, ny = P0.nstates, P0.noutputs
    nw = _check_sizes(P0, K, ncon)
    w, x = _check_excitation(disturbance, x0, t, nw, n)
    V_t = np.interp(t, t_bp, V_bp)
    V_mid = np.interp(t[:-1] + 0.5 * dt, t_bp, V_bp)
    loops = _DiscreteLoops(plant, K, nw, ncon, ny, n, dt, dV, float(V_bp[0]))
    active = int(np.searchsorted(s, float(V_t[0]), side="right"))
    return _march(loops, K, s, hysteresis, transfer, state_limit, t, V_t, V_mid, w, x, active)


def _march(loops, K, s, hysteresis: float, transfer: str, state_limit: float, t, V_t, V_mid,
           w, x, active: int) -> ScheduledResponse:
    """Step the switched closed loop from the plant state ``x`` with controller ``active``
    (see :func:`scheduled_response`)."""
    n, ny, ncon, n_steps = x.size, loops.ny, loops.ncon, t.size - 1
    xk = np.zeros(K[active].nstates)
    used = np.empty(t.size, dtype=int)
    out = np.empty((t.size, ny + ncon))
    switches = []
    stopped_at = None
    last = t.size - 1
    for k in range(t.size):
        V = float(V_t[k])
        new = _next_band(active, V, s, hysteresis)
        if new != active:
            switches.append((float(t[k]), V, active, new))
            active, xk = new, np.zeros(K[new].nstates)
            if transfer == "output" and xk.size and k > 0:
                u_last = out[k - 1, ny:] - ssdata(K[new])[3] @ out[k - 1, :ny]
                xk = np.linalg.lstsq(ssdata(K[new])[2], u_last, rcond=None)[0]
        used[k] = active
        Ad, Bd, C, D = loops.at(active, float(V_mid[min(k, n_steps - 1)]))
        z = np.concatenate([x, xk])
        out[k] = C @ z + D @ w[k]
        if not np.linalg.norm(x) <= state_limit:
            stopped_at, last = float(t[k]), k
            break
        if k < n_steps:
            z = Ad @ z + Bd @ w[k]
            x, xk = z[:n], z[n:]
    keep = slice(0, last + 1)
    return ScheduledResponse(t=t[keep], V=V_t[keep], controller=used[keep],
                             measurements=out[keep, :ny], control=out[keep, ny:],
                             switches=tuple(switches), stopped_at=stopped_at)


def _check_stepping(transfer: str, dt, dV, state_limit, t_end: float) -> None:
    """Check the transfer rule, the time step, the speed grid and the state limit."""
    if transfer not in ("rest", "output"):
        raise ConfigError(f"transfer = {transfer!r}: allowed 'rest' (the incoming controller "
                          "starts from zero) and 'output' (from the state that repeats the "
                          "last command)")
    for name, value in (("dt", dt), ("dV", dV)):
        if not (np.isfinite(value) and value > 0):
            raise ConfigError(f"{name} = {value!r} must be > 0")
    if not (np.isfinite(state_limit) and state_limit > 0):
        raise ConfigError(f"state_limit = {state_limit!r} must be > 0")
    if not dt < t_end:
        raise ConfigError(f"dt = {dt:g} s must be shorter than the run ({t_end:g} s)")


def _check_sizes(P0, K, ncon) -> int:
    """Check that ``ncon`` and every controller fit the plant; the number of disturbances."""
    nin, ny = P0.ninputs, P0.noutputs
    if not (isinstance(ncon, (int, np.integer)) and 1 <= ncon <= nin):
        raise ConfigError(f"ncon = {ncon!r}: the plant has {nin} inputs, the last ncon of which "
                          "are the controls")
    for i, k in enumerate(K):
        if k.ninputs != ny or k.noutputs != ncon:
            raise ConfigError(f"controllers[{i}] has {k.ninputs} inputs and {k.noutputs} "
                              f"outputs; the plant needs {ny} (its measurements) in and "
                              f"{ncon} (its controls) out")
    return nin - ncon


def _check_excitation(disturbance, x0, t, nw: int, n: int):
    """The disturbance samples and the initial state, checked; not both zero."""
    w = np.zeros((t.size, nw)) if disturbance is None else np.asarray(disturbance, float)
    if w.shape != (t.size, nw) or not np.all(np.isfinite(w)):
        raise ConfigError(f"disturbance: finite, of shape ({t.size}, {nw}) (the times 0, dt, "
                          f"..., {t[-1]:g} s and the plant's {nw} disturbance inputs), got "
                          f"{w.shape}")
    x = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float).ravel()
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        raise ConfigError(f"x0: {n} finite numbers (the plant's state), got shape {x.shape}")
    if not (np.any(x) or np.any(w)):
        raise ConfigError("no excitation: x0 and the disturbance are both zero, so the "
                          "response is zero; give an initial state or a disturbance")
    return w, x


def _next_band(active: int, V: float, s: np.ndarray, hysteresis: float) -> int:
    """The controller in use at speed ``V`` after ``active``: one band up or down once ``V``
    is past a switch speed by half the hysteresis."""
    if active < s.size and V >= s[active] + 0.5 * hysteresis:
        return active + 1
    if active > 0 and V <= s[active - 1] - 0.5 * hysteresis:
        return active - 1
    return active


class _DiscreteLoops:
    """The closed loops of the plant with each controller, discretised with a zero-order
    hold (scipy) once per controller and speed of the ``dV`` grid."""

    def __init__(self, plant, K, nw: int, ncon: int, ny: int, n: int, dt: float, dV: float,
                 V0: float):
        self.plant, self.K, self.nw, self.ncon, self.ny, self.n = plant, K, nw, ncon, ny, n
        self.dt, self.dV, self.V0 = dt, dV, V0
        self.cache: dict[tuple[int, int], tuple[np.ndarray, ...]] = {}

    def at(self, i: int, V: float):
        """``(Ad, Bd, C, D)`` of the loop with controller ``i`` at the grid speed nearest
        ``V``."""
        key = (i, int(round(V / self.dV)))
        if key not in self.cache:
            Vg = key[1] * self.dV
            Pa = _augmented(as_statespace(self.plant(Vg), "plant(V)"), self.nw, self.ncon)
            if Pa.nstates != self.n:
                raise ConfigError(f"plant({Vg:g}) has {Pa.nstates} states; "
                                  f"plant({self.V0:g}) has {self.n}")
            Acl, Bcl, Ccl, Dcl = ssdata(lft_closed_loop(Pa, self.K[i], self.ny, self.ncon))
            Ad, Bd, *_ = scipy.signal.cont2discrete((Acl, Bcl, Ccl, Dcl), self.dt, method="zoh")
            self.cache[key] = (Ad, Bd, Ccl, Dcl)
        return self.cache[key]
