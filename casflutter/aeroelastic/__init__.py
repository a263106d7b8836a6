"""The aeroelastic loop (paper Sec. III-A/B, eq. 6-15).

- :class:`AeroelasticSystem` / :func:`aeroelastic_loop` — ΣAE(V) (eq. 8-9) from Σf (eq. 5)
  and the modal structure Σs (:class:`casflutter.structure.ModalStructure`, eq. 6-7);
  :class:`ParametricSystem` — the same with Σf interpolated in V; :class:`TruthLoop` — the
  truth's own linearisation as the same loop (flap behind a servo), what the ROM stands in for;
  :class:`ServoSystem` (``AeroelasticSystem.with_servo``) — a ROM family behind the same servo;
  :class:`LoopFamily` — the interface they share (a loop with one flap at every speed index);
  :class:`PlantFamily` — any linear plant over a speed range (named inputs and outputs,
  controls and measurements, units, feedback convention), of which every loop family is one;
  :class:`MatrixFamily` — a family that computes ``(A, B, C, D)`` at each speed;
  :class:`GriddedFamily` — state-space models at a grid of speeds, interpolated;
  :func:`load_family` / :func:`write_family` — a gridded family from / to a family file
  (``kind = "plant_family"``: a TOML file and an ``.npz`` or MATLAB ``.mat`` data file);
  :class:`FlapWingFamily` — the Goland wing with flap segments behind actuators, rate gyros
  and accelerometers (a 50-state, 4-input, 8-output family);
  :func:`load_rom_loop` — a ROM loop kept in an ``.npz`` file.
- :func:`track_eigenvalues`, :func:`find_flutter` — branch tracking by eigenvector
  continuity, V–g / V–f data, flutter (Hopf) and divergence speeds;
  :func:`family_flutter` — every crossing of a plant family, exact derivatives on its
  polynomial pieces.
- :func:`mode_residues` — a mode's residues in the flap-to-sensor loop along V: the flap's
  grip on the flutter mode and the phase a controller needs to damp it;
  :func:`control_reversal` — the speed at which that grip dips (the mode's control reversal).
- :func:`simulate_loop` — the nonlinear discrete ROM in feedback with Σs (paper Fig. 9),
  stepped at the ROM's sample time or at the speed's own (``convective_V0``: the
  aerodynamic time scale follows the reduced frequency); :func:`structure_step` — the exact
  step of Σs over any (symbolic) step.
- :func:`speed_following_rom` — a ROM identified at one speed whose aerodynamic time scale
  follows the reduced frequency (linear and nonlinear loops), the ROM that follows the wing.
- :func:`build_lft` — the uncertainty LFT of eq. 10-15 (Lemmas 1-2).
- :class:`RFASystem` — ΣAE(U) in the airspeed from a rational-function approximation of
  Q(ik), and :func:`pk_flutter`, the p-k flutter solution on a Q(ik) table.
"""

from ._family import (FEEDBACK_SIGNS, FamilySignals, GriddedFamily, MatrixFamily, PlantFamily,
                      RealisationGap)
from ._family_flutter import family_flutter
from ._family_io import family_record, load_family, write_family
from ._flap_wing import FlapWingFamily
from ._flutter import Crossing, FlutterResult, find_flutter, origin_modes
from ._lft import AeroelasticLFT, build_lft
from ._loop import (AeroelasticLoop, AeroelasticSystem, LoopFamily, ParametricSystem,
                    ServoSystem, aeroelastic_loop, split_sigma_f)
from ._pk import PKResult, pk_flutter
from ._residues import ControlReversal, ModeResidues, control_reversal, mode_residues
from ._rfa_system import RFASystem
from ._rom_loop_file import load_rom_loop
from ._speed_following import SpeedFollowingROM, speed_following_rom
from ._simulate import (HOLDS, LoopSimulation, check_convective_V0, check_hold,
                        loop_sample_time, simulate_loop, structure_step)
from ._tracking import EigenTracking, eig_sorted_by_reference, track_eigenvalues
from ._truth_loop import TruthLoop

__all__ = [
    "PlantFamily", "MatrixFamily", "FamilySignals", "GriddedFamily", "RealisationGap",
    "FEEDBACK_SIGNS",
    "load_family", "write_family", "family_record", "FlapWingFamily", "family_flutter",
    "AeroelasticSystem", "AeroelasticLoop", "LoopFamily", "ParametricSystem", "ServoSystem",
    "aeroelastic_loop",
    "split_sigma_f",
    "EigenTracking", "track_eigenvalues", "eig_sorted_by_reference",
    "Crossing", "FlutterResult", "find_flutter", "origin_modes",
    "AeroelasticLFT", "build_lft", "RFASystem", "PKResult", "pk_flutter",
    "LoopSimulation", "simulate_loop", "structure_step", "loop_sample_time",
    "check_convective_V0", "check_hold", "HOLDS", "TruthLoop", "ModeResidues", "mode_residues",
    "ControlReversal", "control_reversal",
    "load_rom_loop", "SpeedFollowingROM", "speed_following_rom",
]
