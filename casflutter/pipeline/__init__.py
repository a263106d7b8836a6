"""The study run: every stage of the paper wired by one validated configuration.

- :func:`run` — ``run(config) -> RunResult``: the stages of :mod:`._run` on a truth problem;
  the result has a typed field per stage and :meth:`RunResult.summary` (``summary.json``).
- :func:`load_config` / :class:`RunConfig` — the TOML configuration; each table is the
  settings class of its stage.
"""

from ._config import (STAGES, ClosedLoopSection, ControllerSettings, DataSection,
                      FlutterSection, LcoSection, ParametricSection, ProblemSection, RomSection,
                      RunConfig, SensorsSection, SolverSection, VerifySection, config_path,
                      default_config_path, flutter_config, load_config)
from ._result import ClosedLoopChecks, LcoResult, ParametricResult, RunResult, SimulationCheck
from ._run import run

__all__ = [
    "run", "RunResult", "LcoResult", "ParametricResult", "SimulationCheck", "ClosedLoopChecks",
    "RunConfig", "load_config", "default_config_path", "config_path", "flutter_config",
    "STAGES",
    "ProblemSection", "DataSection", "RomSection", "FlutterSection", "LcoSection",
    "ControllerSettings", "VerifySection", "ClosedLoopSection", "ParametricSection",
    "SensorsSection", "SolverSection",
]
