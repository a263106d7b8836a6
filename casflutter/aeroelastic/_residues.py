"""The flap's grip on one aeroelastic mode along the speed: its residue in ΣAE(V) (eq. 8-9).

A controller ``v = K(s) zm`` (the flap command from the sensors) moves an open-loop eigenvalue
``λ`` of ΣAE(V), to first order in the controller, by

.. math:: \\delta\\lambda = K(\\lambda)\\, r, \\qquad
          r_j = \\frac{(w^H B_2)\\,(C_2 v)_j}{w^H v},

with ``v`` and ``w`` the right and left eigenvectors of ``A(V)`` at ``λ`` (the first-order
eigenvalue perturbation of ``A + B_2 K C_2``).  The residue ``r`` is what a controller has to
work with: its size is the flap's authority over the mode (times the sensors' view of it), its
phase says which phase ``K(jω)`` must have near the mode's frequency to damp it
(``Re(K r) < 0``).  Where ``r`` turns through 180° along V while the mode's frequency hardly
moves, a controller that damps the mode on one side of the turn pushes it the wrong way on
the other, to first order; only a controller whose phase changes fast enough in frequency, or
a large enough gain to move the mode far, holds both sides.  The turn comes with a dip in
``|r|``: near it the flap hardly reaches the mode (the mode's own control reversal).
:func:`control_reversal` locates that dip where the mode is unstable: the speed at which a
ROM loop must put it to stand for the wing's controllability.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ._tracking import _eig

__all__ = ["ModeResidues", "mode_residues", "ControlReversal", "control_reversal"]


@dataclass(frozen=True)
class ModeResidues:
    """Outcome of :func:`mode_residues`: one mode of ΣAE(V) and its residues along V.

    Attributes
    ----------
    V : ndarray, shape (nV,)
        Speed indices (the requested ones plus the tracking's refinement points), increasing.
    eigenvalue : ndarray, shape (nV,)
        The mode's open-loop eigenvalue (upper half-plane) at each speed.
    residues : ndarray, shape (nV, n_sensors)
        ``r_j``: the eigenvalue's first-order shift per unit static gain from sensor ``j`` to
        the flap command (``v = K zm``); for a dynamic controller ``δλ = K(λ) r``.
    worst_overlap : float
        The smallest eigenvector overlap accepted between neighbouring speeds (1: the mode
        was followed without doubt; below the call's ``min_score``: a step still ambiguous
        after ``max_refine`` bisections, e.g. where two modes veer).
    """

    __repr__ = result_repr

    V: np.ndarray
    eigenvalue: np.ndarray
    residues: np.ndarray
    worst_overlap: float

    @property
    def authority(self) -> np.ndarray:
        """``|r_j|`` per speed and sensor [rad/s per unit gain]."""
        return np.abs(self.residues)

    @property
    def grip(self) -> np.ndarray:
        """``‖r‖`` over the sensors, per speed: the flap's grip on the mode."""
        return np.linalg.norm(self.residues, axis=1)

    @property
    def phase_deg(self) -> np.ndarray:
        """``arg r_j`` per speed and sensor [deg], unwrapped along V (continuous)."""
        return np.degrees(np.unwrap(np.angle(self.residues), axis=0))

    @property
    def phase_swing_deg(self) -> np.ndarray:
        """How far each sensor's residue turns over the speeds: ``max − min`` of
        :attr:`phase_deg` [deg], per sensor."""
        p = self.phase_deg
        return p.max(axis=0) - p.min(axis=0)

    def weakest_index(self, *, unstable_only: bool = False) -> int | None:
        """Index of the speed at which the flap's grip on the mode is weakest (smallest
        :attr:`grip`).

        Parameters
        ----------
        unstable_only : bool
            Look only where the mode is unstable (``Re λ > 0``): the dip that matters to a
            controller, rather than the lowest speeds, where the flap's aerodynamic force
            vanishes with the dynamic pressure.

        Returns
        -------
        int or None
            ``None`` when ``unstable_only`` and the mode is stable at every speed.
        """
        grip = self.grip
        candidates = (np.flatnonzero(self.eigenvalue.real > 0) if unstable_only
                      else np.arange(len(self.V)))
        if candidates.size == 0:
            return None
        return int(candidates[np.argmin(grip[candidates])])

    @property
    def weakest_V(self) -> float:
        """The speed at which the flap's grip on the mode is weakest (smallest :attr:`grip`)
        over all the speeds; see :meth:`weakest_index` for the unstable ones alone."""
        return float(self.V[self.weakest_index()])


def _eig_at(family, V: float):
    """Eigenvalues, unit right eigenvectors and the loop at V."""
    lp = family.loop(float(V))
    return (*_eig(lp.A), lp)


def _follow(prev, cand):
    """The eigenpair of ``cand`` (upper half-plane) whose right eigenvector is most parallel
    to the previous one, and that overlap."""
    lam, R, _ = cand
    upper = np.flatnonzero(lam.imag > 0)
    overlap = np.abs(prev.conj() @ R[:, upper])
    k = int(np.argmax(overlap))
    return int(upper[k]), float(overlap[k])


def mode_residues(family, speeds, *, mode: complex | None = None, min_score: float = 0.9,
                  max_refine: int = 8) -> ModeResidues:
    """The residues of one mode of ΣAE(V) in the flap-to-sensor loop along the speed.

    Parameters
    ----------
    family : LoopFamily
        ΣAE(V) at any speed index (an :class:`AeroelasticSystem`, a :class:`ServoSystem`, a
        :class:`TruthLoop`, ...): ``family.loop(V)`` gives ``A``, ``B2`` (the flap or the servo
        command) and ``C2`` (the sensors).
    speeds : array_like
        Increasing, finite speed indices (at least 2).  The mode is followed along them by
        the continuity of its right eigenvector (the most parallel one of the next speed);
        a step whose overlap is below ``min_score`` is bisected, up to ``max_refine`` times.
    mode : complex, optional
        The mode: the upper-half-plane eigenvalue nearest to ``mode`` at the first speed,
        followed upwards.  Default: the flutter mode, the upper-half-plane eigenvalue with the
        largest real part at the last speed, followed downwards.
    min_score : float
        Smallest accepted eigenvector overlap between neighbouring speeds, in (0, 1).
    max_refine : int
        Bisections per step at most.

    Returns
    -------
    ModeResidues

    Raises
    ------
    ConfigError
        A family without ``loop(V)``, speeds that are not increasing and finite, a
        ``min_score`` outside (0, 1), or a loop without a complex mode.

    Notes
    -----
    With ``w`` the row of ``R⁻¹`` that belongs to the mode (so that ``w v = 1``),
    ``r_j = (w B_2) (C_2 v)_j``.  The feed-through ``D22`` of accelerometers enters
    ``A + B_2 K (I − D_22 K)⁻¹ C_2`` only at second order in ``K``.

    Examples
    --------
    >>> import numpy as np
    >>> from casflutter.aeroelastic import TruthLoop, mode_residues
    >>> from casflutter.truth import SeedWing
    >>> res = mode_residues(TruthLoop(SeedWing(), servo_omega=251.3),
    ...                     np.linspace(1.1, 2.4, 27))
    >>> bool(res.phase_swing_deg.min() > 150)        # the flap's grip turns round
    True
    """
    if not callable(getattr(family, "loop", None)):
        raise ConfigError(f"family must be a loop family with loop(V); got "
                          f"{type(family).__name__}")
    grid = np.asarray(speeds, dtype=float).ravel()
    if grid.size < 2 or not np.all(np.isfinite(grid)) or np.any(np.diff(grid) <= 0):
        raise ConfigError("speeds must hold at least 2 finite, strictly increasing speed "
                          "indices")
    if not 0.0 < min_score < 1.0:
        raise ConfigError(f"min_score must be in (0, 1), got {min_score}")
    order = grid if mode is not None else grid[::-1]
    computed: dict[float, tuple] = {}       # a bisected step comes back to its end speed

    def eig_at(V: float):
        if V not in computed:
            computed[V] = _eig_at(family, V)
        return computed[V]

    first = eig_at(float(order[0]))
    lam0 = first[0]
    upper = np.flatnonzero(lam0.imag > 0)
    if upper.size == 0:
        raise ConfigError(f"ΣAE(V = {order[0]:g}) has no complex mode to follow")
    k = int(upper[np.argmin(np.abs(lam0[upper] - complex(mode)))] if mode is not None
            else upper[np.argmax(lam0[upper].real)])
    points = [(float(order[0]), first, k)]
    worst = 1.0
    for V in order[1:]:
        pending = [(float(V), 0)]
        while pending:
            Vb, depth = pending[-1]
            Va, cand_a, ka = points[-1]
            cand = eig_at(Vb)
            kb, score = _follow(cand_a[1][:, ka], cand)
            if score < min_score and depth < max_refine:
                pending[-1] = (Vb, depth + 1)
                pending.append((0.5 * (Va + Vb), depth + 1))
                continue
            pending.pop()
            points.append((Vb, cand, kb))
            worst = min(worst, score)
    if mode is None:
        points.reverse()
    res = []
    for _, (lam, R, lp), b in points:
        w = np.linalg.solve(R.T, np.eye(R.shape[0])[b])     # row b of R⁻¹: w v = 1
        res.append((w @ lp.B2) * (lp.C2 @ R[:, b]))
    return ModeResidues(np.array([p[0] for p in points]),
                        np.array([p[1][0][p[2]] for p in points]), np.array(res), worst)


@dataclass(frozen=True)
class ControlReversal:
    """Outcome of :func:`control_reversal`: where the flap's grip on an unstable mode dips.

    Attributes
    ----------
    V : float
        Speed index of the weakest grip (:attr:`ModeResidues.grip`) among the speeds at which
        the mode is unstable.
    eigenvalue : complex
        The mode's open-loop eigenvalue there.
    grip : float
        ``‖r‖`` there.
    grip_at_onset : float
        ``‖r‖`` at the first unstable speed of the scan (near the flutter speed).
    residues : ModeResidues
        The scan over the whole speed range (the mode, its residues and its phase turn).
    """

    __repr__ = result_repr

    V: float
    eigenvalue: complex
    grip: float
    grip_at_onset: float
    residues: ModeResidues


def control_reversal(family, speeds, *, mode: complex | None = None,
                     n_fine: int = 41) -> ControlReversal | None:
    """The control reversal speed of a mode of ΣAE(V): the speed, among those where the mode
    is unstable, at which the flap's grip on it is weakest.

    The residues of :func:`mode_residues` are scanned over ``speeds``; the smallest grip
    ``‖r‖`` where ``Re λ > 0`` is then located on a finer grid of ``n_fine`` speeds between
    the scan's neighbours of that point (the mode followed up from the lower neighbour).  The
    dip comes with the residue's turn through 180° (module docstring), so this is where a
    controller that damps the mode below it pushes it the wrong way above it.

    Parameters
    ----------
    family : LoopFamily
        ΣAE(V) with ``loop(V)`` (a ROM loop, a :class:`TruthLoop`, either behind a servo:
        ``family.with_servo(omega)``).
    speeds : array_like
        Increasing, finite speed indices of the scan (at least 3).
    mode : complex, optional
        The mode, as for :func:`mode_residues` (default: the flutter mode, the most unstable
        one at the last speed).
    n_fine : int
        Points of the refinement grid (at least 3).

    Returns
    -------
    ControlReversal or None
        ``None`` when the mode is stable at every speed of the scan.

    Raises
    ------
    ConfigError
        As :func:`mode_residues`, or ``n_fine < 3``.

    Examples
    --------
    >>> import numpy as np
    >>> from casflutter.aeroelastic import TruthLoop, control_reversal
    >>> from casflutter.truth import SeedWing
    >>> wing = TruthLoop(SeedWing(), servo_omega=251.3)      # the flap behind a 40 Hz servo
    >>> rev = control_reversal(wing, np.linspace(0.05, 2.4, 48))
    >>> 1.4 < rev.V < 1.5                      # the wing's flutter mode reverses near 1.46
    True
    """
    if isinstance(n_fine, bool) or not isinstance(n_fine, (int, np.integer)) or n_fine < 3:
        raise ConfigError(f"n_fine = {n_fine!r}: give an integer >= 3")
    grid = np.asarray(speeds, dtype=float).ravel()
    if grid.size < 3:
        raise ConfigError("speeds must hold at least 3 finite, strictly increasing speed "
                          "indices")
    scan = mode_residues(family, grid, mode=mode)
    k = scan.weakest_index(unstable_only=True)
    if k is None:
        return None
    unstable = np.flatnonzero(scan.eigenvalue.real > 0)
    lo, hi = max(k - 1, 0), min(k + 1, len(scan.V) - 1)
    fine = mode_residues(family, np.linspace(scan.V[lo], scan.V[hi], int(n_fine)),
                         mode=scan.eigenvalue[lo])
    j = fine.weakest_index(unstable_only=True)
    best = (fine.V[j], fine.eigenvalue[j], fine.grip[j]) if j is not None and (
        fine.grip[j] < scan.grip[k]) else (scan.V[k], scan.eigenvalue[k], scan.grip[k])
    return ControlReversal(V=float(best[0]), eigenvalue=complex(best[1]), grip=float(best[2]),
                           grip_at_onset=float(scan.grip[unstable[0]]), residues=scan)
