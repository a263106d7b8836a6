"""Modes no controller can move: the plant's eigenvalues its controls cannot reach or its
measurements cannot see.

An eigenvalue ``λ`` of ``A`` is an eigenvalue of every closed loop ``u = K y`` (any order,
any ``K``) when ``[λI − A, B₂]`` or ``[λI − A; C₂]`` loses rank (the Popov–Belevitch–Hautus
test): the controls do not reach that mode, or the measurements do not see it.  Such a mode
bounds what a design can ask: the loop cannot decay faster than it does, and where it grows
no controller stabilises the plant.  Real models have them: an aircraft's rigid-body
position states that accelerometers do not see, a repeated aerodynamic lag pole, COMPleib's
HE6 (modes at −0.005 that the measurements do not see).  Only the modes slower than the decay
rate asked are tested, so the test costs a few singular value decompositions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr

__all__ = ["OutOfReach", "modes_out_of_reach"]

#: smallest singular value of the PBH pencil, relative to ‖A‖ (B and C scaled to ‖A‖), below
#: which a mode counts as out of reach.  A structural zero (a state no control drives, a mode
#: no sensor reads) gives 1e-16 and less; a mode in reach of a stiff plant can give 1e-9
#: (COMPleib's AC10, ‖A‖ = 1.6e7, whose flutter mode a controller does move)
_RANK_TOL = 1e-12

#: an eigenvalue this small [rad per time unit] is a pole at the origin to rounding (a time
#: constant of decades in seconds)
_ORIGIN = 1e-9


@dataclass(frozen=True)
class OutOfReach:
    """A mode of the plant that no controller moves.

    Attributes
    ----------
    eigenvalue : complex
        The mode (the one of a complex pair with ``Im >= 0``).
    reached : bool
        Whether the controls reach it.
    seen : bool
        Whether the measurements see it (at least one of ``reached`` and ``seen`` is false).
    """

    __repr__ = result_repr

    eigenvalue: complex
    reached: bool
    seen: bool

    def describe(self) -> str:
        """``"the mode at λ = -0.0232+0.0925j (unseen by the measurements)"``; a pole at
        the origin (to rounding) is named as such."""
        why = " and ".join(w for w, ok in (("unreached by the controls", self.reached),
                                          ("unseen by the measurements", self.seen)) if not ok)
        lam = complex(self.eigenvalue)
        if abs(lam) < _ORIGIN:
            return f"the mode at λ = 0 (a pole at the origin: a position or an integrator; {why})"
        text = f"{lam.real:.4g}{lam.imag:+.4g}j" if lam.imag else f"{lam.real:.4g}"
        return f"the mode at λ = {text} ({why})"


def modes_out_of_reach(A, B, C, slower_than: float) -> list[OutOfReach]:
    """The modes of ``(A, B, C)`` with ``Re λ >= −slower_than`` that no controller moves.

    Parameters
    ----------
    A, B, C : array_like
        The plant's state matrix, its control columns and its measurement rows.
    slower_than : float
        Decay rate (>= 0): only modes decaying slower than it (or growing) are tested.

    Returns
    -------
    list of OutOfReach
        Slowest first.
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    n = A.shape[0]
    B = np.asarray(B, dtype=float).reshape(n, -1)
    C = np.asarray(C, dtype=float).reshape(-1, n)
    if n == 0:
        return []
    scale = float(np.linalg.norm(A, 2)) or 1.0
    # the controls and measurements in the units of A: a gain scale does not move a mode
    Bs, Cs = (M * (scale / nm) if (nm := float(np.linalg.norm(M, 2))) > 0 else M
              for M in (B, C))
    lam = np.linalg.eigvals(A)
    out = []
    for mu in lam[(lam.real >= -slower_than) & (lam.imag >= 0)]:
        M = mu * np.eye(n) - A
        reached = np.linalg.svd(np.hstack([M, Bs]), compute_uv=False)[-1] > _RANK_TOL * scale
        seen = np.linalg.svd(np.vstack([M, Cs]), compute_uv=False)[-1] > _RANK_TOL * scale
        if not (reached and seen):
            out.append(OutOfReach(complex(mu), bool(reached), bool(seen)))
    return sorted(out, key=lambda m: -m.eigenvalue.real)
