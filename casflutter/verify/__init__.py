"""Independent verification of controllers (Lum et al., ACC 2016, eq. 10-16).

Closed-loop poles, the exact H∞ norm with its peak frequency (SLICOT ``AB13DD`` via
slycot, or a numpy/scipy Hamiltonian implementation), the small-gain speed interval
and the exact speed interval of closed-loop stability (bialternate-sum guardian map), on the
paper's LFT or on any loop polynomial in the speed index (a truth's own linearisation), and
the time response of a loop whose speed changes under controllers switched with the speed;
and on any plant family (:class:`casflutter.aeroelastic.PlantFamily`) the certified stable
interval of a controller, its absolute and robust flutter speeds and its loop-at-a-time
margins (:func:`verify_family`), and how far a model family's response lies from the plant's
it stands for (:func:`model_mismatch`).
Uses python-control, slycot, numpy and scipy only; shares no code with
:mod:`casflutter.design`, whose results it re-checks.
"""

from ._common import IllPosedError, NotHurwitzError
from ._family import ClosedLoopCrossing, FamilyVerification, verify_family
from ._family_controller import FamilyController, match_controller
from ._family_interval import CertifiedInterval, PieceCertificate, certified_interval
from ._hinf import HinfNorm, hinf_norm, sigma_max, slycot_available
from ._interval import (StabilityInterval, bialternate_sum, feedback_stability_interval,
                        polynomial_stability_interval, small_gain_interval,
                        speed_family_interval, speed_interval, stability_interval)
from ._io import (PlantData, controller_from_json, controller_to_json, load_controller,
                  load_plant, plant_from_json, plant_to_json, save_json)
from ._lft import lft_closed_loop, partition_plant
from ._mismatch import ModelMismatch, model_mismatch
from ._margins import (LoopMargins, MarginTable, broken_loops, classical_margins, disk_margin,
                       loop_margins)
from ._report import VerificationReport, delta_family, verify_controller, verify_lft
from ._schedule import ScheduledResponse, scheduled_response
from ._sweep import SpeedSweep, speed_sweep

__all__ = [
    "IllPosedError", "NotHurwitzError",
    "HinfNorm", "hinf_norm", "sigma_max", "slycot_available",
    "StabilityInterval", "bialternate_sum", "feedback_stability_interval",
    "small_gain_interval", "speed_interval",
    "stability_interval", "polynomial_stability_interval", "speed_family_interval",
    "PlantData", "controller_from_json", "controller_to_json", "load_controller", "load_plant",
    "plant_from_json", "plant_to_json", "save_json",
    "lft_closed_loop", "partition_plant",
    "VerificationReport", "delta_family", "verify_controller", "verify_lft",
    "SpeedSweep", "speed_sweep", "ScheduledResponse", "scheduled_response",
    "verify_family", "FamilyVerification", "ClosedLoopCrossing", "FamilyController",
    "match_controller", "certified_interval", "CertifiedInterval", "PieceCertificate",
    "LoopMargins", "MarginTable", "classical_margins", "broken_loops", "loop_margins",
    "disk_margin", "ModelMismatch", "model_mismatch",
]
