"""The figures and the HTML report of a study run (``casflutter run``), written to a folder.

Each figure comes from a stage's typed result (paper Fig. 7–11); a figure whose stage did
not run is left out.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..aeroelastic import simulate_loop
from ..lco import speed_convention
from ._family_plots import plot_family_vg_vf
from ._flutter_plots import plot_lco, plot_pole_loci, plot_vg_vf, speed_axes
from ._html import html_report
from ._labels import frequency_unit, label_unit, sensor_labels
from ._lco_plots import plot_bifurcation_pair
from ._margin_plots import plot_family_verification, plot_model_mismatch
from ._pipeline_plots import plot_flap_pulses, plot_gain_ramp, plot_hankel, plot_rom_fit

__all__ = ["write_figures", "write_html", "flap_pulse_comparison", "figure_captions"]

log = logging.getLogger(__name__)


def _save(fig, path: Path) -> Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def flap_pulse_comparison(truth, model, structure, V: float, *, dt: float,
                          duration: float = 4.0, amplitude: float = np.radians(2.0)) -> dict:
    """Sensor response to a sequence of finite-width flap pulses at V (paper Fig. 8).

    The nonlinear ROM in the loop with Σs against the truth, both read by the sensors of
    ``structure`` (its ``Hs`` and ``sensor`` kind).

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator.
    model : HWLModel
        The ROM.
    structure : ModalStructure
        Σs with the sensors.
    V : float
        Speed index.
    dt : float
        The ROM's sampling time.
    duration : float
        Length of the record.
    amplitude : float
        Pulse height [rad].

    Returns
    -------
    dict
        ``timepts``, ``v`` (flap), ``truth_zm``, ``rom_zm``.
    """
    t = np.arange(0.0, duration, dt)
    v = np.zeros_like(t)
    for k, t0 in enumerate((0.2, 0.9, 1.6, 2.3)):
        w = 0.05 + 0.03 * k
        v += (-1) ** k * amplitude * np.exp(-0.5 * ((t - t0) / (0.35 * w)) ** 2)
    sim_t = truth.simulate(t, truth.modal_state(), V, v=v)
    sim_r = simulate_loop(model, structure, V, t.size, v=v)
    motion = {"acceleration": sim_t.uddot, "velocity": sim_t.udot, "displacement": sim_t.u}
    return {"timepts": t, "v": v, "truth_zm": motion[structure.sensor] @ structure.Hs.T,
            "rom_zm": sim_r.zm}


def _sensor_labels(result) -> list[str]:
    """Axis labels of the run's sensors with their units (the truth's units when the run
    reads the truth's own sensor rows)."""
    st = result.system.structure
    wing_units = getattr(result.problem, "sensor_units", None)
    if isinstance(wing_units, tuple) and not result.config.sensors.rows:
        # a wing file gives the unit of each sensor's reading itself
        return [f"{n} [{u or '-'}]" for n, u in zip(st.sensor_names, wing_units)]
    units = (() if result.config.sensors.rows or result.truth is None
             else result.truth.sensor_units())
    return sensor_labels(st.sensor_names, units, st.sensor, st.time_unit)


def _speed_kw(result, time_unit: str) -> dict:
    """The V–g/V–f keywords of a run: the airspeed with the speed index on a second axis
    where the problem has a speed scale, and frequencies in Hz (in the problem's own
    nondimensional frequency when its time is not seconds)."""
    problem = result.problem if result.problem is not None else result.truth
    scale, unit = speed_convention(problem)
    funit = frequency_unit(time_unit)
    kw = dict(hz=funit is None, frequency_unit=funit)
    if unit == "m/s":
        return dict(kw, speed_scale=scale, speed_unit="m/s", speed_label="airspeed U [m/s]",
                    index_label="speed index V")
    return dict(kw, speed_label=f"speed index {unit}".strip())


def write_figures(out: Path, result) -> dict:
    """Paper Fig. 7–11, the V–g/V–f plot, the Hankel singular values and (when the run
    computed them) the LCO branches as PNG files.

    Parameters
    ----------
    out : Path
        Existing output folder.
    result : casflutter.pipeline.RunResult
        The run.

    Returns
    -------
    dict
        Figure name -> path.
    """
    out = Path(out)
    files = {}
    if result.route == "family":        # a family file: its crossings and certificate
        return _family_figures(out, result)
    if result.identification is None:   # a GAF wing file: no records, ROM or ERA
        names = result.problem.structure.mode_names
        if result.rfa_flutter is not None:
            fl = result.rfa_flutter     # the structural branches, not the lag roots
            lam = fl.tracking.eigenvalues
            modes = [b for b in fl.tracking.upper_branches()
                     if fl.origin[b] >= 0 and np.mean(np.abs(lam[:, b].imag)) > 0]
            fig = plot_vg_vf(fl, branches=modes, hz=False, mode_names=names, speed_unit="m/s",
                             speed_label="airspeed U [m/s]")
            speed_axes(fig.axes[0], result.problem.U_ref, "speed index V = U / U_ref")
            fig.tight_layout()
            files["vg_vf_airspeed"] = _save(fig, out / "vg_vf_airspeed.png")
        if result.flutter is not None:
            files["vg_vf"] = _save(plot_vg_vf(result.flutter, mode_names=names,
                                              **_speed_kw(result, "s")), out / "vg_vf.png")
        return files
    model = result.identification.model
    st = result.system.structure
    labels = _sensor_labels(result)
    files["fig7_rom_fit"] = _save(plot_rom_fit(model, result.data, fit=result.fit,
                                               mode_names=st.mode_names,
                                               time_unit=st.time_unit),
                                  out / "fig7_rom_fit.png")
    real = result.realization
    files["hankel"] = _save(plot_hankel(real.hankel_singular_values, real.order),
                            out / "hankel_singular_values.png")
    if result.truth is not None:   # a wing file has no truth to compare with
        fp = flap_pulse_comparison(result.truth, model, st, result.config.data.V0, dt=model.dt)
        files["fig8_flap_pulses"] = _save(plot_flap_pulses(fp["timepts"], fp["truth_zm"],
                                                           fp["rom_zm"], fp["v"], labels,
                                                           time_unit=st.time_unit),
                                          out / "fig8_flap_pulses.png")
    speed = _speed_kw(result, st.time_unit)
    air = dict(speed_scale=speed.get("speed_scale", 1.0), speed_unit=speed.get("speed_unit", ""))
    if result.lco is not None:
        lco = result.lco
        pct = 100 * (result.config.lco.speed_factor - 1)
        files["fig9_lco"] = _save(plot_lco(
            lco.rom, truth=lco.truth, labels=labels,
            title=f"Fig. 9: LCO of each model {pct:.3g} % above its own flutter speed",
            time_unit=st.time_unit, **air),
            out / "fig9_lco.png")
        for c in lco.speed_following:
            files[_following_key(c.speed_factor)] = _save(plot_lco(
                c.rom, truth=c.truth, labels=labels,
                title=(f"LCO of the speed-following ROM and of the truth at "
                       f"{c.speed_factor:g} x the truth's flutter speed"),
                time_unit=st.time_unit, **air), out / f"{_following_key(c.speed_factor)}.png")
        if lco.truth_branch is not None and lco.rom_branch is not None:
            files["lco_branches"] = _save(plot_bifurcation_pair(lco.truth_branch,
                                                                lco.rom_branch),
                                          out / "lco_branches.png")
    files["vg_vf"] = _save(plot_vg_vf(result.flutter, mode_names=st.mode_names, **speed),
                           out / "vg_vf.png")
    vr = result.config.flutter.V_range
    Vg = np.linspace(max(vr[0], 1e-3), vr[1], 60)
    # the family whose interval the run certifies (with the servo for a scaled ROM)
    fig10 = plot_pole_loci(result.controlled_rom, Vg, controller=result.controller)
    # the structural region (far aerodynamic and controller poles would set the scale)
    w_max = 1.3 * float(np.max(st.omega))
    fig10.axes[0].set_xlim(-0.25 * w_max / 2, 0.1 * w_max / 2)
    fig10.axes[0].set_ylim(0.0, w_max)
    files["fig10_pole_loci"] = _save(fig10, out / "fig10_pole_loci.png")
    files.update(_margin_figures(out, result))
    if result.suppression is not None:
        files["fig11_gain_ramp"] = _save(_fig11(result, labels, st.time_unit, air),
                                         out / "fig11_gain_ramp.png")
    return files


def _fig11(result, labels, time_unit: str, air: dict):
    """Paper Fig. 11, one column per suppression run (speed)."""
    runs = result.suppression.runs
    ss = result.config.suppression
    limit = None if ss.flap_limit is None else float(np.degrees(ss.flap_limit))
    m = runs[0].simulation.zm.shape[1]
    fig, grid = plt.subplots(m + 2, len(runs), sharex=True, squeeze=False,
                             figsize=(6.0 * len(runs) + 1.5, 1.8 * (m + 2) + 0.6))
    for k, sup in enumerate(runs):
        sim = sup.simulation
        t0 = float(sim.timepts[0]) + ss.settle
        dom = sup.dominant_sensor
        amp = sup.open_loop_amplitude[dom] if sup.open_loop_amplitude else None
        att = ("" if sup.attenuation_percent is None
               else f", attenuation {sup.attenuation_percent:.1f} %")
        if sup.flap_rate_saturated_percent:
            att += f"\nflap rate at its limit {sup.flap_rate_saturated_percent:.0f} % of the hold"
        factor = "" if sup.speed_factor is None else f" ({sup.speed_factor:g} Vf)"
        airspeed = f", {sup.V * air['speed_scale']:.4g} m/s" if air["speed_unit"] else ""
        plot_gain_ramp(sim.timepts, sim.zm, sim.gain, sim.v, labels,
                       phases=(t0, t0 + ss.ramp, t0 + ss.ramp + ss.hold),
                       open_loop_amplitude=amp, dominant=dom, time_unit=time_unit,
                       flap_limit_deg=limit, axes=grid[:, k],
                       title=f"V = {sup.V:.4g}{factor}{airspeed}{att}")
    fig.suptitle("Fig. 11: suppression of the truth's established LCO in turbulence, gain "
                 "ramp and release", fontsize=10)
    fig.tight_layout()
    return fig


def _margin_figures(out: Path, result) -> dict:
    """Margins and closed-loop damping against the speed, one figure per certified model
    (``margins_design.png``, ``margins_truth.png``), and the design model's response error
    against each reference (``model_error_truth.png``)."""
    if result.control is None:
        return {}
    files = {f"margins_{name}": _save(plot_family_verification(check),
                                      out / f"margins_{name}.png")
             for name, check in result.control.checks.items()}
    for name, mismatch in result.control.mismatch.items():
        lost = result.control.checks[name].crossings
        files[f"model_error_{name}"] = _save(plot_model_mismatch(mismatch, crossings=lost),
                                             out / f"model_error_{name}.png")
    return files


def _family_figures(out: Path, result) -> dict:
    """A family file's V–g/V–f in its own units, and the controller's margins."""
    files = {"vg_vf": _save(plot_family_vg_vf(result.flutter, result.model.family),
                            out / "vg_vf.png")}
    files.update(_margin_figures(out, result))
    return files


def _amplitudes(values, units) -> str:
    """``124.2 m/s², 86.33 m/s²``: amplitudes with their sensors' units."""
    units = list(units) + [""] * len(values)
    return ", ".join(f"{a:.4g} {u}".rstrip() for a, u in zip(values, units))


def _following_key(speed_factor: float) -> str:
    """``lco_speed_following_1p2``: the figure of the speed-following ROM's LCO at a
    multiple of the truth's flutter speed."""
    return f"lco_speed_following_{speed_factor:g}".replace(".", "p")


def figure_captions(result) -> dict:
    """A caption per figure of :func:`write_figures`, for the report.

    Parameters
    ----------
    result : casflutter.pipeline.RunResult
        The run.

    Returns
    -------
    dict
        Figure name -> caption.
    """
    cfg = result.config
    control = {f"margins_{name}": (
        f"Loop-at-a-time gain and phase margins at the plant inputs and outputs against the "
        f"speed, and the closed-loop damping, of the controller on the {name} model "
        f"({check.family}); the thresholds {check.gain_margin_db:g} dB / "
        f"{check.phase_margin_deg:g}° are dashed, the absolute and robust flutter speeds marked.")
        for name, check in (result.control.checks.items() if result.control is not None
                            else ())}
    control.update({f"model_error_{name}": (
        f"How far the design model's response from the controls to the measurements lies "
        f"from the {name}'s at five speeds: σmax(G_{name} − G) / σmax(G) against the "
        f"frequency (0.1: a gain error of 10 % or a phase error of about 6°).  Where it is "
        f"large near the frequencies the closed loop needs, a certificate on the design model "
        f"need not carry over to the {name}; the red lines mark where the controller's loop "
        f"on the {name} loses stability (speed and frequency).")
        for name in (result.control.mismatch if result.control is not None else ())})
    if result.route == "family":
        fam = result.model.family
        return {"vg_vf": (f"V–g and V–f of the plant family {fam.name}'s open-loop branches "
                          f"against the speed [{fam.speed_unit}], crossings marked."),
                **control}
    if result.identification is None:   # a GAF wing file: the RFA's V-g/V-f only
        return {"vg_vf": "V–g and V–f of ΣAE(V) with Σf frozen at the flutter airspeed.",
                "vg_vf_airspeed": ("V–g and V–f of the RFA's ΣAE(U) against the airspeed: the "
                                   "structural branches.")}
    cap = {
        "fig7_rom_fit": (
            "Fig. 7. Generalised aerodynamic forces y_i of the truth's chirp records (black) "
            "and the ROM's free run from the same inputs (dashed), one mode per panel. "
            f"Error = 100 ||y - ŷ|| / ||y|| after the first {result.fit.skip} samples, on the "
            "record shown and over all records (the number of the fit table)."),
        "hankel": ("Hankel singular values of the linearised ROM; the dashed line is the "
                   f"order nf = {result.realization.order} of Σf."),
        "fig8_flap_pulses": (
            f"Fig. 8. Sensor response to a sequence of flap pulses at V0 = {cfg.data.V0:g}: "
            "the ROM in the loop with Σs (dashed) against the truth (black)."),
        "vg_vf": ("V–g and V–f of ΣAE (the ROM's linear aeroelastic system): the branches of "
                  "the structural modes in colour (numbered from 1), the aerodynamic lag "
                  "states in grey; the red dashed line marks flutter."),
        "fig10_pole_loci": ("Fig. 10. Poles of ΣAE over the speed range, open loop (x) and "
                            "with the controller (o)."),
    }
    if result.control is not None and cfg.controller.servo_omega > 0:
        cap["fig10_pole_loci"] = (
            "Fig. 10. Poles of the ROM loop the controller was designed on over the speed "
            f"range, the flap behind the {cfg.controller.servo_omega:g} rad/s servo, open "
            "loop (x) and with the controller (o): the loop whose stable interval the run "
            "certifies.")
    if result.lco is not None:
        lco = result.lco
        sens = lco.rom.sensors
        units = [label_unit(lab) for lab in _sensor_labels(result)]
        rom_a = _amplitudes(sens.amplitude, units) if sens is not None else "-"
        tr = lco.truth
        V_rom = lco.V_hopf_loop if lco.V_hopf_loop is not None else lco.V_hopf_exact_order
        Vt = None if result.flutter_truth is None else result.flutter_truth.Vf
        f = cfg.lco.speed_factor
        text = (f"Fig. 9. Limit-cycle oscillation of the ROM loop at V = {lco.V:.4g} ({f:g} "
                f"x its own flutter speed {V_rom:.4g}, that of the sampled-data loop)")
        if tr is not None:
            tr_a = _amplitudes(tr.amplitude, units)
            text += (f" and of the truth at V = {tr.V:.4g} ({f:g} x its flutter speed "
                     f"{float('nan') if Vt is None else Vt:.4g}); sensor amplitudes (half "
                     f"peak to peak) ROM {rom_a}, truth {tr_a}.")
        else:
            text += f"; sensor amplitudes (half peak to peak) {rom_a}."
        cap["fig9_lco"] = text
        for c in lco.speed_following:
            cap[_following_key(c.speed_factor)] = (
                f"LCO of the ROM that follows the wing over speed (left) and of the truth "
                f"(right), both at V = {c.V:.4g}, {c.speed_factor:g} x the truth's flutter "
                f"speed: sensor amplitudes ROM {_amplitudes(c.rom_amplitude, units)}, truth "
                f"{_amplitudes(c.truth.amplitude, units)} (ROM "
                + c.describe_error() + "); ROM frequency "
                f"{c.rom.sensors.frequency_hz:.4g} Hz, truth {c.truth.freq_hz:.4g} Hz.")
        cap["lco_branches"] = (
            "LCO branches from the flutter points, continued in the airspeed: the truth "
            "(left, orthogonal collocation) and the ROM loop (right, invariant circles of the "
            "sampled-data map). Stable cycles solid, unstable dashed; the open circle marks "
            "the flutter (Hopf / Neimark–Sacker) point.")
    if result.suppression is not None:
        ss = cfg.suppression
        each = "; ".join(
            f"V = {sup.V:.4g} ({sup.speed_factor:g} Vf): attenuation "
            + ("-" if sup.attenuation_percent is None else f"{sup.attenuation_percent:.1f} %")
            + f", flap peak {np.degrees(sup.flap_peak):.3g} deg, rate peak "
            f"{np.degrees(sup.flap_rate_peak):.3g} deg/s"
            + (f" (at the rate limit {sup.flap_rate_saturated_percent:.0f} % of the hold)"
               if sup.flap_rate_saturated_percent else "")
            + ", the LCO returns on release: "
            f"{'yes' if sup.lco_returns else 'no'}"
            + ("; the truth's linearised loop is not certified stable at this speed, so the "
               "wing cannot come to rest there and this is not a suppressed LCO"
               if certified is False else "")
            for sup, certified in zip(result.suppression.runs,
                                      result.suppression.linear_loop_certified))
        tunnel = (f"in a Dryden turbulence of intensity {100 * ss.gust_intensity:g} % and "
                  f"scale {ss.gust_scale:g} m" if ss.gust_intensity > 0 else "without turbulence")
        cap["fig11_gain_ramp"] = (
            "Fig. 11. Suppression of the truth's established LCO: the controller gain is "
            "ramped 0 -> 1, held and released (shaded: open loop and full gain; dashed: the "
            "LCO amplitude before the ramp; dotted: the flap travel), " + tunnel
            + f", with sensor noise of rms {ss.noise:g}, the flap behind a servo "
            + ("without a rate limit" if ss.flap_rate_limit is None
               else f"limited to {np.degrees(ss.flap_rate_limit):.3g} deg/s")
            + {"none": "", "rate": ", its command rate-limited in software to the same rate",
               "phase_compensated": ", its command through a phase-compensating rate limiter "
               "at the same rate (the flap turns with the command)"}[ss.command_limiter]
            + ". Attenuation = 1 - RMS(last third of the full gain) / RMS(open-loop "
            f"LCO) of the dominant sensor. {each}.")
    cap.update(control)
    return cap


def write_html(out: Path, summary: dict, figures: dict, captions: dict | None = None, *,
               config: dict | None = None) -> Path:
    """``report.html`` with every figure embedded.

    A run on a plant family file (``summary["route"] == "family"``) gets the family's
    design report, any other run the paper's reproduction (:func:`html_report`).

    Parameters
    ----------
    out : Path
        Output folder.
    summary : dict
        The run's summary (``summary.json``).
    figures : dict
        Figure name -> PNG path.
    captions : dict, optional
        Figure name -> caption (:func:`figure_captions`).
    config : dict, optional
        The run's configuration (``config.json``); default: the folder's ``config.json``
        when it is there (the run writes it before the report).

    Returns
    -------
    Path
        The report's path.
    """
    out = Path(out)
    if config is None and (out / "config.json").is_file():
        try:
            config = json.loads((out / "config.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:   # the report does without it
            log.warning("report: cannot read %s (%s); the controller's settings are left "
                        "out of the report", out / "config.json", exc)
            config = None
    path = out / "report.html"
    path.write_text(html_report(summary, figures, captions=captions,
                                config=config if isinstance(config, dict) else None),
                    encoding="utf-8")
    return path
