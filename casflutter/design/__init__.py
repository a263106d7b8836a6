"""Fixed-order robust H∞ synthesis (paper §III.C) as a sequence of CasADi/Ipopt NLPs.

Public names: :func:`synthesize` with :class:`SynthesisOptions`, :class:`SynthesisResult`,
:class:`StartRecord`; :func:`load_compleib` for the benchmark plants; :func:`partition`,
:class:`Partition`; :func:`verify_closed_loop` for an independent check of a controller.
"""

from ._norm import hinf_norm
from ._plant import Partition, exact_hinf_norm, load_compleib, partition
from ._synthesis import (StartRecord, SynthesisOptions, SynthesisResult, synthesize,
                         verify_closed_loop)

__all__ = ["synthesize", "SynthesisOptions", "SynthesisResult", "StartRecord", "load_compleib",
           "partition", "Partition", "exact_hinf_norm", "hinf_norm", "verify_closed_loop"]
