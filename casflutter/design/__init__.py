"""Fixed-order robust H∞ synthesis (paper §III.C) and flutter suppression over a speed interval.

Public names: :func:`synthesize` with :class:`SynthesisOptions`, :class:`SynthesisResult`,
:class:`StartRecord`; :func:`design_flutter_controller` with :class:`FlutterDesign` (the
LFT at Vf plus stability of ΣAE(V) over an interval, eq. 8-16); :func:`load_compleib` for
the benchmark plants; :func:`partition`, :class:`Partition`; :func:`hinf_norm` /
:func:`exact_hinf_norm` (the synthesis' own Hamiltonian norm) and :func:`verify_closed_loop`;
:func:`stabilize_interval` with :func:`full_order_start` and :class:`IntervalReach` (how far
one controller holds ΣAE(V) stable, by continuation in speed), :func:`search_random_starts`
with :class:`RandomStartSearch` (seeded random low-order starts at one end, continued) and :func:`reduce_order` with
:class:`OrderReduction` (the same interval at lower orders, by continuation in the order),
chained by :func:`design_interval_controller` (:class:`IntervalDesign`); :func:`order_relaxation` with
:class:`OrderBound` (what order ``k`` can reach at a few frequencies: the rank relaxation,
minimised locally) and :func:`static_direction_bound` with :class:`StaticDirectionBound` (a
certified lower bound on γ for every controller with fewer states than controls).
"""

from ._flutter import FlutterDesign, design_flutter_controller, loop_abscissa, with_flap_rate
from ._interval import (IntervalDesign, IntervalReach, OrderReduction, OrderStep,
                        design_interval_controller, full_order_start, reduce_order,
                        stabilize_interval)
from ._interval_search import RandomStartSearch, search_random_starts
from ._norm import hinf_norm
from ._orderbound import (OrderBound, StaticDirectionBound, order_relaxation,
                          static_direction_bound)
from ._plant import Partition, exact_hinf_norm, load_compleib, partition
from ._synthesis import (StartRecord, SynthesisOptions, SynthesisResult, synthesize,
                         verify_closed_loop)

__all__ = ["synthesize", "SynthesisOptions", "SynthesisResult", "StartRecord",
           "design_flutter_controller", "with_flap_rate", "FlutterDesign", "loop_abscissa",
           "stabilize_interval", "full_order_start", "IntervalReach",
           "reduce_order", "OrderReduction", "OrderStep", "design_interval_controller",
           "IntervalDesign", "search_random_starts", "RandomStartSearch",
           "order_relaxation", "OrderBound", "static_direction_bound", "StaticDirectionBound",
           "load_compleib", "partition", "Partition", "exact_hinf_norm", "hinf_norm", "verify_closed_loop"]
