"""Truth-side simulations of the end-to-end study: LCO, flap pulses, flutter suppression."""

from __future__ import annotations

import control
import numpy as np

from ..aeroelastic import ModalStructure, analyze_response, simulate_loop
from ..errors import CasflutterError
from ._config import check_sensor_rows

__all__ = ["sensor_rows_of", "accelerometer_structure", "truth_lco", "flap_pulse_comparison",
           "suppression_run", "closed_loop_truth", "gain_schedule"]


def sensor_rows_of(truth, rows=None) -> np.ndarray:
    """The sensor rows ``Hs`` (eq. 7) of a run: ``rows`` if given, else the truth's own.

    Parameters
    ----------
    truth : AeroelasticTruth
        The problem (its ``modal_structure().sensor_rows`` are the default, for the seed
        wing the paper's §IV rows of the two tip-store accelerometers).
    rows : array_like, shape (n_sensors, N), optional
        Sensor locations in modal coordinates (``[sensors] rows`` of the run
        configuration); ``None`` or empty: the truth's rows.

    Returns
    -------
    numpy.ndarray
        ``(n_sensors, N)`` float array (a copy).

    Raises
    ------
    ConfigError
        Rows of the wrong length, non-finite entries or a row of zeros.
    """
    if rows is None or len(rows) == 0:
        return np.array(truth.modal_structure().sensor_rows, dtype=float)
    if isinstance(rows, np.ndarray):
        rows = rows.tolist()
    checked = check_sensor_rows(rows, truth.n_modes, key="sensor rows",
                                problem=getattr(truth, "name", type(truth).__name__))
    return np.array(checked, dtype=float)


def accelerometer_structure(truth, rows=None) -> ModalStructure:
    """Σs (eq. 6-7) of a truth read by accelerometers (the paper's tip-store
    accelerometers): ``zm = Hs u''`` computed from the closed loop.

    Parameters
    ----------
    truth : AeroelasticTruth
        In-vacuo ω, ζ and the flow constant α.
    rows : array_like, shape (n_sensors, N), optional
        ``Hs`` (default: the truth's own sensor rows, :func:`sensor_rows_of`).

    Returns
    -------
    ModalStructure
    """
    ms = truth.modal_structure()
    return ModalStructure(ms.omega, ms.zeta, ms.alpha, Hs=sensor_rows_of(truth, rows),
                          sensor="acceleration")


def _sensors(sim, Hs: np.ndarray, kind: str = "acceleration") -> np.ndarray:
    """``zm`` of a truth simulation: ``Hs u''`` (accelerometers), ``Hs u'`` or ``Hs u``."""
    motion = {"acceleration": sim.uddot, "velocity": sim.udot, "displacement": sim.u}
    if kind not in motion:
        raise ValueError(f"sensor kind {kind!r}: use one of {', '.join(motion)}")
    return motion[kind] @ np.asarray(Hs, dtype=float).T


def truth_lco(truth, V: float, duration: float, mode: int, deflection: float, *,
              dt: float, sensor_rows=None, max_extensions: int = 5) -> dict:
    """The truth's own response at V from a deflected ``mode`` (its LCO, if any), read by
    the accelerometers ``sensor_rows`` (default: the truth's own, :func:`sensor_rows_of`).

    Just above the Hopf point an LCO grows slowly: while the modal displacements of the last
    ``duration`` seconds are still classified as growing (a test that does not depend on
    the sensors), the simulation is continued from its final state (at most
    ``max_extensions`` times); the returned history is the last ``duration`` seconds and
    ``t_start`` says where it begins."""
    t = np.arange(0.0, duration, dt)
    x0 = np.zeros(2 * truth.n_modes)
    x0[mode] = deflection
    rows = sensor_rows_of(truth, sensor_rows)
    t_start = 0.0
    for k in range(max_extensions + 1):
        sim = truth.simulate(t, x0, V)
        growing = analyze_response(t, sim.u).kind == "divergence"
        if not growing or not np.all(np.isfinite(sim.states[-1])) or k == max_extensions:
            break
        x0, t_start = sim.states[-1], t_start + t[-1]
    zm = _sensors(sim, rows)
    an = analyze_response(t, zm)
    return {"kind": an.kind, "freq_hz": float(an.frequency_hz),
            "amplitude": [float(a) for a in an.amplitude], "timepts": t, "zm": zm,
            "analysis": an, "t_start": t_start}


def flap_pulse_comparison(truth, model, structure, V: float, *, dt: float,
                          duration: float = 4.0, amplitude: float = np.radians(2.0)) -> dict:
    """Sensor response to a sequence of finite-width flap pulses at V (paper Fig. 8):
    the nonlinear ROM in the loop with Σs against the truth, both read by the sensors of
    ``structure`` (its ``Hs`` and ``sensor`` kind)."""
    t = np.arange(0.0, duration, dt)
    v = np.zeros_like(t)
    for k, t0 in enumerate((0.2, 0.9, 1.6, 2.3)):
        w = 0.05 + 0.03 * k
        v += (-1) ** k * amplitude * np.exp(-0.5 * ((t - t0) / (0.35 * w)) ** 2)
    sim_t = truth.simulate(t, np.zeros(2 * truth.n_modes), V, v=v)
    sim_r = simulate_loop(model, structure, V, t.size, v=v)
    return {"timepts": t, "v": v, "truth_zm": _sensors(sim_t, structure.Hs, structure.sensor),
            "rom_zm": sim_r.zm}


def gain_schedule(settle: float, ramp: float, hold: float):
    """g(t): 0 for ``t < settle``, linear to 1 over ``ramp``, 1 for ``hold``, then 0."""
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
                      sensor_rows=None) -> dict:
    """Sampled-data closed loop of the nonlinear truth with the controller ``K``.

    At every sample ``t_k`` the sensors (``zm = Hs u''`` for ``sensor="acceleration"``, the
    paper's accelerometers, or ``zm = Hs u`` for ``"displacement"``) are read, the controller
    (ZOH discretisation at the sample time) updates, and the flap command
    ``v_c = g(t_k) K zm`` is held until ``t_{k+1}``; the flap follows a second-order actuator
    (``actuator_omega``, ``actuator_zeta``: our choice, the paper gives none), which supplies
    the flap rate and acceleration the aerodynamics need.  The truth is integrated by
    classical Runge--Kutta with ``substeps`` steps per sample.  ``kick = (time, mode,
    deflection)`` adds a modal deflection at that time (a tap on the wing, as the tunnel's
    turbulence would give), so that a released flutter can restart from a quiet wing.
    ``sensor_rows`` are ``Hs`` (default: the truth's own, :func:`sensor_rows_of`).
    """
    if sensor not in ("acceleration", "displacement"):
        raise ValueError(f"sensor={sensor!r}: use 'acceleration' or 'displacement'")
    t = np.asarray(timepts, dtype=float)
    dt = float(t[1] - t[0])
    f = truth.flap_dynamics(V)
    Hs = sensor_rows_of(truth, sensor_rows)
    Kd = control.sample_system(K, dt, method="zoh") if K.nstates else K
    Ak, Bk, Ck, Dk = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (Kd.A, Kd.B, Kd.C, Kd.D))
    nk = Ak.shape[0] if K.nstates else 0
    nx = truth.state_matrix(V).shape[0]
    s = np.zeros(nx)
    x0 = np.asarray(x0, dtype=float).ravel()
    s[:x0.size] = x0  # [u, u'] (flow at rest) or the full state
    xa = np.zeros(2)  # actuator: v, v'
    xk = np.zeros(nk)
    wa2, ca = actuator_omega ** 2, 2 * actuator_zeta * actuator_omega
    h = dt / substeps
    n = t.size
    ZM = np.full((n, Hs.shape[0]), np.nan)
    Vf = np.zeros(n)
    G = np.zeros(n)

    def deriv(s_, xa_, vc):
        vdd = wa2 * (vc - xa_[0]) - ca * xa_[1]
        ds, _ = f(s_, xa_[0], xa_[1], vdd)
        return ds, np.array([xa_[1], vdd])

    vc = 0.0  # command held over the current sample interval
    kicked = kick is None
    for k in range(n):
        if not kicked and t[k] >= kick[0]:
            s[kick[1]] += kick[2]
            kicked = True
        vdd_now = wa2 * (vc - xa[0]) - ca * xa[1]
        _, acc = f(s, xa[0], xa[1], vdd_now)
        zm = Hs @ (acc if sensor == "acceleration" else s[:Hs.shape[1]])
        if not np.all(np.isfinite(zm)) or np.abs(s).max() > 1e6:
            break
        ZM[k], Vf[k], G[k] = zm, xa[0], gain(t[k])
        vc = G[k] * float((Ck @ xk + Dk @ zm)[0]) if nk else G[k] * float((Dk @ zm)[0])
        if nk:
            xk = Ak @ xk + Bk @ zm
        if k == n - 1:
            break
        for _ in range(substeps):
            k1s, k1a = deriv(s, xa, vc)
            k2s, k2a = deriv(s + 0.5 * h * k1s, xa + 0.5 * h * k1a, vc)
            k3s, k3a = deriv(s + 0.5 * h * k2s, xa + 0.5 * h * k2a, vc)
            k4s, k4a = deriv(s + h * k3s, xa + h * k3a, vc)
            s = s + h / 6 * (k1s + 2 * k2s + 2 * k3s + k4s)
            xa = xa + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
    return {"timepts": t, "zm": ZM, "v": Vf, "gain": G}


def suppression_run(truth, K, cfg, Vf: float, *, dt: float, mode: int) -> dict:
    """Paper Fig. 11 on the truth: LCO develops, the gain ramps 0 -> 1, holds, is released.

    The controller reads the accelerometers of the run configuration (``cfg.sensors.rows``,
    default the truth's own rows).

    The attenuation compares the RMS of the dominant sensor over the last third of the
    hold with its RMS over the last third of the settling phase (open-loop LCO);
    ``lco_returns`` checks that after the release (the wing is tapped with the initial
    deflection at that moment) the amplitude climbs back above half the open-loop LCO.
    """
    sp = cfg.suppression
    V = Vf * sp.speed_factor
    T = sp.settle + sp.ramp + sp.hold + sp.release
    t = np.arange(0.0, T, dt)
    x0 = np.zeros(2 * truth.n_modes)
    x0[mode] = cfg.lco.initial_deflection
    g = gain_schedule(sp.settle, sp.ramp, sp.hold)
    t_release = sp.settle + sp.ramp + sp.hold
    res = closed_loop_truth(truth, K, V, t, x0, g,
                            kick=(t_release, mode, cfg.lco.initial_deflection),
                            sensor_rows=getattr(getattr(cfg, "sensors", None), "rows", None))
    zm = res["zm"]
    if not np.all(np.isfinite(zm)):
        raise CasflutterError(f"the closed-loop truth simulation at V = {V:.4f} blew up")

    def rms(a, b):
        sel = (t >= a) & (t < b)
        return np.sqrt(np.mean(zm[sel] ** 2, axis=0))

    open_rms = rms(sp.settle * 2 / 3, sp.settle)
    dom = int(np.argmax(open_rms))
    t_full = sp.settle + sp.ramp
    closed_rms = rms(t_full + sp.hold * 2 / 3, t_full + sp.hold)
    after = rms(T - sp.release / 3, T)
    att = 100.0 * (1.0 - closed_rms[dom] / open_rms[dom]) if open_rms[dom] > 0 else None
    res.update(V=V, attenuation_percent=att, open_loop_rms=open_rms.tolist(),
               closed_loop_rms=closed_rms.tolist(), released_rms=after.tolist(),
               lco_returns=bool(after[dom] > 0.5 * open_rms[dom]), dominant_sensor=dom)
    return res
