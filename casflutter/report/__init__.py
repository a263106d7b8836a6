"""Figures and reports (matplotlib; each figure function returns a Figure).

:func:`write_figures` and :func:`write_html` write the figures and the HTML report of a study
run (``casflutter run``).
"""

from ._family_plots import family_branches, plot_family_vg_vf
from ._flutter_plots import plot_lco, plot_pole_loci, plot_root_locus, plot_vg_vf, speed_axes
from ._html import PAPER_TABLE_I, VF_FLAG_FRACTION, flutter_speed_flags, html_report
from ._labels import frequency_unit, sensor_labels
from ._lco_plots import plot_bifurcation, plot_bifurcation_pair
from ._margin_plots import (plot_closed_loop_damping, plot_family_verification,
                            plot_margins_vs_speed, plot_model_mismatch)
from ._pipeline_plots import plot_flap_pulses, plot_gain_ramp, plot_hankel, plot_rom_fit
from ._run_report import figure_captions, flap_pulse_comparison, write_figures, write_html

__all__ = ["plot_vg_vf", "plot_root_locus", "plot_lco", "plot_pole_loci", "plot_rom_fit",
           "plot_flap_pulses", "plot_gain_ramp", "plot_hankel", "html_report",
           "PAPER_TABLE_I", "plot_bifurcation", "plot_bifurcation_pair", "write_figures",
           "write_html", "flap_pulse_comparison", "figure_captions", "sensor_labels",
           "speed_axes", "frequency_unit", "flutter_speed_flags", "VF_FLAG_FRACTION",
           "plot_family_vg_vf", "family_branches", "plot_margins_vs_speed",
           "plot_closed_loop_damping", "plot_family_verification", "plot_model_mismatch"]
