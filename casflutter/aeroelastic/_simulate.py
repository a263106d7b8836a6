"""Nonlinear aeroelastic loop: the discrete HWL ROM in feedback with the continuous Σs.

Coupling (sampled-data, exact for the structure)
-----------------------------------------------
The ROM is discrete with sample time ``dt``; Σs (eq. 6-7) is continuous.  At each
sample ``t_k = k dt``:

1. the modal displacements ``u_k = Cs x_s(t_k)`` are sampled;
2. the sensors are read, ``zm_k = Hx x_s(t_k) + Hf F_{k-1}`` — for accelerometers the
   forcing term is the value held just before ``t_k`` (left limit), so the measurement
   never depends on the flap command it produces (no algebraic loop);
3. the controller (if any) gives ``v_k = v_ext(t_k) + g(t_k) · K_d(zm)_k``;
4. the ROM gives ``y_k = rom.step(y_hist, u_hist, v_hist)`` (rows: time k, k−1, …);
5. the structural forcing ``F_k = V² y_k + w(t_k)`` is held constant (ZOH) on
   ``[t_k, t_{k+1})`` and Σs is propagated exactly,
   ``x_s(t_{k+1}) = Ad x_s(t_k) + Bd F_k`` with ``[Ad Bd] = expm([[As, Bs], [0, 0]] dt)``.

The controller ``K`` (continuous ``control.StateSpace``, inputs zm, output v) is
discretised with ZOH at the same ``dt``, consistent with the held flap command; its
state evolves whatever the gain ``g(t)`` (paper Fig. 11 ramps g from 0 to 1).

The records are classified (decay, LCO, divergence) and the LCO measured by
:func:`casflutter.data.analyze_response`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import control
import numpy as np
from scipy.linalg import expm

from .._format import result_repr
from ..data import ResponseAnalysis, analyze_response
from ..errors import ConfigError, DimensionError
from ..structure import ModalStructure

__all__ = ["LoopSimulation", "simulate_loop"]


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
    V, dt : float
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
                  tol: float = 0.05, blowup: float = 1e6) -> LoopSimulation:
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
    dt = float(rom.dt)
    W = _signal(w, n_steps, dt, N, "w")
    Vext = _signal(v, n_steps, dt, None, "v")
    Kd = None if controller is None else _discrete_controller(controller, m, dt)
    g = (lambda t: 1.0) if gain is None else gain
    xs = s.layout.initial(xs0, s.n_states)
    rec, stopped = _run_loop(rom, s, float(V), xs, W, Vext, Kd, g, n_steps, blowup)
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
    """The controller's ``(A, B, C, D)`` sampled with a zero-order hold at the ROM's ``dt``
    (as given when it is already discrete at that ``dt``)."""
    if controller.ninputs != m or controller.noutputs != 1:
        raise DimensionError(f"the controller has {controller.ninputs} inputs and "
                             f"{controller.noutputs} outputs; it needs {m} inputs (sensors) and 1 output (flap)")
    if controller.dt not in (0, None) and not np.isclose(controller.dt, dt):
        raise ConfigError(f"the discrete controller has dt={controller.dt} but the ROM has "
                          f"dt={dt}; give a continuous controller or one sampled at the ROM's dt")
    Kd = control.sample_system(controller, dt, method="zoh") if controller.dt == 0 else controller
    return tuple(np.atleast_2d(np.asarray(M, dtype=float)) for M in (Kd.A, Kd.B, Kd.C, Kd.D))


def _run_loop(rom, s: ModalStructure, V: float, xs, W, Vext, Kd, g, n_steps: int,
              blowup: float):
    """The sample-by-sample recursion of the module docstring (steps 1-5) from the
    structural state ``xs``: the records per key and whether the run blew up."""
    N, L, dt = s.n_modes, int(rom.max_lag), float(rom.dt)
    V2 = V ** 2
    nx = s.n_states
    E = expm(np.block([[s.As, s.Bs], [np.zeros((N, nx + N))]]) * dt)
    Ad, Bd = E[:nx, :nx], E[:nx, nx:]
    Hx, Hf = s.sensor_matrices()
    Cs = s.Cs
    if Kd is not None:
        Ak, Bk, Ck, Dk = Kd
        xk = np.zeros(Ak.shape[0])
    y_hist, v_hist = np.zeros((L + 1, N)), np.zeros(L + 1)
    u_hist = np.tile(Cs @ xs, (L + 1, 1))  # held at the initial deflection before release
    F_prev = np.zeros(N)
    rec = {k: [] for k in ("xs", "u", "y", "zm", "v", "g")}
    for k in range(n_steps):
        t = k * dt
        uk = Cs @ xs
        zk = Hx @ xs + Hf @ F_prev
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
        F_prev = V2 * yk + W[k]
        xs = Ad @ xs + Bd @ F_prev
    return rec, False
