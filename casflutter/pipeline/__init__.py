"""The stages wired together on the truth problems.

- :func:`run_pipeline` — ``casflutter run``: the paper's study end to end (Table I).

- :func:`rom_flutter` — the paper's ROM route (chirp data of the truth at one speed, HWL
  ROM, Σf by ERA + Tustin, ΣAE with the V² scaling, flutter) beside the truth, with the
  error explained (:func:`frozen_aero_truth`), and a parametric ROM interpolated in V.

- :func:`flutter_check` — issue 4's check on the typical section: an order-2 controller
  through the flap designed on the ROM's LFT at its flutter speed, its verified stable
  interval, and closed-loop simulations of the ROM and the truth above flutter.
"""

from ._config import RunConfig, default_config_path, load_config  # noqa: F401
from ._rom_data import (RomIdentification, backward_derivatives, chirp_motion,  # noqa: F401
                        identify_common_denominator, truth_records)
from ._rom_flutter import (ParametricROM, RomFlutterResult, RomSettings,  # noqa: F401
                           frozen_aero_truth, rom_flutter, rom_settings, rom_system,
                           structure_of, truth_flutter)

from ._run import RunResult, run_pipeline  # noqa: F401
from ._suppression import sensor_rows_of  # noqa: F401
from ._flutter_check import (FlutterCheckResult, FlutterCheckSettings,  # noqa: F401
                             SimulationCheck, TruthLoopSweep, flutter_check,
                             flutter_check_settings, truth_loop_matrix)

__all__ = [
    "RunConfig", "load_config", "default_config_path", "RunResult", "run_pipeline",
    "sensor_rows_of",
    "chirp_motion", "backward_derivatives", "truth_records", "RomIdentification",
    "identify_common_denominator",
    "RomSettings", "rom_settings", "structure_of", "truth_flutter", "frozen_aero_truth",
    "rom_system", "ParametricROM", "RomFlutterResult", "rom_flutter",
    "flutter_check", "flutter_check_settings", "FlutterCheckSettings", "FlutterCheckResult",
    "SimulationCheck", "TruthLoopSweep", "truth_loop_matrix",
]
