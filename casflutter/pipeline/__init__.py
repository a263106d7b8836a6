"""The study run: every stage of the paper wired by one validated configuration.

- :func:`run` — ``run(config) -> RunResult``: the stages of :mod:`._run` on any problem (a
  truth, a wing or GAF file, a plant family file), each route chosen in one place
  (:data:`ROUTES`); the result has a typed result per stage (:class:`ModelStage`,
  :class:`FlutterStage`, :class:`LcoResult`, :class:`ControllerStage`,
  :class:`SuppressionStage`, ...) and
  :meth:`RunResult.summary` (``summary.json``).
- :func:`design_family`, :func:`multispeed_settings` and :func:`start_controller` — the
  family a configuration's controller stage designs on, the settings of its multi-speed
  design, and the controller file it starts from matched to that family.
- :func:`load_config` / :class:`RunConfig` — the TOML configuration; each table is the
  settings class of its stage.
"""

from ._config import (STAGES, ClosedLoopSection, ControllerSettings, DataSection,
                      FlutterSection, LcoSection, ParametricSection, ProblemSection, RomSection,
                      RunConfig, SensorsSection, SolverSection, VerifySection, config_path,
                      default_config_path, flutter_config, load_config)
from ._control import ControllerStage, multispeed_settings, start_controller
from ._model import ROUTES, FlutterStage, ModelStage, ParametricResult, Route
from ._result import ClosedLoopChecks, LcoResult, RunResult, SimulationCheck
from ._run import check_requested_stages, design_family, model_stages, run
from ._suppression import SuppressionStage

__all__ = [
    "run", "RunResult", "LcoResult", "ParametricResult", "SimulationCheck", "ClosedLoopChecks",
    "ModelStage", "FlutterStage", "ControllerStage", "SuppressionStage", "ROUTES", "Route", "design_family",
    "multispeed_settings", "start_controller", "model_stages", "check_requested_stages",
    "RunConfig", "load_config", "default_config_path", "config_path", "flutter_config",
    "STAGES",
    "ProblemSection", "DataSection", "RomSection", "FlutterSection", "LcoSection",
    "ControllerSettings", "VerifySection", "ClosedLoopSection", "ParametricSection",
    "SensorsSection", "SolverSection",
]
