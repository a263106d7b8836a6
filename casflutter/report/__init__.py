"""Figures and reports (matplotlib; each figure function returns a Figure)."""

from ._flutter_plots import plot_lco, plot_pole_loci, plot_root_locus, plot_vg_vf  # noqa: F401
from ._html import PAPER_TABLE_I, html_report  # noqa: F401
from ._lco_plots import plot_bifurcation, plot_bifurcation_pair  # noqa: F401
from ._pipeline_plots import (plot_flap_pulses, plot_gain_ramp, plot_hankel,  # noqa: F401
                              plot_rom_fit)

__all__ = ["plot_vg_vf", "plot_root_locus", "plot_lco", "plot_pole_loci", "plot_rom_fit",
           "plot_flap_pulses", "plot_gain_ramp", "plot_hankel", "html_report",
           "PAPER_TABLE_I", "plot_bifurcation", "plot_bifurcation_pair"]
