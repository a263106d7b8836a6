"""Input--output records, their loaders (CSV, NPZ, MATLAB) and excitation signals."""

from ._records import IOData, Record  # noqa: F401
from ._signals import chirp_excitation  # noqa: F401
