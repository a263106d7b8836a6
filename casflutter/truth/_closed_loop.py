"""A truth simulator in closed loop with a controller: the wind tunnel of the paper's §IV.

- :func:`closed_loop_truth` — the sampled-data loop of the nonlinear truth, a controller
  ``K`` (ZOH at the sample time) and a second-order flap actuator, with a gain schedule
  ``g(t)`` on the controller output (paper Fig. 11 ramps it 0 -> 1);
- :func:`suppression_run` — paper Fig. 11: the LCO develops, the gain ramps, holds and is
  released, in the tunnel's turbulence with noisy sensors; the attenuation of the dominant
  sensor; :func:`suppression_runs` — one such run per speed, each from the established LCO;
- :func:`truth_loop_matrix` / :func:`truth_loop_sweep` — the truth's *linear* loop with the
  controller and the actuator, and its spectral abscissa over a range of speeds with the
  closed-loop stable interval around the flutter speed.

Controllers follow the convention of eq. 14: the flap command is ``v_c = +K zm``.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Callable

import control
import numpy as np
from scipy.optimize import brentq

from .._format import result_repr
from .._linalg import spectral_abscissa
from .._processes import map_in_processes
from .._settings import finite_numbers
from .._threads import single_threaded
from ..errors import CasflutterError, ConfigError, DimensionError
from ._lco import truth_lco
from ._turbulence import tunnel_disturbances

__all__ = ["TruthLoopSimulation", "closed_loop_truth", "gain_schedule", "limit_command",
           "SuppressionSettings",
           "SuppressionResult", "suppression_run", "suppression_runs", "truth_loop_matrix",
           "TruthLoopSweep", "truth_loop_sweep"]


def _sensor_rows(truth, rows) -> np.ndarray:
    """``Hs`` of a truth: ``rows`` if given (checked), else the truth's own."""
    return truth.modal_structure().with_sensors(rows).Hs


@dataclass(frozen=True)
class TruthLoopSimulation:
    """Record of :func:`closed_loop_truth` (NaN after a blow-up).

    Attributes
    ----------
    timepts : ndarray, shape (K,)
        Sample times.
    zm : ndarray, shape (K, n_sensors)
        Sensor readings.
    v : ndarray, shape (K,)
        Flap angle (actuator output).
    gain : ndarray, shape (K,)
        Gain schedule ``g(t_k)``.
    v_rate : ndarray, shape (K,)
        Flap rate (actuator output rate).
    """

    __repr__ = result_repr

    timepts: np.ndarray
    zm: np.ndarray
    v: np.ndarray
    gain: np.ndarray
    v_rate: np.ndarray | None = None


def _record(values, shape: tuple, name: str) -> np.ndarray | None:
    """A per-sample input record of ``shape`` as floats (``None`` stays ``None``)."""
    if values is None:
        return None
    out = np.asarray(values, dtype=float)
    if out.shape != shape:
        raise DimensionError(f"{name} must have shape {shape} (samples, channels), got "
                             f"{out.shape}")
    return out


def gain_schedule(settle: float, ramp: float, hold: float) -> Callable[[float], float]:
    """g(t): 0 for ``t < settle``, linear to 1 over ``ramp``, 1 for ``hold``, then 0.

    Parameters
    ----------
    settle, ramp, hold : float
        Durations of the open loop, of the ramp and of the full gain.

    Returns
    -------
    callable
        ``g(t) -> float``.
    """
    t_on, t_full, t_off = settle, settle + ramp, settle + ramp + hold

    def g(t: float) -> float:
        if t < t_on or t >= t_off:
            return 0.0
        if t < t_full:
            return (t - t_on) / ramp
        return 1.0

    return g


def closed_loop_truth(truth, K: control.StateSpace, V: float, timepts, x0, gain, *,
                      actuator_omega: float = 2 * np.pi * 40.0, actuator_zeta: float = 0.7,
                      substeps: int = 4, sensor: str = "acceleration",
                      kick: tuple[float, int, float] | None = None,
                      sensor_rows=None, flap_limit: float | None = None,
                      flap_rate_limit: float | None = None, disturbance=None,
                      sensor_noise=None, command_limiter: str = "none",
                      stop: Callable[[int, np.ndarray], bool] | None = None
                      ) -> TruthLoopSimulation:
    """Sampled-data closed loop of the nonlinear truth with the controller ``K``.

    At every sample ``t_k`` the sensors are read, the controller (ZOH discretisation at the
    sample time) updates, and the flap command ``v_c = g(t_k) K zm`` is held until
    ``t_{k+1}``; the flap follows a second-order actuator (our choice, the paper gives none),
    which supplies the flap rate and acceleration the aerodynamics need.  The truth is
    integrated by classical Runge--Kutta with ``substeps`` steps per sample.

    The controller is engaged with the gain: its state stays at zero while ``g = 0`` (a
    controller switched on in the tunnel starts from rest; one that ran open-loop beside an
    established LCO would have integrated it, and a slow controller pole turns that into a
    flap offset at switch-on).

    A real flap servo saturates: with ``flap_limit`` the command is clipped to
    ``±flap_limit`` and the actuator stops at that angle; with ``flap_rate_limit`` the
    actuator's rate stops growing at ``±flap_rate_limit`` (its acceleration is cut while the
    rate is at the limit and pushing outwards, the flap moves at the clipped rate within a
    Runge--Kutta step, whose stages a sharp command would otherwise carry past the limit,
    and the rate is clipped after every step).  A flap at its rate limit lags its command,
    by up to a quarter period deep in saturation; ``command_limiter`` puts a software rate
    limiter between the controller and the servo (:class:`_CommandLimiter`), whose
    phase-compensated form turns the flap with the command.

    A tunnel's turbulence enters as eq. 7's modal disturbance ``w`` (``disturbance``, held over
    each sample interval, through the truth's own disturbance input of
    :meth:`~casflutter.truth.AeroelasticTruth.statespace`), and its sensors' noise is added to
    the readings the controller sees and the record keeps (``sensor_noise``);
    :func:`~casflutter.truth.tunnel_disturbances` draws both.

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator (its :meth:`flap_dynamics`).
    K : control.StateSpace
        Continuous controller from the sensors to the flap command.
    V : float
        Speed index.
    timepts : array_like, shape (K,)
        Uniform sample times.
    x0 : ModalState or array_like
        Initial state: a :class:`~casflutter.structure.ModalState` (e.g.
        :meth:`displaced_state`) or ``[u, u']``, the flow at rest; or the truth's full state.
    gain : callable
        ``g(t)`` multiplying the controller output.
    actuator_omega, actuator_zeta : float
        Natural frequency [rad per time unit] and damping ratio of the flap actuator.
    substeps : int
        Runge--Kutta steps per sample.
    sensor : {"acceleration", "displacement"}
        ``zm = Hs u''`` (the paper's accelerometers) or ``zm = Hs u``.
    kick : (float, int, float), optional
        ``(time, mode, deflection)``: a modal deflection added at that time (a tap on the
        wing, as the tunnel's turbulence would give), so that a released flutter can restart
        from a quiet wing.
    sensor_rows : array_like, shape (n_sensors, N), optional
        ``Hs`` (default: the truth's own).
    flap_limit : float, optional
        Largest flap angle (the truth's flap unit, rad for the seed wing); no limit when
        omitted.
    flap_rate_limit : float, optional
        Largest flap rate [flap unit per time unit]; no limit when omitted.
    disturbance : array_like, shape (K, N), optional
        Eq. 7's modal disturbance ``w`` at the samples (zero when omitted).
    sensor_noise : array_like, shape (K, n_sensors), optional
        Added to the sensor readings (zero when omitted).
    command_limiter : {"none", "rate", "phase_compensated"}
        The software limiter of the flap command at the sample rate, at ``flap_rate_limit``
        (:class:`_CommandLimiter`; ``"none"``: the command goes to the servo as it is).
    stop : callable, optional
        ``stop(k, zm) -> bool``, called once sample ``k`` is recorded, with the readings so
        far (``zm[:k + 1]`` are set): ``True`` ends the simulation there, and the record
        ends with sample ``k``.

    Returns
    -------
    TruthLoopSimulation
        Stopped (NaN from there on) when the state blows up; cut after the sample at which
        ``stop`` said so.

    Raises
    ------
    ConfigError
        An unknown ``sensor`` or ``command_limiter``, a non-positive limit, or a command
        limiter without ``flap_rate_limit``.
    DimensionError
        A disturbance or noise record of the wrong shape.

    See Also
    --------
    suppression_run : the paper's gain ramp and release (Fig. 11) on the truth.

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> K = control.ss([], [], [], [[0.0, 0.0]])
    >>> t = np.arange(0.0, 50.0, 0.1)
    >>> sim = cf.closed_loop_truth(truth, K, 1.5, t, truth.displaced_state(1, 0.01),
    ...                            lambda t: 1.0, sensor="displacement")
    >>> sim.zm.shape
    (500, 2)
    """
    if sensor not in ("acceleration", "displacement"):
        raise ConfigError(f"sensor={sensor!r}: use 'acceleration' or 'displacement'")
    servo = _FlapServo.of(actuator_omega, actuator_zeta, flap_limit, flap_rate_limit)
    t = np.asarray(timepts, dtype=float)
    dt = float(t[1] - t[0])
    limiter = _CommandLimiter.of(command_limiter, flap_rate_limit, dt, flap_limit)
    nx = truth.state_matrix(V).shape[0]
    s = truth.layout.initial(x0, nx)  # the flow at rest
    Hs = _sensor_rows(truth, sensor_rows)
    W = _record(disturbance, (t.size, truth.n_modes), "disturbance")
    noise = _record(sensor_noise, (t.size, Hs.shape[0]), "sensor_noise")
    # the disturbance's rate of the truth state, per sample (eq. 7's input of statespace)
    forcing = None if W is None else W @ np.asarray(truth.statespace(V).B)[:nx, 1:].T
    ZM = np.full((t.size, Hs.shape[0]), np.nan)
    Vf = np.zeros(t.size)
    Vr = np.zeros(t.size)
    G = np.zeros(t.size)
    n = _run_closed_loop(truth, truth.flap_dynamics(V), s, _sampled(K, dt), servo, Hs,
                         sensor == "acceleration", t, gain, kick, substeps, (ZM, Vf, Vr, G),
                         forcing=forcing, noise=noise, stop=stop, limiter=limiter)
    return TruthLoopSimulation(t[:n], ZM[:n], Vf[:n], G[:n], Vr[:n])


def _sampled(K: control.StateSpace, dt: float):
    """``(A, B, C, D, n_states)`` of the controller sampled with a zero-order hold at ``dt``
    (a static gain as it is)."""
    Kd = control.sample_system(K, dt, method="zoh") if K.nstates else K
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (Kd.A, Kd.B, Kd.C, Kd.D))
    return Ak, Bk, Ck, Dk, (Ak.shape[0] if K.nstates else 0)


def _run_closed_loop(truth, f, s, controller, servo, Hs, acceleration: bool, t, gain, kick,
                     substeps: int, records, *, forcing=None, noise=None, stop=None,
                     limiter=None) -> int:
    """The sample loop of :func:`closed_loop_truth` from the truth state ``s``: read the
    sensors, update the controller (state ``(A, B, C, D, n)`` discretised), hold the command
    and integrate over the sample; fills ``records = (zm, v, v', g)`` up to a blow-up.
    ``forcing`` (samples, states): the disturbance's rate of the state, held over each
    sample; ``noise`` (samples, sensors): added to the readings; ``stop(k, zm)``: end after
    sample ``k``; ``limiter``: a :class:`_CommandLimiter` the command passes through.
    Returns the number of samples the record keeps."""
    Ak, Bk, Ck, Dk, nk = controller
    ZM, Vf, Vr, G = records
    N, n = truth.n_modes, t.size
    h = float(t[1] - t[0]) / substeps
    xa = np.zeros(2)  # actuator: v, v'
    xk = np.zeros(nk)
    fw = None  # the disturbance's rate of the state over the current sample interval
    vc = 0.0  # command held over the current sample interval
    kicked = kick is None
    for k in range(n):
        if not kicked and t[k] >= kick[0]:
            s[:2 * N] += truth.layout.vector(truth.displaced_state(kick[1], kick[2]))
            kicked = True
        if forcing is not None:
            fw = forcing[k]
        _, acc = f(s, xa[0], xa[1], servo.acceleration(xa, vc))
        if fw is not None:
            acc = acc + fw[N:2 * N]
        zm = Hs @ (acc if acceleration else s[:Hs.shape[1]])
        if noise is not None:
            zm = zm + noise[k]
        if not np.all(np.isfinite(zm)) or np.abs(s).max() > 1e6:
            break
        ZM[k], Vf[k], Vr[k], G[k] = zm, xa[0], xa[1], gain(t[k])
        if stop is not None and stop(k, ZM):
            return k + 1
        vc = G[k] * float((Ck @ xk + Dk @ zm)[0]) if nk else G[k] * float((Dk @ zm)[0])
        if limiter is not None:     # on the controller's own command: where it turns
            vc = limiter.step(vc)
        vc = min(max(vc, -servo.pos_max), servo.pos_max)
        if nk and G[k] > 0:  # the controller runs from its engagement (state zero before)
            xk = Ak @ xk + Bk @ zm
        if k == n - 1:
            break
        s, xa = servo.integrate(f, s, xa, vc, h, substeps, fw)
    return n


@dataclass(frozen=True)
class _FlapServo:
    """The second-order flap actuator of :func:`closed_loop_truth` with its end stops
    (``pos_max``) and rate limit (``rate_max``, ``inf`` without them), and the classical
    Runge--Kutta integration of the truth and the servo over one sample."""

    wa2: float        # actuator_omega ** 2
    ca: float         # 2 actuator_zeta actuator_omega
    pos_max: float
    rate_max: float

    @classmethod
    def of(cls, actuator_omega, actuator_zeta, flap_limit, flap_rate_limit) -> "_FlapServo":
        """The servo of the arguments of :func:`closed_loop_truth` (limits checked)."""
        for name, value in (("flap_limit", flap_limit), ("flap_rate_limit", flap_rate_limit)):
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ConfigError(f"{name} = {value!r}: give a positive limit, or None for none")
        return cls(actuator_omega ** 2, 2 * actuator_zeta * actuator_omega,
                   np.inf if flap_limit is None else float(flap_limit),
                   np.inf if flap_rate_limit is None else float(flap_rate_limit))

    def acceleration(self, xa, vc: float) -> float:
        """Flap acceleration for the servo state ``xa = (v, v')`` and the command ``vc``."""
        vdd = self.wa2 * (vc - xa[0]) - self.ca * xa[1]
        if abs(xa[1]) >= self.rate_max and vdd * xa[1] > 0:
            vdd = 0.0  # the servo runs at its rate limit
        if abs(xa[0]) >= self.pos_max and xa[0] * vdd > 0:
            vdd = 0.0  # on the end stop
        return vdd

    def integrate(self, f, s, xa, vc: float, h: float, steps: int, forcing=None):
        """``steps`` Runge--Kutta steps of length ``h`` of the truth ``f`` (its
        :meth:`flap_dynamics`) and the servo under the held command ``vc`` (and the held
        rate ``forcing`` of the state by a disturbance).  Within a step the flap moves at
        most at the rate limit: a sharp command would otherwise carry the stages past it."""

        def deriv(s_, xa_):
            vdd = self.acceleration(xa_, vc)
            rate = min(max(xa_[1], -self.rate_max), self.rate_max)
            ds, _ = f(s_, xa_[0], rate, vdd)
            return (ds if forcing is None else ds + forcing), np.array([rate, vdd])

        for _ in range(steps):
            k1s, k1a = deriv(s, xa)
            k2s, k2a = deriv(s + 0.5 * h * k1s, xa + 0.5 * h * k1a)
            k3s, k3a = deriv(s + 0.5 * h * k2s, xa + 0.5 * h * k2a)
            k4s, k4a = deriv(s + h * k3s, xa + h * k3a)
            s = s + h / 6 * (k1s + 2 * k2s + 2 * k3s + k4s)
            xa = xa + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
            xa[1] = min(max(float(xa[1]), -self.rate_max), self.rate_max)
            if abs(xa[0]) > self.pos_max:  # the end stop
                xa[0], xa[1] = float(np.sign(xa[0]) * self.pos_max), 0.0
        return s, xa


#: the command limiters of :func:`closed_loop_truth`
COMMAND_LIMITERS = ("none", "rate", "phase_compensated")


class _CommandLimiter:
    """A software rate limiter of the flap command, run at the sample rate ``dt``.

    Each sample the output moves towards the command by at most ``rate * dt``.  A plain
    limiter (``"rate"``) always moves towards the command, so under a command faster than
    the limit it peaks only when it meets the command again: a triangle wave that falls
    behind the command by up to a quarter period the deeper the saturation, the lag that a
    rate-limited servo adds to a loop (and that drives rate-limit-induced oscillations in
    flight control).

    The phase-compensated limiter (``"phase_compensated"``) turns as soon as the command does:
    while it is behind the command and the command's rate points back towards it, it moves
    with the command's rate instead, so it peaks with the command (a triangle wave in phase
    with it, whose fundamental, ``4 rate / (pi omega)`` at the frequency ``omega``, is the
    largest any signal of that rate can have).  A turn that would carry it further from zero
    is not taken (it then moves towards the command, as the plain limiter does), so the
    triangle stays around the flap's neutral position instead of drifting to one side
    (without that rule the seed wing's flap drifted onto its end stop).
    This is the rule of the phase-compensating rate limiters of flight control (reverse the
    output's rate when the command reverses while saturated, with a bias correction towards
    neutral).  Below the limit both are the identity.

    The limiter reads the controller's own command, not the command clipped to the flap's
    travel: a clipped command stays flat at the end of the travel, and the limiter would turn
    only when the command comes off it, as late as the plain one (on the seed wing at 1.2 Vf
    that undid the whole gain).  Its output is kept inside the travel (``bound``), so it cannot
    wind up beyond it.
    """

    def __init__(self, kind: str, rate: float, dt: float, bound: float | None = None):
        self.kind, self.step_max = kind, float(rate) * float(dt)
        self.bound = np.inf if bound is None else float(bound)
        self.y = self.u = 0.0

    @classmethod
    def of(cls, kind: str, rate: float | None, dt: float, bound: float | None = None
           ) -> "_CommandLimiter | None":
        """The limiter of :func:`closed_loop_truth`'s arguments (``None`` for ``"none"``;
        ``bound``: the flap's travel, ``None`` for none)."""
        if kind not in COMMAND_LIMITERS:
            raise ConfigError(f"command_limiter = {kind!r}: allowed {list(COMMAND_LIMITERS)}")
        if kind == "none":
            return None
        if rate is None:
            raise ConfigError(f"command_limiter = {kind!r} limits the command's rate to the "
                              "servo's: give flap_rate_limit too")
        return cls(kind, rate, dt, bound)

    def step(self, u: float) -> float:
        """The output for the command ``u`` of this sample."""
        e, du = u - self.y, u - self.u
        self.u = u
        if abs(e) <= self.step_max:
            self.y = u
        elif self.kind == "phase_compensated" and du * e < 0 and du * self.y < 0:
            self.y += self.step_max * np.sign(du)       # turn with the command, towards 0
        else:
            self.y += self.step_max * np.sign(e)
        self.y = min(max(self.y, -self.bound), self.bound)
        return self.y


def limit_command(command, rate: float, dt: float, kind: str = "phase_compensated", *,
                  travel: float | None = None) -> np.ndarray:
    """A sampled flap command through the software limiter of :func:`closed_loop_truth`.

    Parameters
    ----------
    command : array_like, shape (K,)
        The command at the samples, from rest (the limiter starts at 0).
    rate : float
        The rate limit [flap unit per time unit] (> 0).
    dt : float
        Sample time (> 0).
    kind : {"rate", "phase_compensated", "none"}
        The limiter (:class:`_CommandLimiter`): the plain one falls behind a command faster
        than ``rate`` by up to a quarter period, the phase-compensated one turns with it.
    travel : float, optional
        The flap's travel: the output stays within ``±travel`` (no bound when omitted).

    Returns
    -------
    ndarray, shape (K,)
        What the servo is commanded.

    Raises
    ------
    ConfigError
        An unknown ``kind`` or a non-positive ``rate`` or ``dt``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 1.0, 0.002)
    >>> u = np.sin(2 * np.pi * 10 * t)                # 63 rad/s of command rate at most
    >>> y = limit_command(u, 5.0, 0.002)
    >>> bool(np.max(np.abs(np.diff(y))) <= 5.0 * 0.002 + 1e-12)
    True
    """
    for name, value in (("rate", rate), ("dt", dt)):
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
            raise ConfigError(f"{name} = {value!r}: a positive number")
    u = np.asarray(command, dtype=float).ravel()
    limiter = _CommandLimiter.of(kind, float(rate), float(dt), travel)
    if limiter is None:
        return u.copy() if travel is None else np.clip(u, -travel, travel)
    return np.array([limiter.step(float(x)) for x in u])


def _nonnegative(name: str, value, *, positive: bool = False) -> None:
    """Refuse a setting that is not a finite number ``>= 0`` (``> 0`` when ``positive``)."""
    ok = (not isinstance(value, bool) and isinstance(value, (int, float))
          and np.isfinite(value) and (value > 0 if positive else value >= 0))
    if not ok:
        raise ConfigError(f"{name} = {value!r}: must be a finite number "
                          f"{'> 0' if positive else '>= 0'}")


@dataclass(frozen=True)
class SuppressionSettings:
    """The gain-ramp runs of paper Fig. 11 in a tunnel (times in the problem's time unit):
    one run per speed factor, in turbulence with noisy sensors when asked."""

    speed_factors: tuple = (1.05,)
    """Run at each of these multiples of the truth's own flutter speed (where the wing
    itself has an LCO)."""
    settle: float = 10.0
    """Open loop: the LCO develops."""
    ramp: float = 5.0
    """The controller gain rises linearly from 0 to 1."""
    hold: float = 10.0
    """Full gain."""
    release: float = 10.0
    """Open loop again, after a tap on the wing, until the LCO has returned (the RMS of the
    dominant sensor over the last ``settle / 3``, the open-loop window, above half the open
    loop's) and at most this long."""
    flap_limit: float | None = None
    """Largest flap angle of the servo (the truth's flap unit; ``None``: no limit)."""
    flap_rate_limit: float | None = None
    """Largest flap rate of the servo (flap unit per time unit; ``None``: no limit)."""
    gust_intensity: float = 0.0
    """Turbulence intensity ``σ_w / U``: the rms of the vertical gust over the airspeed
    (Dryden spectrum, :mod:`casflutter.truth._turbulence`); 0 for none.  Needs a strip-theory
    truth (the seed wing)."""
    gust_scale: float = 0.3
    """Integral scale ``L_w`` of the turbulence [m]: the Dryden filter's time constant is
    ``L_w / U``."""
    noise: float = 0.0
    """Rms of each sensor's white noise, in the sensors' unit (m/s² for accelerometers); 0 for
    none."""
    command_limiter: str = "none"
    """A software limiter of the flap command before the servo, at ``flap_rate_limit``
    (:func:`closed_loop_truth`): ``"none"``, ``"rate"`` (the flap then lags the command as a
    rate-limited servo does) or ``"phase_compensated"`` (the flap turns with the command;
    part of the controller's implementation, the identity below the limit)."""

    def __post_init__(self):
        factors = self.speed_factors
        if isinstance(factors, np.ndarray):
            factors = factors.tolist()
        if not isinstance(factors, (list, tuple)) or not factors:
            raise ConfigError(f"speed_factors = {factors!r}: give a list of multiples of the "
                              "flutter speed, e.g. [1.05, 1.2]")
        factors = finite_numbers("speed_factors", list(factors), len(factors),
                                 what="multiples of the flutter speed")
        if not all(f > 0 for f in factors):
            raise ConfigError(f"speed_factors = {list(factors)!r}: every factor must be > 0")
        object.__setattr__(self, "speed_factors", tuple(factors))
        for name in ("settle", "ramp", "hold", "release", "gust_scale"):
            _nonnegative(name, getattr(self, name), positive=True)
        for name in ("gust_intensity", "noise"):
            _nonnegative(name, getattr(self, name))
        for name in ("flap_limit", "flap_rate_limit"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool)
                                      or not isinstance(value, (int, float))
                                      or not (np.isfinite(value) and value > 0)):
                raise ConfigError(f"{name} = {value!r}: a positive number (or leave it out "
                                  "for no limit)")
        _CommandLimiter.of(self.command_limiter, self.flap_rate_limit, 1.0)   # checked


@dataclass(frozen=True)
class SuppressionResult:
    """Outcome of :func:`suppression_run`.

    Attributes
    ----------
    V : float
        Speed index of the run.
    simulation : TruthLoopSimulation
        The closed-loop record.
    attenuation_percent : float or None
        ``100 (1 - rms_closed / rms_open)`` of the dominant sensor (``None`` when the open
        loop is at rest).
    open_loop_rms, closed_loop_rms, released_rms : tuple of float
        RMS per sensor over the last third of the settling phase, over the last third of the
        hold, and over the last ``settle / 3`` of the release (the record's end).
    lco_returns : bool
        After the release the dominant sensor climbs back above half its open-loop RMS (over
        a window as long as the open loop's); the run ends there.
    open_loop_amplitude : tuple of float
        Peak ``|zm|`` per sensor over the last third of the settling phase, just before the
        ramp: the amplitude of the LCO the controller is switched on against.
    closed_loop_amplitude : tuple of float
        Peak ``|zm|`` per sensor over the last third of the hold.
    started_from_lco : bool
        Whether the run started from a given (established) LCO state rather than from a
        deflected mode.
    dominant_sensor : int
        The sensor with the largest open-loop RMS.
    speed_factor : float or None
        ``V`` over the truth's flutter speed.
    flap_peak, flap_rate_peak : float or None
        Largest ``|v|`` and ``|v'|`` while the controller is engaged (ramp and hold).
    flap_saturated_percent, flap_rate_saturated_percent : float or None
        Share of the hold [%] during which the flap is at its travel limit and its rate at
        the rate limit (``None`` where the servo has no such limit).  Near 100 % the servo's
        authority, not the controller's gain, sets what is left of the LCO: the flap is then
        a triangle wave lagging the command, whatever the controller asks.
    gust_rms : float
        Rms of the gust velocity of the run [m/s] (0 without turbulence).
    """

    __repr__ = result_repr

    V: float
    simulation: TruthLoopSimulation
    attenuation_percent: float | None
    open_loop_rms: tuple
    closed_loop_rms: tuple
    released_rms: tuple
    lco_returns: bool
    dominant_sensor: int
    open_loop_amplitude: tuple = ()
    closed_loop_amplitude: tuple = ()
    started_from_lco: bool = False
    speed_factor: float | None = None
    flap_peak: float | None = None
    flap_rate_peak: float | None = None
    gust_rms: float = 0.0
    flap_saturated_percent: float | None = None
    flap_rate_saturated_percent: float | None = None

    def record(self) -> dict:
        """The run as plain numbers (``summary.json`` → ``suppression.runs``).

        Returns
        -------
        dict
            ``speed_factor``, ``V``, ``attenuation_percent``, ``open_loop_rms``,
            ``closed_loop_rms`` (per sensor), ``dominant_sensor``, ``flap_peak``,
            ``flap_rate_peak``, ``flap_saturated_percent``, ``flap_rate_saturated_percent``,
            ``lco_returns``, ``started_from_lco``, ``gust_rms``.
        """
        return {"speed_factor": self.speed_factor, "V": self.V,
                "attenuation_percent": self.attenuation_percent,
                "open_loop_rms": list(self.open_loop_rms),
                "closed_loop_rms": list(self.closed_loop_rms),
                "dominant_sensor": self.dominant_sensor, "flap_peak": self.flap_peak,
                "flap_rate_peak": self.flap_rate_peak,
                "flap_saturated_percent": self.flap_saturated_percent,
                "flap_rate_saturated_percent": self.flap_rate_saturated_percent,
                "lco_returns": self.lco_returns,
                "started_from_lco": self.started_from_lco, "gust_rms": self.gust_rms}


def suppression_run(truth, K: control.StateSpace, V_flutter: float,
                    settings: SuppressionSettings | None = None, *, dt: float, mode: int,
                    deflection: float, sensor_rows=None, sensor: str = "acceleration",
                    x0=None, speed_factor: float | None = None,
                    seed=0) -> SuppressionResult:
    """Paper Fig. 11 on the truth: the LCO develops, the gain ramps 0 -> 1, holds, is released.

    Started from ``x0``, the end state of a simulation in which the truth's LCO has
    converged (:attr:`TruthLco.final_state`), the controller is switched on against the
    established LCO, as in the wind tunnel; without it the run starts from a deflected mode
    and the LCO must develop during ``settle``.  The tunnel's turbulence and the sensors'
    noise of ``settings`` act throughout (:func:`~casflutter.truth.tunnel_disturbances`,
    drawn from ``seed``), and the flap goes through the servo with its limits.

    The attenuation compares the RMS of the dominant sensor over the last third of the
    hold with its RMS over the last third of the settling phase (open-loop LCO);
    ``lco_returns`` checks that after the release (the wing is tapped with the initial
    deflection at that moment) the RMS of the dominant sensor over a window as long as the
    open loop's climbs back above half the open-loop RMS; the run ends as soon as it does
    (``settings.release`` is the longest release).

    Parameters
    ----------
    truth : AeroelasticTruth
        The nonlinear simulator (:func:`closed_loop_truth` runs it with the flap servo).
    K : control.StateSpace
        Controller from the sensors to the flap command (``v_c = +K zm``).
    V_flutter : float
        The truth's flutter speed index; the run is at ``speed_factor`` times it.
    settings : SuppressionSettings, optional
        Durations, servo limits, turbulence and noise.
    dt : float
        Sample time of the loop.
    mode : int
        0-based mode deflected at the start and at the release.
    deflection : float
        Its deflection.
    sensor_rows : array_like, optional
        Sensor rows ``Hs`` (default: the truth's own).
    sensor : {"acceleration", "displacement"}
        What the sensors read (:func:`closed_loop_truth`).
    x0 : array_like, optional
        Full truth state to start from (an established LCO at this speed).
    speed_factor : float, optional
        Default: the first of ``settings.speed_factors``.
    seed : int or sequence of int
        Seed of the turbulence and the noise (``numpy.random.default_rng``).

    Returns
    -------
    SuppressionResult

    Raises
    ------
    CasflutterError
        The closed-loop simulation blew up.

    See Also
    --------
    suppression_runs : one run per speed factor, each from the truth's established LCO.
    closed_loop_truth : the closed-loop simulation it runs.
    truth_lco : the established LCO it starts from.

    Examples
    --------
    A controller ``K`` from :func:`synthesize` (through :meth:`AeroelasticLFT.physical_controller`)
    on the seed wing, started from the truth's converged LCO at 1.05 times the flutter speed
    (a run of a minute; :func:`run` does the same from a configuration):

    >>> lco = cf.truth_lco(truth, 1.05 * Vf, 20.0, mode=1, deflection=0.01, dt=0.002)  # doctest: +SKIP
    >>> sup = cf.suppression_run(truth, K, Vf, dt=0.002, mode=1, deflection=0.01,
    ...                          x0=lco.final_state, speed_factor=1.05)      # doctest: +SKIP
    >>> sup.attenuation_percent, sup.lco_returns                           # doctest: +SKIP
    """
    sp = settings or SuppressionSettings()
    factor = float(sp.speed_factors[0] if speed_factor is None else speed_factor)
    V = V_flutter * factor
    T = sp.settle + sp.ramp + sp.hold + sp.release
    t = np.arange(0.0, T, dt)
    g = gain_schedule(sp.settle, sp.ramp, sp.hold)
    t_release = sp.settle + sp.ramp + sp.hold
    n_sensors = _sensor_rows(truth, sensor_rows).shape[0]
    w, noise, gust = tunnel_disturbances(truth, V, t.size, dt, gust_intensity=sp.gust_intensity,
                                         gust_scale=sp.gust_scale, noise=sp.noise,
                                         n_sensors=n_sensors, seed=seed)
    start = truth.displaced_state(mode, deflection) if x0 is None else x0
    sim = closed_loop_truth(truth, K, V, t, start, g,
                            kick=(t_release, mode, deflection), sensor_rows=sensor_rows,
                            sensor=sensor, flap_limit=sp.flap_limit,
                            flap_rate_limit=sp.flap_rate_limit,
                            command_limiter=sp.command_limiter,
                            disturbance=w if sp.gust_intensity > 0 else None,
                            sensor_noise=noise if sp.noise > 0 else None,
                            stop=_lco_returned(t, sp))
    if not np.all(np.isfinite(sim.zm)):
        raise CasflutterError(f"the closed-loop truth simulation at V = {V:.4f} blew up")
    return _suppression_result(float(V), sim, sp, started_from_lco=x0 is not None,
                               speed_factor=factor,
                               gust_rms=float(np.sqrt(np.mean(gust[:sim.timepts.size] ** 2))))


def _lco_returned(t, sp: SuppressionSettings) -> Callable[[int, np.ndarray], bool]:
    """``stop(k, zm)`` of a suppression run: after the release, the RMS of the dominant
    sensor over the last ``settle / 3`` (as many samples as the open-loop window) is above
    half its open-loop RMS."""
    open_window = (t >= sp.settle * 2 / 3) & (t < sp.settle)
    m = int(open_window.sum())
    k_release = int(np.searchsorted(t, sp.settle + sp.ramp + sp.hold))
    half = {}

    def returned(k: int, zm: np.ndarray) -> bool:
        if m == 0 or k < k_release + m - 1:
            return False
        if not half:      # the open loop's dominant sensor and half its RMS, once
            open_rms = np.sqrt(np.mean(zm[open_window] ** 2, axis=0))
            half["sensor"] = int(np.argmax(open_rms))
            half["rms"] = 0.5 * float(open_rms[half["sensor"]])
        last = zm[k - m + 1:k + 1, half["sensor"]]
        return bool(np.sqrt(np.mean(last ** 2)) > half["rms"])

    return returned


def _suppression_result(V: float, sim: TruthLoopSimulation, sp: SuppressionSettings,
                        started_from_lco: bool, speed_factor: float | None = None,
                        gust_rms: float = 0.0) -> SuppressionResult:
    """The RMS and peaks of each phase of a suppression run, the flap's peaks while the
    controller is engaged, and the attenuation of the dominant sensor (see
    :func:`suppression_run`)."""
    zm, t = sim.zm, sim.timepts
    t_full = sp.settle + sp.ramp
    t_release = t_full + sp.hold

    def window(a, b):
        return (t >= a) & (t < b)

    def rms(a, b):
        return np.sqrt(np.mean(zm[window(a, b)] ** 2, axis=0))

    def peak(a, b):
        return np.max(np.abs(zm[window(a, b)]), axis=0)

    open_rms = rms(sp.settle * 2 / 3, sp.settle)
    dom = int(np.argmax(open_rms))
    closed_rms = rms(t_full + sp.hold * 2 / 3, t_release)
    m = int(window(sp.settle * 2 / 3, sp.settle).sum())   # the open-loop window's samples
    released = zm[t >= t_release]
    after = np.sqrt(np.mean(released[-m:] ** 2, axis=0))
    att = 100.0 * (1.0 - closed_rms[dom] / open_rms[dom]) if open_rms[dom] > 0 else None
    engaged = window(sp.settle, t_release)
    hold = window(t_full, t_release)

    def at_limit(x, limit):
        # the servo stops its angle and its rate exactly at the limits (_FlapServo)
        if limit is None or not hold.any():
            return None
        return float(100.0 * np.mean(np.abs(x[hold]) >= limit * (1.0 - 1e-6)))

    return SuppressionResult(V=V, simulation=sim,
                             attenuation_percent=None if att is None else float(att),
                             open_loop_rms=tuple(map(float, open_rms)),
                             closed_loop_rms=tuple(map(float, closed_rms)),
                             released_rms=tuple(map(float, after)),
                             lco_returns=bool(after[dom] > 0.5 * open_rms[dom]),
                             dominant_sensor=dom,
                             open_loop_amplitude=tuple(map(float, peak(sp.settle * 2 / 3,
                                                                       sp.settle))),
                             closed_loop_amplitude=tuple(map(float, peak(
                                 t_full + sp.hold * 2 / 3, t_release))),
                             started_from_lco=started_from_lco, speed_factor=speed_factor,
                             flap_peak=float(np.max(np.abs(sim.v[engaged]))),
                             flap_rate_peak=float(np.max(np.abs(sim.v_rate[engaged]))),
                             gust_rms=gust_rms,
                             flap_saturated_percent=at_limit(sim.v, sp.flap_limit),
                             flap_rate_saturated_percent=at_limit(sim.v_rate,
                                                                  sp.flap_rate_limit))


def suppression_runs(truth, K: control.StateSpace, V_flutter: float,
                     settings: SuppressionSettings | None = None, *, dt: float, mode: int,
                     deflection: float, lco_duration: float, sensor_rows=None,
                     sensor: str = "acceleration", seed: int = 0,
                     lcos=None, workers: int = 0) -> tuple[SuppressionResult, ...]:
    """One :func:`suppression_run` per speed factor of ``settings``, each from the truth's
    established LCO at that speed.

    The LCO is established by :func:`~casflutter.truth.truth_lco` (the truth released from
    a deflected mode and continued while it still grows) unless ``lcos`` holds that run;
    where the truth has no LCO the run starts from the deflected mode
    (``started_from_lco`` False).  Run ``k`` draws its turbulence and noise from the seed
    ``(seed, k)``: one seed gives the same runs, whichever process computes them.

    Parameters
    ----------
    truth, K, V_flutter, settings, dt, mode, deflection, sensor_rows, sensor :
        As :func:`suppression_run`.
    lco_duration : float
        Length of each simulation that establishes the LCO.
    seed : int
        The runs' seed.
    lcos : mapping of float to TruthLco, optional
        The truth's runs of :func:`~casflutter.truth.truth_lco` by speed factor, where
        already computed (e.g. by an LCO study at the same speeds).
    workers : int
        Processes for the runs (:func:`casflutter._processes.map_in_processes`): 0, one per
        speed up to the machine's cores; 1, every run in this process.

    Returns
    -------
    tuple of SuppressionResult
        In the order of ``settings.speed_factors``.
    """
    sp = settings or SuppressionSettings()
    if isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 0:
        raise ConfigError(f"workers = {workers!r}: an integer >= 0 (0: one process per speed "
                          "up to the machine's cores, 1: this process)")
    known = {round(float(f), 9): lco for f, lco in (lcos or {}).items()}
    K_abcd = tuple(np.atleast_2d(np.asarray(M, dtype=float)) for M in (K.A, K.B, K.C, K.D))
    jobs = [_SuppressionJob(truth, K_abcd, V_flutter, sp, dt, mode, deflection, lco_duration,
                            sensor_rows, sensor, float(factor), (int(seed), k),
                            known.get(round(factor, 9)))
            for k, factor in enumerate(sp.speed_factors)]
    return tuple(map_in_processes(_run_job, jobs, int(workers)))


@dataclass(frozen=True)
class _SuppressionJob:
    """Everything one run of :func:`suppression_runs` depends on (picklable: the controller
    as its ``(A, B, C, D)``)."""

    truth: object
    K: tuple
    V_flutter: float
    settings: SuppressionSettings
    dt: float
    mode: int
    deflection: float
    lco_duration: float
    sensor_rows: object
    sensor: str
    speed_factor: float
    seed: tuple
    lco: object


def _run_job(job: _SuppressionJob) -> SuppressionResult:
    """One run: the truth's LCO at the speed (unless given), then the suppression run."""
    with single_threaded():     # the same numbers in a worker as in the parent
        lco = job.lco
        if lco is None:
            lco = truth_lco(job.truth, job.V_flutter * job.speed_factor, job.lco_duration,
                            job.mode, job.deflection, dt=job.dt, sensor_rows=job.sensor_rows,
                            sensor=job.sensor)
        x0 = lco.final_state if lco.kind == "lco" else None
        return suppression_run(job.truth, control.ss(*job.K), job.V_flutter, job.settings,
                               dt=job.dt, mode=job.mode, deflection=job.deflection,
                               sensor_rows=job.sensor_rows, sensor=job.sensor, x0=x0,
                               speed_factor=job.speed_factor, seed=job.seed)


def truth_loop_matrix(truth, K: control.StateSpace, V: float, *, actuator_omega: float,
                      actuator_zeta: float = 0.7, sensor_rows=None) -> np.ndarray:
    """State matrix of the truth's linear loop with the flap command ``v_c = K zm``.

    The truth's :meth:`statespace` with the flap behind the actuator, read by displacement
    sensors ``zm = Hs u``, closed by ``K`` from ``zm`` to ``v_c`` (positive feedback, the
    ``control.hinfsyn`` convention of eq. 14).  States ``[x_truth, x_actuator, x_K]``.

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator, linearised at ``V`` (its :meth:`statespace` with the actuator).
    K : control.StateSpace
        Controller from the sensors to the flap command.
    V : float
        Speed index.
    actuator_omega, actuator_zeta : float
        The flap actuator.
    sensor_rows : array_like, optional
        ``Hs`` (default: the truth's own).

    Returns
    -------
    ndarray
    """
    G = truth.statespace(V, actuator_omega=actuator_omega, actuator_zeta=actuator_zeta)
    A, B = np.asarray(G.A), np.asarray(G.B)[:, :1]
    Hs = _sensor_rows(truth, sensor_rows)
    C = np.zeros((Hs.shape[0], A.shape[0]))
    C[:, :truth.n_modes] = Hs
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in
                      (K.A, K.B, K.C, K.D))
    if K.nstates == 0:
        return A + B @ Dk @ C
    return np.block([[A + B @ Dk @ C, B @ Ck], [Bk @ C, Ak]])


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

    __repr__ = result_repr

    V: np.ndarray
    open_abscissa: np.ndarray
    closed_abscissa: np.ndarray
    stable_V: tuple | None


def truth_loop_sweep(truth, K: control.StateSpace, V_flutter: float, V, *,
                     actuator_omega: float, actuator_zeta: float = 0.7,
                     sensor_rows=None) -> TruthLoopSweep:
    """Open- and closed-loop spectral abscissae of the truth's linear loop on a grid of V.

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator.
    K : control.StateSpace
        Controller from the (displacement) sensors to the flap command.
    V_flutter : float
        The truth's flutter speed index: the stable interval reported is the one around it.
    V : array_like
        Increasing speed indices.
    actuator_omega, actuator_zeta, sensor_rows :
        The actuator and the sensor rows, as in :func:`truth_loop_matrix`.

    Returns
    -------
    TruthLoopSweep
    """
    kw = dict(actuator_omega=actuator_omega, actuator_zeta=actuator_zeta,
              sensor_rows=sensor_rows)
    V = np.asarray(V, dtype=float)
    ol = np.array([spectral_abscissa(truth.state_matrix(v)) for v in V])

    def cl_fun(v):
        return spectral_abscissa(truth_loop_matrix(truth, K, v, **kw))

    cl = np.array([cl_fun(v) for v in V])
    i = int(np.argmin(np.abs(V - V_flutter)))
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
