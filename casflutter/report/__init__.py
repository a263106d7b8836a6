"""Figures and reports (matplotlib; each figure function returns a Figure)."""

from ._flutter_plots import plot_lco, plot_pole_loci, plot_root_locus, plot_vg_vf  # noqa: F401

__all__ = ["plot_vg_vf", "plot_root_locus", "plot_lco", "plot_pole_loci"]
