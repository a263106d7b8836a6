"""Figures and the HTML report of ``casflutter run`` (written into the output folder)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=False)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["write_figures", "write_html"]


def _save(fig, path: Path) -> Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_figures(out: Path, objects: dict, cfg) -> dict:
    """Paper Fig. 7--11 (and the Hankel singular values) as PNG files."""
    from ..report import (plot_flap_pulses, plot_gain_ramp, plot_hankel, plot_lco,
                          plot_pole_loci, plot_rom_fit, plot_vg_vf)
    from ._suppression import flap_pulse_comparison

    model = objects["identification"].model
    files = {}
    files["fig7_rom_fit"] = _save(plot_rom_fit(model, objects["data"]), out / "fig7_rom_fit.png")
    real = objects["realization"]
    files["hankel"] = _save(plot_hankel(real.hankel_singular_values, real.order),
                            out / "hankel_singular_values.png")
    fp = flap_pulse_comparison(objects["truth"], model, objects["system"].structure,
                               cfg.data.V0, dt=model.dt)
    files["fig8_flap_pulses"] = _save(plot_flap_pulses(fp["timepts"], fp["truth_zm"],
                                                       fp["rom_zm"], fp["v"]),
                                      out / "fig8_flap_pulses.png")
    files["fig9_lco"] = _save(plot_lco(objects["lco"], truth=objects.get("lco_truth")),
                              out / "fig9_lco.png")
    fl = objects["flutter"]
    files["vg_vf"] = _save(plot_vg_vf(fl), out / "vg_vf.png")
    vr = cfg.flutter.vrange
    Vg = np.linspace(max(vr[0], 1e-3), vr[1], 60)
    fig10 = plot_pole_loci(objects["system"], Vg, controller=objects["controller"])
    # the structural region (far aerodynamic and controller poles would set the scale)
    w_max = 1.3 * float(np.max(objects["system"].structure.omega))
    fig10.axes[0].set_xlim(-0.25 * w_max / 2, 0.1 * w_max / 2)
    fig10.axes[0].set_ylim(0.0, w_max)
    files["fig10_pole_loci"] = _save(fig10, out / "fig10_pole_loci.png")
    sup = objects["suppression"]
    files["fig11_gain_ramp"] = _save(plot_gain_ramp(sup["timepts"], sup["zm"], sup["gain"],
                                                    sup["v"]), out / "fig11_gain_ramp.png")
    return files


def write_html(out: Path, summary: dict, figures: dict) -> Path:
    """``report.html`` with every figure embedded."""
    from ..report import html_report

    path = out / "report.html"
    path.write_text(html_report(summary, figures), encoding="utf-8")
    return path
