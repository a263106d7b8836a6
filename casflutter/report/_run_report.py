"""The figures and the HTML report of a study run (``casflutter run``), written to a folder.

Each figure comes from a stage's typed result (paper Fig. 7–11); a figure whose stage did
not run is left out.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..aeroelastic import simulate_loop
from ._flutter_plots import plot_lco, plot_pole_loci, plot_vg_vf
from ._html import html_report
from ._pipeline_plots import plot_flap_pulses, plot_gain_ramp, plot_hankel, plot_rom_fit

__all__ = ["write_figures", "write_html", "flap_pulse_comparison"]


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


def write_figures(out: Path, result) -> dict:
    """Paper Fig. 7–11 (and the Hankel singular values) of a run as PNG files.

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
    if result.identification is None:   # a GAF wing file: no records, ROM or ERA
        if result.rfa_flutter is not None:
            fl = result.rfa_flutter     # the structural branches, not the lag roots
            modes = [b for b in fl.tracking.upper_branches() if fl.origin[b] >= 0]
            fig = plot_vg_vf(fl, branches=modes, hz=False)
            fig.axes[-1].set_xlabel("airspeed U [m/s]")
            files["vg_vf_airspeed"] = _save(fig, out / "vg_vf_airspeed.png")
        if result.flutter is not None:
            files["vg_vf"] = _save(plot_vg_vf(result.flutter), out / "vg_vf.png")
        return files
    model = result.identification.model
    files["fig7_rom_fit"] = _save(plot_rom_fit(model, result.data), out / "fig7_rom_fit.png")
    real = result.realization
    files["hankel"] = _save(plot_hankel(real.hankel_singular_values, real.order),
                            out / "hankel_singular_values.png")
    if result.truth is not None:   # a wing file has no truth to compare with
        fp = flap_pulse_comparison(result.truth, model, result.system.structure,
                                   result.config.data.V0, dt=model.dt)
        files["fig8_flap_pulses"] = _save(plot_flap_pulses(fp["timepts"], fp["truth_zm"],
                                                           fp["rom_zm"], fp["v"]),
                                          out / "fig8_flap_pulses.png")
    if result.lco is not None:
        files["fig9_lco"] = _save(plot_lco(result.lco.rom, truth=result.lco.truth),
                                  out / "fig9_lco.png")
    files["vg_vf"] = _save(plot_vg_vf(result.flutter), out / "vg_vf.png")
    vr = result.config.flutter.V_range
    Vg = np.linspace(max(vr[0], 1e-3), vr[1], 60)
    fig10 = plot_pole_loci(result.system, Vg, controller=result.controller)
    # the structural region (far aerodynamic and controller poles would set the scale)
    w_max = 1.3 * float(np.max(result.system.structure.omega))
    fig10.axes[0].set_xlim(-0.25 * w_max / 2, 0.1 * w_max / 2)
    fig10.axes[0].set_ylim(0.0, w_max)
    files["fig10_pole_loci"] = _save(fig10, out / "fig10_pole_loci.png")
    if result.suppression is not None:
        sim = result.suppression.simulation
        files["fig11_gain_ramp"] = _save(plot_gain_ramp(sim.timepts, sim.zm, sim.gain, sim.v),
                                         out / "fig11_gain_ramp.png")
    return files


def write_html(out: Path, summary: dict, figures: dict) -> Path:
    """``report.html`` with every figure embedded.

    Parameters
    ----------
    out : Path
        Output folder.
    summary : dict
        The run's summary (``summary.json``).
    figures : dict
        Figure name -> PNG path.

    Returns
    -------
    Path
    """
    path = Path(out) / "report.html"
    path.write_text(html_report(summary, figures), encoding="utf-8")
    return path
