"""Input--output records, their loaders (CSV, NPZ, MATLAB), excitation signals, the
analysis of response records (decay, LCO, divergence), tables of frequency-domain
generalised aerodynamic forces Q(ik) with their files, and gridded plant-family files
(state-space models at a grid of speeds, :class:`FamilyFile`)."""

from ._family_arrays import check_grid_speeds, check_stack, check_state_stack, read_family_arrays
from ._family_file import (FAMILY_KIND, FEEDBACK_CONVENTIONS, INTERPOLATIONS, FamilyFile,
                           read_family_file)
from ._gaf import GAFTable, load_gaf
from ._records import IOData, Record
from ._response import ResponseAnalysis, analyze_response, dominant_frequency, envelope_growth_rate
from ._signals import (backward_derivatives, check_band, chirp_excitation, chirp_motion,
                       stepped_chirp_motion)

__all__ = ["IOData", "Record", "chirp_excitation", "chirp_motion", "stepped_chirp_motion",
           "backward_derivatives",
           "check_band", "ResponseAnalysis", "analyze_response", "envelope_growth_rate",
           "dominant_frequency", "GAFTable", "load_gaf",
           "FAMILY_KIND", "FEEDBACK_CONVENTIONS", "INTERPOLATIONS", "FamilyFile",
           "read_family_file", "read_family_arrays", "check_grid_speeds", "check_stack",
           "check_state_stack"]
