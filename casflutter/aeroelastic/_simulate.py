"""Nonlinear aeroelastic loop: the discrete HWL ROM in feedback with the continuous Σs.

Coupling (sampled-data, exact for the structure)
-----------------------------------------------
The ROM is discrete with one sample per step ``h`` (its sample time ``dt``, or the speed's
own step below); Σs (eq. 6-7) is continuous.  At each sample ``t_k = k h``:

1. the modal displacements ``u_k = Cs x_s(t_k)`` are sampled;
2. the sensors are read, ``zm_k = Hx x_s(t_k) + Hf F(t_k^-)`` — for accelerometers the
   forcing term is the value of the hold just before ``t_k`` (left limit), so the
   measurement never depends on the flap command it produces (no algebraic loop);
3. the controller (if any) gives ``v_k = v_ext(t_k) + g(t_k) · K_d(zm)_k``;
4. the ROM gives ``y_k = rom.step(y_hist, u_hist, v_hist)`` (rows: time k, k−1, …);
5. the structural forcing ``F_k = V² y_k + w(t_k)`` is held on ``[t_k, t_{k+1})`` and Σs is
   propagated exactly (:func:`structure_step`):

   - ``hold = "zoh"`` (zero-order hold, the loose coupling of a CFD time march):
     ``F(t) = F_k``, ``x_s(t_{k+1}) = Ad x_s(t_k) + B0 F_k``;
   - ``hold = "foh"`` (predictive first-order hold): ``F(t) = F_k + (t − t_k)/h ·
     (F_k − F_{k−1})``, ``x_s(t_{k+1}) = Ad x_s(t_k) + B0 F_k + B1 (F_k − F_{k−1})``, and
     the accelerometers' left limit is ``2 F_{k−1} − F_{k−2}``.

   A zero-order hold delays the force by half a step on average, a phase lag ``ω h / 2``
   that the lightly damped flutter mode feels: on the seed wing it moves the sampled loop's
   flutter by several per cent from that of the continuous ΣAE of the same ROM (eq. 8).  The
   first-order hold extrapolates the force's slope, cancelling the lag to first order, and
   the sampled loop then flutters within a few tenths of a per cent of ΣAE.

The controller ``K`` (continuous ``control.StateSpace``, inputs zm, output v) is
discretised with ZOH at the same ``dt``, consistent with the held flap command; its
state evolves whatever the gain ``g(t)`` (paper Fig. 11 ramps g from 0 to 1).

Speed-following time step (reduced frequency)
---------------------------------------------
The ROM is identified at ``V0`` from records sampled every ``dt`` seconds.  Linear unsteady
aerodynamics depend on the reduced frequency ``k = ω b / U``: they live in reduced time
``s = U t / b``, and one sample of the identified recursion spans ``U0 dt / b`` of it.  At
another speed the same recursion describes the same flow when each of its samples spans the
same reduced time, i.e. ``dt · V0 / V`` seconds.  With ``convective_V0 = V0`` the loop is
stepped so: the ROM advances one sample per ``h = dt V0 / V``, the structure is propagated
exactly over ``h`` (:func:`structure_step`) and the forces still scale with ``V²``.  This is
the discrete counterpart of Σf's dynamics scaled by ``V / V0``
(:class:`~casflutter.aeroelastic.AeroelasticSystem` ``convective_V0``): the Tustin image of
the recursion at step ``h`` is Σf with ``Af, Bf, bf`` times ``V / V0``.  Without it (the
paper's eq. 8) the recursion runs at ``dt`` at every speed and its time scale stays that of
``V0``.

The records are classified (decay, LCO, divergence) and the LCO measured by
:func:`casflutter.data.analyze_response`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import casadi as ca
import control
import numpy as np

from .._format import result_repr
from ..data import ResponseAnalysis, analyze_response
from ..errors import ConfigError, DimensionError
from ..structure import ModalStructure

__all__ = ["LoopSimulation", "simulate_loop", "structure_step", "loop_sample_time",
           "check_convective_V0", "check_hold", "HOLDS"]


@dataclass(frozen=True)
class LoopSimulation:
    """Record of :func:`simulate_loop` (samples at ``t_k``).

    Attributes
    ----------
    timepts : ndarray (n,)
    xs : ndarray (n, 2N)
        Structural states.
    u, y : ndarray (n, N)
        Modal displacements and generalised forces.
    zm : ndarray (n, m)
        Sensor outputs (see module docstring).
    v : ndarray (n,)
        Flap command.
    w : ndarray (n, N)
        Disturbance.
    gain : ndarray (n,)
        Controller gain schedule g(t_k) (zeros without controller).
    V : float
        Speed index.
    dt : float
        The loop's step: the ROM's sample time, or ``dt · V0 / V`` when it follows the speed.
    stopped_early : bool
        True when the record blew up (non-finite or above ``blowup``) and was truncated.
    modes : ResponseAnalysis
        Classification / LCO analysis of the modal displacements.
    sensors : ResponseAnalysis or None
        The same for the sensors.
    """

    __repr__ = result_repr

    timepts: np.ndarray
    xs: np.ndarray
    u: np.ndarray
    y: np.ndarray
    zm: np.ndarray
    v: np.ndarray
    w: np.ndarray
    gain: np.ndarray
    V: float
    dt: float
    stopped_early: bool
    modes: ResponseAnalysis
    sensors: ResponseAnalysis | None

    @property
    def kind(self) -> str:
        """``"decay"``, ``"lco"`` or ``"divergence"`` (from the modal displacements)."""
        return self.modes.kind


def structure_step(structure: ModalStructure) -> ca.Function:
    """The exact step of Σs (eq. 7) over a step ``h`` with a force that is constant or ramps.

    Over ``[t_k, t_k + h)`` with the force ``F(t) = F0 + (t − t_k)/h · F1``,
    ``x(t_k + h) = Ad x(t_k) + B0 F0 + B1 F1``.  Mode by mode, ``ü + 2σu̇ + ω² u = α F``
    with ``σ = ζω``, ``κ = ω²(1 − ζ²)``, ``C(h) = cos(√κ h)``, ``S(h) = sin(√κ h)/√κ`` (their
    hyperbolic forms for ``κ < 0``; ``1`` and ``h`` for ``κ = 0``):

    .. math:: A_d = e^{-σh} \\begin{bmatrix} C + σS & S \\\\ -ω^2 S & C - σS \\end{bmatrix},
              \\quad B_0 = (I - A_d) \\begin{bmatrix} α/ω^2 \\\\ 0 \\end{bmatrix},
              \\quad B_1 = (I - A_d) \\begin{bmatrix} b \\\\ a \\end{bmatrix}
              + \\begin{bmatrix} a h \\\\ 0 \\end{bmatrix},

    ``a = α / (ω² h)``, ``b = −2σ α / (ω⁴ h)`` (the ramp's particular solution ``a t + b``),
    i.e. ``[Ad, B0, B1]`` is ``expm`` of the loop with a held and a ramping input, in closed
    form; ``h`` may be symbolic (the speed-following loop map differentiates it in V).

    Parameters
    ----------
    structure : ModalStructure
        Σs.

    Returns
    -------
    casadi.Function
        ``(h) -> (Ad, B0, B1)`` of shapes ``(2N, 2N)``, ``(2N, N)``, ``(2N, N)``.
    """
    N = structure.n_modes
    h = ca.SX.sym("h")
    Ad = ca.SX.zeros(2 * N, 2 * N)
    B0 = ca.SX.zeros(2 * N, N)
    B1 = ca.SX.zeros(2 * N, N)
    alpha = float(structure.alpha)
    for i, (w, z) in enumerate(zip(structure.omega, structure.zeta)):
        w, z = float(w), float(z)
        sig, kap = z * w, w * w * (1.0 - z * z)
        if kap > 0:
            r = np.sqrt(kap)
            C, S = ca.cos(r * h), ca.sin(r * h) / r
        elif kap < 0:
            r = np.sqrt(-kap)
            C, S = ca.cosh(r * h), ca.sinh(r * h) / r
        else:
            C, S = 1.0, h
        e = ca.exp(-sig * h)
        i0, i1 = 2 * i, 2 * i + 1
        A = ca.vertcat(ca.horzcat(e * (C + sig * S), e * S),
                       ca.horzcat(-w * w * e * S, e * (C - sig * S)))
        Ad[i0:i1 + 1, i0:i1 + 1] = A
        a, b = alpha / (w * w * h), -2.0 * sig * alpha / (w ** 4 * h)
        B0[i0:i1 + 1, i] = ca.mtimes(ca.SX.eye(2) - A, ca.vertcat(alpha / (w * w), 0.0))
        B1[i0:i1 + 1, i] = ca.mtimes(ca.SX.eye(2) - A, ca.vertcat(b, a)) + ca.vertcat(a * h, 0.0)
    return ca.Function("structure_step", [h], [Ad, B0, B1], ["h"], ["Ad", "B0", "B1"])


def loop_sample_time(dt: float, V, convective_V0: float | None):
    """The physical duration of one ROM sample in the loop at speed index V.

    Parameters
    ----------
    dt : float
        The ROM's sample time (that of its records at ``convective_V0``).
    V : float or casadi.SX
        Speed index.
    convective_V0 : float or None
        The identification speed index: the step is ``dt · V0 / V`` (module docstring);
        ``None``: ``dt`` at every speed (eq. 8 as the paper writes it).

    Returns
    -------
    float or casadi.SX
    """
    return dt if convective_V0 is None else dt * float(convective_V0) / V


def check_convective_V0(convective_V0, V=None) -> None:
    """Refuse a speed-following reference speed (and speed) that is not finite and > 0.

    Parameters
    ----------
    convective_V0 : float or None
        The identification speed index (``None``: eq. 8's frozen time scale).
    V : float, optional
        The speed index the loop is stepped at.

    Raises
    ------
    ConfigError
    """
    if convective_V0 is None:
        return
    if (isinstance(convective_V0, bool) or not isinstance(convective_V0, (int, float, np.floating))
            or not (np.isfinite(convective_V0) and convective_V0 > 0)):
        raise ConfigError(f"convective_V0 = {convective_V0!r}: the ROM's identification speed "
                          "index (> 0), or None for eq. 8's frozen time scale")
    if V is not None and not (np.isfinite(V) and V > 0):
        raise ConfigError(f"V = {V!r}: the speed-following loop (convective_V0 set) is "
                          "stepped at dt V0 / V and needs a speed index > 0")


#: the holds of the force between samples (module docstring)
HOLDS = ("zoh", "foh")


def check_hold(hold) -> None:
    """Refuse a hold that is not one of :data:`HOLDS`.

    Parameters
    ----------
    hold : str
        ``"zoh"`` or ``"foh"``.

    Raises
    ------
    ConfigError
    """
    if hold not in HOLDS:
        raise ConfigError(f"hold = {hold!r}: use 'zoh' (zero-order hold, the force held over "
                          "each step) or 'foh' (predictive first-order hold)")


def _signal(sig, n: int, dt: float, width: int | None, name: str) -> np.ndarray:
    """Sample a signal given as None, callable t -> value, or array (n, width)/(n,)."""
    shape = (n,) if width is None else (n, width)
    if sig is None:
        return np.zeros(shape)
    if callable(sig):
        out = np.array([np.asarray(sig(k * dt), dtype=float) for k in range(n)])
    else:
        out = np.asarray(sig, dtype=float)
    out = out.reshape(n, -1) if width is not None else out.reshape(-1)
    if out.shape != shape:
        raise DimensionError(f"{name} must have shape {shape} (one value per ROM sample), got {out.shape}")
    return out


def _check_rom(rom, n_modes: int) -> None:
    for attr in ("step", "n_modes", "max_lag", "dt"):
        if not hasattr(rom, attr):
            raise ConfigError(f"the ROM lacks '{attr}'; it must implement step(y_hist, u_hist, "
                              "v_hist) and the attributes n_modes, max_lag, dt")
    if rom.n_modes != n_modes:
        raise DimensionError(f"the ROM has n_modes={rom.n_modes} but Σs has {n_modes} modes; "
                             "they must be equal")
    if not rom.dt > 0:
        raise ConfigError(f"the ROM must be discrete with dt > 0, got dt={rom.dt}")


def simulate_loop(rom, structure: ModalStructure, V: float, n_steps: int, *, xs0=None,
                  w=None, v=None, controller: control.StateSpace | None = None,
                  gain: Callable[[float], float] | None = None, window: float = 0.3,
                  tol: float = 0.05, blowup: float = 1e6,
                  convective_V0: float | None = None, hold: str = "zoh") -> LoopSimulation:
    """Simulate the nonlinear ROM in feedback with Σs at speed index V (module docstring).

    Parameters
    ----------
    rom : object
        Discrete ROM with ``step(y_hist, u_hist, v_hist) -> y_k``, ``n_modes``,
        ``max_lag``, ``dt`` (the HWL ROM of ``casflutter.ident`` or any such model).
    structure : ModalStructure
        Σs (eq. 6-7).
    V : float
        Speed index (forcing ``V² y``).
    n_steps : int
        Number of ROM samples.
    xs0 : ModalState or array_like (2N,), optional
        Initial structural state: a :class:`~casflutter.structure.ModalState` (e.g.
        ``structure.displaced_state(mode, deflection)``) or Σs's own state
        ``[u_1, u̇_1, ...]`` (zero by default).  The ROM's past inputs are the initial
        displacements held constant (the wing is held deflected and released at t = 0); its
        past outputs and flap inputs are zero.
    w : None, callable t -> (N,), or array (n_steps, N)
        Disturbance added to ``V² y`` (eq. 7).
    v : None, callable t -> float, or array (n_steps,)
        External flap command.
    controller : control.StateSpace, optional
        Continuous K with ``n_sensors`` inputs and one output; closes ``v = g(t) K zm``.
    gain : callable t -> float, optional
        Gain schedule g(t) (default 1 when a controller is given).
    window, tol :
        Classification settings, see :func:`analyze_response`.
    blowup : float
        ``|u|`` above which the run is stopped and classified as divergence.
    convective_V0 : float, optional
        The ROM's identification speed index: step the loop at ``rom.dt · V0 / V`` (the
        aerodynamic time scale follows the reduced frequency, module docstring); the
        samples of ``w``, ``v``, the controller's discretisation and the record are on that
        step.  Default: ``rom.dt`` at every speed (eq. 8).
    hold : {"zoh", "foh"}
        How the force is held between samples (module docstring): zero-order (default) or
        predictive first-order.

    Returns
    -------
    LoopSimulation

    See Also
    --------
    find_flutter : the speed above which the loop diverges or settles on an LCO.
    rom_lco_branch : the ROM loop's LCO branch by continuation.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth, rom = cf.load_problem("typical_section"), cf.example_rom()
    >>> structure = truth.modal_structure()
    >>> sim = cf.simulate_loop(rom, structure, 1.5, 500, xs0=structure.displaced_state(1, 0.01))
    >>> sim.zm.shape, bool(abs(sim.zm[-50:]).max() < 0.1 * abs(sim.zm[:50]).max())
    ((500, 2), True)
    """
    s = structure
    N, m = s.n_modes, s.n_sensors
    _check_rom(rom, N)
    if n_steps < 2:
        raise ConfigError(f"n_steps must be >= 2, got {n_steps}")
    check_convective_V0(convective_V0, V)
    check_hold(hold)
    dt = float(loop_sample_time(float(rom.dt), float(V), convective_V0))
    W = _signal(w, n_steps, dt, N, "w")
    Vext = _signal(v, n_steps, dt, None, "v")
    Kd = None if controller is None else _discrete_controller(controller, m, dt)
    g = (lambda t: 1.0) if gain is None else gain
    xs = s.layout.initial(xs0, s.n_states)
    rec, stopped = _run_loop(rom, s, float(V), xs, W, Vext, Kd, g, n_steps, blowup, dt, hold)
    n = len(rec["u"])
    tpts = dt * np.arange(n)
    U = np.asarray(rec["u"])
    Z = np.asarray(rec["zm"]).reshape(n, m)
    modes = analyze_response(tpts, U, window=window, tol=tol, blowup=blowup)
    sens = analyze_response(tpts, Z, window=window, tol=tol, blowup=np.inf) if m else None
    if stopped:
        modes = ResponseAnalysis("divergence", modes.growth_rate, modes.amplitude, modes.frequency_hz,
                                 modes.omega, modes.dominant, modes.spectrum_freq_hz, modes.spectrum,
                                 modes.window)
    return LoopSimulation(tpts, np.asarray(rec["xs"]), U, np.asarray(rec["y"]), Z,
                          np.asarray(rec["v"], dtype=float), W[:n], np.asarray(rec["g"], dtype=float),
                          float(V), dt, stopped, modes, sens)


def _discrete_controller(controller: control.StateSpace, m: int, dt: float):
    """The controller's ``(A, B, C, D)`` sampled with a zero-order hold at the loop's step
    ``dt`` (as given when it is already discrete at that ``dt``)."""
    if controller.ninputs != m or controller.noutputs != 1:
        raise DimensionError(f"the controller has {controller.ninputs} inputs and "
                             f"{controller.noutputs} outputs; it needs {m} inputs (sensors) and 1 output (flap)")
    if controller.dt not in (0, None) and not np.isclose(controller.dt, dt):
        raise ConfigError(f"the discrete controller has dt={controller.dt} but the loop is "
                          f"stepped at dt={dt}; give a continuous controller or one sampled "
                          "at the loop's step")
    Kd = control.sample_system(controller, dt, method="zoh") if controller.dt == 0 else controller
    return tuple(np.atleast_2d(np.asarray(M, dtype=float)) for M in (Kd.A, Kd.B, Kd.C, Kd.D))


def _run_loop(rom, s: ModalStructure, V: float, xs, W, Vext, Kd, g, n_steps: int,
              blowup: float, dt: float, hold: str):
    """The sample-by-sample recursion of the module docstring (steps 1-5) from the
    structural state ``xs``, stepped at ``dt`` with the force held as ``hold`` says: the
    records per key and whether the run blew up."""
    N, L = s.n_modes, int(rom.max_lag)
    V2 = V ** 2
    nx = s.n_states
    Ad, B0, B1 = (np.asarray(M, dtype=float) for M in structure_step(s)(dt))
    foh = hold == "foh"
    Hx, Hf = s.sensor_matrices()
    Cs = s.Cs
    if Kd is not None:
        Ak, Bk, Ck, Dk = Kd
        xk = np.zeros(Ak.shape[0])
    y_hist, v_hist = np.zeros((L + 1, N)), np.zeros(L + 1)
    u_hist = np.tile(Cs @ xs, (L + 1, 1))  # held at the initial deflection before release
    F_prev, F_prev2 = np.zeros(N), np.zeros(N)    # F_{k-1}, F_{k-2}
    rec = {k: [] for k in ("xs", "u", "y", "zm", "v", "g")}
    for k in range(n_steps):
        t = k * dt
        uk = Cs @ xs
        zk = Hx @ xs + Hf @ (2.0 * F_prev - F_prev2 if foh else F_prev)
        vk = Vext[k]
        gk = 0.0
        if Kd is not None:
            gk = float(g(t))
            vk = vk + gk * float((Ck @ xk + Dk @ zk)[0])
            xk = Ak @ xk + Bk @ zk
        u_hist[1:] = u_hist[:-1].copy()
        u_hist[0] = uk
        v_hist[1:] = v_hist[:-1].copy()
        v_hist[0] = vk
        y_hist[1:] = y_hist[:-1].copy()
        y_hist[0] = 0.0
        yk = np.asarray(rom.step(y_hist.copy(), u_hist.copy(), v_hist.copy()), dtype=float).reshape(N)
        y_hist[0] = yk
        for key, val in (("xs", xs), ("u", uk), ("y", yk), ("zm", zk), ("v", vk), ("g", gk)):
            rec[key].append(val)
        if not (np.all(np.isfinite(yk)) and np.all(np.abs(uk) < blowup)):
            return rec, True
        Fk = V2 * yk + W[k]
        xs = Ad @ xs + B0 @ Fk + (B1 @ (Fk - F_prev) if foh else 0.0)
        F_prev, F_prev2 = Fk, F_prev
    return rec, False
