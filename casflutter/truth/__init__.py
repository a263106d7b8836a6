"""Full-order truth simulators that stand in for the paper's CFD, and the experiments run on
them.

Given prescribed modal displacements (and flap) they return the generalised aerodynamic
forces ``y`` of eq. (6), so identification runs on them as it would on CFD output; their
own linear state space in the speed index ``V`` gives the true flutter speed.

- :class:`TypicalSection` -- pitch--plunge section, Wagner aerodynamics in R. T. Jones'
  two-lag form, optional flap and polynomial pitch stiffness (Hodges & Pierce HP-1 default).
- :class:`GolandWing` -- cantilever beam with assumed bending/torsion modes and strip-theory
  Jones aerodynamics (Goland 1945), with a trailing-edge flap of our own.
- :class:`SeedWing` -- the paper's wind-tunnel wing with tip store (five modes at the
  paper's frequencies, strip theory with Wagner lags per strip, saturating lift, flap,
  tip-store accelerometers), nonlinear, calibrated to the paper's Vf and LCO.
- :class:`PitchPlungeSection` -- a dimensional pitch--plunge rig section read from a TOML
  file (``kind = "pitch_plunge"``; Wagner or quasi-steady aerodynamics, polynomial pitch
  spring, flap), e.g. the Texas A&M NATA section in ``problems/nata``.
- :class:`WingProblem`, :class:`GAFProblem` -- a user's wing without a simulator, read from a
  wing file: modal data with records (``kind = "wing"``) or with ``Q(ik)`` (``kind = "gaf"``).
- :func:`load_problem` -- a problem by name or file, with parameter changes.
- :func:`truth_records` -- chirp records of a truth (the paper's CFD runs, §IV.A).
- :func:`truth_lco`, :func:`closed_loop_truth`, :func:`suppression_run`,
  :func:`suppression_runs`, :func:`truth_loop_sweep` -- the truth's own LCO, and the truth in
  closed loop with a controller (the wind tunnel, paper Fig. 11), in the tunnel's turbulence
  with noisy sensors (:func:`tunnel_disturbances`); :func:`limit_command` -- the software
  limiter of the flap command those runs can put before the servo.
- :func:`frozen_aero_truth` -- the truth with its aerodynamics frozen at one speed: what a
  ROM with the V² scaling of eq. 8 represents.
"""

from ._aero import JONES_A, JONES_B, jones_C, strip_coefficients, theodorsen_T
from ._base import AeroelasticTruth, AeroMatrices, SimulationResult
from ._closed_loop import (SuppressionResult, SuppressionSettings, TruthLoopSimulation,
                           TruthLoopSweep, closed_loop_truth, gain_schedule, limit_command,
                           suppression_run,
                           suppression_runs, truth_loop_matrix, truth_loop_sweep)
from ._frozen import frozen_aero_truth
from ._goland import GolandParams, GolandWing
from ._lco import TruthLco, truth_lco
from ._params import parse_sets
from ._records import RecordSettings, truth_records
from ._pitch_plunge import FlapCoefficients, PitchPlungeParams, PitchPlungeSection
from ._registry import (PROBLEMS, file_problem_names, load_problem, load_problem_file,
                        problem_definition, problem_label, problem_names)
from ._seed_wing import (SEED_FREQUENCIES_HZ, SEED_MODE_NAMES, SEED_SENSOR_ROWS, SEED_U_REF,
                         SeedWing, SeedWingParams)
from ._turbulence import dryden_gust, gust_modal_forces, tunnel_disturbances
from ._typical_section import TypicalSection, TypicalSectionParams
from ._wing_file import GAFProblem, WingProblem

__all__ = [
    "AeroelasticTruth", "AeroMatrices", "SimulationResult",
    "TypicalSection", "TypicalSectionParams", "GolandWing", "GolandParams",
    "SeedWing", "SeedWingParams", "SEED_FREQUENCIES_HZ", "SEED_MODE_NAMES", "SEED_SENSOR_ROWS",
    "SEED_U_REF",
    "PitchPlungeSection", "PitchPlungeParams", "FlapCoefficients", "WingProblem", "GAFProblem",
    "PROBLEMS", "problem_names", "file_problem_names", "load_problem", "load_problem_file",
    "problem_definition", "problem_label", "parse_sets",
    "RecordSettings", "truth_records", "frozen_aero_truth",
    "TruthLco", "truth_lco",
    "TruthLoopSimulation", "closed_loop_truth", "gain_schedule", "limit_command",
    "SuppressionSettings",
    "SuppressionResult", "suppression_run", "suppression_runs", "truth_loop_matrix",
    "TruthLoopSweep", "truth_loop_sweep", "dryden_gust", "gust_modal_forces",
    "tunnel_disturbances",
    "JONES_A", "JONES_B", "jones_C", "theodorsen_T", "strip_coefficients",
]
