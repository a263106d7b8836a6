"""The aeroelastic loop (paper Sec. III-A/B, eq. 6-15).

- :class:`ModalStructure` — modal structural dynamics Σs (eq. 6-7), with accelerometer,
  velocity, displacement or the paper's literal state sensors.
- :class:`AeroelasticSystem` / :func:`aeroelastic_loop` — ΣAE(V) (eq. 8-9) from Σf (eq. 5).
- :func:`track_eigenvalues`, :func:`find_flutter` — branch tracking by eigenvector
  continuity, V–g / V–f data, flutter (Hopf) and divergence speeds.
- :func:`simulate_loop` — the nonlinear discrete ROM in feedback with Σs, decay / LCO /
  divergence classification and LCO amplitude and frequency (paper Fig. 9).
- :func:`build_lft` — the uncertainty LFT of eq. 10-15 (Lemmas 1-2).
- :class:`RFASystem` — ΣAE(U) in the airspeed from a rational-function approximation of
  Q(ik), and :func:`pk_flutter`, the p-k flutter solution on a Q(ik) table.
"""

from ._flutter import Crossing, FlutterResult, find_flutter, origin_modes
from ._lft import AeroelasticLFT, build_lft
from ._pk import PKResult, pk_flutter
from ._rfa_system import RFASystem
from ._loop import AeroelasticLoop, AeroelasticSystem, aeroelastic_loop, split_sigma_f
from ._simulate import (LoopSimulation, ResponseAnalysis, analyze_response, dominant_frequency,
                        envelope_growth_rate, simulate_loop)
from ._structure import SENSOR_KINDS, ModalStructure
from ._tracking import EigenTracking, eig_sorted_by_reference, track_eigenvalues

__all__ = [
    "ModalStructure", "SENSOR_KINDS",
    "AeroelasticSystem", "AeroelasticLoop", "aeroelastic_loop", "split_sigma_f",
    "EigenTracking", "track_eigenvalues", "eig_sorted_by_reference",
    "Crossing", "FlutterResult", "find_flutter", "origin_modes",
    "AeroelasticLFT", "build_lft", "RFASystem", "PKResult", "pk_flutter",
    "LoopSimulation", "ResponseAnalysis", "simulate_loop", "analyze_response",
    "envelope_growth_rate", "dominant_frequency",
]
