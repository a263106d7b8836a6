"""Parameter studies: resumable sweeps (local processes or Dask) and flutter sensitivities.

- :func:`load_study` / :class:`Study`: a full grid or Latin hypercube over named parameters,
  an evaluator (a point -> a dict of outputs) and fixed settings, from a TOML file.
- :func:`run_sweep`: runs it on local worker processes or a Dask cluster; every finished
  point is stored at once (:class:`PointStore`), so a sweep resumes where it stopped;
  failures are recorded, not raised.
- :func:`sweep_table`, :func:`write_table`, :func:`plot_sweep`: the tidy table (CSV,
  Parquet with pyarrow) and summary plots.
- :func:`flutter_sensitivity`: dVf/dp by eigenvalue perturbation at the crossing
  (paper Sec. III-B), checked by :func:`flutter_speed_fd`.
- :func:`flutter_sensitivity_nlp`: the same derivatives from the parametric sensitivity of
  the Hopf-point NLP (:func:`hopf_point`, CasADi).
- :func:`gamma_sensitivity`: dγ*/dp of fixed-order H∞ synthesis at its solution (envelope
  theorem of the minimax NLP, CasADi AD), checked against closed-form optima.
- :func:`pipeline_evaluator`: the ``pipeline`` evaluator, one ``casflutter run`` per point,
  parameters as dotted run-config paths (``controller.order``, ``problem.set.zeta_lateral``);
  :func:`rom_flutter_evaluator` the same for the ROM route of ``casflutter flutter``.
- :func:`cached_solver`: one parametric CasADi solver per worker process and structure
  (the ``truth_hopf`` evaluator builds its NLP once per worker).
"""

from ._evaluators import (Evaluator, evaluator_names, get_evaluator, register_evaluator,
                          synthesis_gamma, truth_flutter_evaluator)
from ._gamma import GammaSensitivity, gamma_sensitivity
from ._pipeline_eval import (PIPELINE_OUTPUTS, PIPELINE_SETTINGS, flatten_summary,
                             pipeline_config, pipeline_evaluator, rom_flutter_evaluator)
from ._hopf import (HopfPoint, flutter_sensitivity_nlp, hopf_point, quadratic_coefficients,
                    truth_hopf)
from ._runner import Progress, SweepResult, evaluate_point, run_sweep
from ._sensitivity import (FlutterSensitivity, ParameterSensitivity, flutter_sensitivity,
                           flutter_speed_fd)
from ._solvers import cached_solver, clear_solver_cache, solver_builds
from ._spec import Parameter, Study, load_study, point_key
from ._store import PointStore
from ._table import plot_sweep, sweep_table, write_table

__all__ = [
    "Study", "Parameter", "load_study", "point_key", "PointStore",
    "run_sweep", "SweepResult", "Progress", "evaluate_point",
    "Evaluator", "register_evaluator", "get_evaluator", "evaluator_names",
    "truth_flutter_evaluator", "synthesis_gamma",
    "pipeline_evaluator", "rom_flutter_evaluator", "pipeline_config", "flatten_summary", "PIPELINE_OUTPUTS",
    "PIPELINE_SETTINGS",
    "sweep_table", "write_table", "plot_sweep",
    "flutter_sensitivity", "flutter_speed_fd", "FlutterSensitivity", "ParameterSensitivity",
    "cached_solver", "solver_builds", "clear_solver_cache",
    "gamma_sensitivity", "GammaSensitivity",
    "hopf_point", "HopfPoint", "quadratic_coefficients", "flutter_sensitivity_nlp", "truth_hopf",
]
