"""Periodic orbits (LCO) and their continuation in the speed.

Between the aeroelastic loop and the design stage: the branch of limit cycles that leaves
the flutter (Hopf) point of a nonlinear aeroelastic system, with its stability, its folds
and the criticality of the Hopf point.

- :func:`lco_branch` -- a continuous-time truth (``x' = f(x, V)``, the truths'
  :meth:`vector_field`): orthogonal collocation of one period, Floquet multipliers from the
  monodromy matrix, first Lyapunov coefficient.
- :func:`rom_lco_branch` -- the sampled-data loop of the HWL ROM (eq. 3) with Σs (eq. 7),
  a discrete map whose LCO is an invariant circle: Fourier series in the circle's angle,
  rotation number, transfer-operator stability, Neimark--Sacker coefficient.
- :func:`established_loop_lco` -- the ROM loop's LCO by simulation, continued while it
  grows; :func:`compare_lco` -- the speed-following ROM's LCO beside the wing's.
- :class:`LCOBranch`, :class:`LCOPoint`, :class:`Fold`, :class:`HopfClassification`,
  :class:`SettledMotion` (what the motion settles on above a subcritical point whose
  branch has no stable cycle) -- the frozen results (``LCOBranch.to_dict()`` is the JSON of ``casflutter lco``).
"""

from ._results import (SUBCRITICAL, SUPERCRITICAL, Fold, HopfClassification, LCOBranch,
                       LCOPoint, LCOSettings, SettledMotion)
from ._following import LcoComparison, compare_lco, established_loop_lco
from ._rom_loop import InvariantCircle, rom_lco_branch, rom_loop_flutter, rom_loop_map
from ._truth import Outputs, continue_lco, default_vrange, lco_branch, speed_convention, truth_outputs

__all__ = ["LCOSettings", "LCOPoint", "Fold", "HopfClassification", "LCOBranch",
           "SettledMotion",
           "SUPERCRITICAL", "SUBCRITICAL", "lco_branch", "continue_lco", "truth_outputs",
           "speed_convention", "default_vrange", "Outputs", "rom_lco_branch", "rom_loop_map",
           "rom_loop_flutter",
           "InvariantCircle", "established_loop_lco", "LcoComparison", "compare_lco"]
