"""Fixed-order robust H∞ synthesis (paper §III.C) and flutter suppression over a speed interval.

Public names: :func:`design_over_speeds` with :class:`MultiSpeedSettings`,
:class:`MultiSpeedDesign`, :class:`HoldRecord` and :func:`default_objective` (one fixed-order controller that keeps a
plant family decaying over a speed interval, with the smallest worst H∞ objective over the
speeds); :func:`synthesize` with :class:`SynthesisOptions`, :class:`SynthesisResult`,
:class:`StartRecord` (the H∞ synthesis over one plant or the worst case of several, eq. 16);
:func:`with_flap_rate` (a plant with the weighted flap rate as one more output);
:func:`load_compleib` for the benchmark plants; :func:`partition`, :class:`Partition`;
:func:`hinf_norm` / :func:`exact_hinf_norm` (the synthesis' own Hamiltonian norm) and
:func:`verify_closed_loop`; :func:`order_relaxation` with :class:`OrderBound` (what order
``k`` can reach at a few frequencies: the rank relaxation, minimised locally) and
:func:`static_direction_bound` with :class:`StaticDirectionBound` (a certified lower bound on
γ for every controller with fewer states than controls).
"""

from ._multispeed import (HoldRecord, MultiSpeedDesign, MultiSpeedSettings, default_objective,
                          design_over_speeds)
from ._norm import hinf_norm
from ._orderbound import (OrderBound, StaticDirectionBound, order_relaxation,
                          static_direction_bound)
from ._plant import Partition, exact_hinf_norm, load_compleib, partition, with_flap_rate
from ._synthesis import (StartRecord, SynthesisOptions, SynthesisResult, synthesize,
                         verify_closed_loop)

__all__ = ["design_over_speeds", "MultiSpeedSettings", "MultiSpeedDesign", "HoldRecord",
           "default_objective",
           "synthesize", "SynthesisOptions", "SynthesisResult", "StartRecord",
           "with_flap_rate", "order_relaxation", "OrderBound", "static_direction_bound",
           "StaticDirectionBound", "load_compleib", "partition", "Partition", "exact_hinf_norm",
           "hinf_norm", "verify_closed_loop"]
