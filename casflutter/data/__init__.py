"""Input--output records, their loaders (CSV, NPZ, MATLAB) and excitation signals; tables of
frequency-domain generalised aerodynamic forces Q(ik) and their files."""

from ._records import IOData, Record  # noqa: F401
from ._signals import chirp_excitation  # noqa: F401
from ._gaf import GAFTable, load_gaf  # noqa: F401
