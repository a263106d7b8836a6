"""Flutter (Hopf) and static-divergence analysis over a speed-index range.

By Hopf bifurcation analysis the onset of flutter is the crossing of the imaginary axis
by a complex pair of eigenvalues of ΣAE as V increases past Vf (paper Sec. III-B);
static divergence is a real eigenvalue passing through zero.  :func:`find_flutter`
tracks every branch with :func:`track_eigenvalues`, reports every sign change of
Re λ on every branch, and refines each one with Brent's method on
``V -> Re λ_branch(V)``, the branch being followed by eigenvector continuity inside
the bracket (never by sorting).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, linear_sum_assignment

from .._format import result_repr
from ..errors import ConfigError
from ._tracking import (EigenTracking, as_matrix_fn, eig_sorted_by_reference,
                        track_eigenvalues)

__all__ = ["Crossing", "FlutterResult", "find_flutter", "origin_modes"]


@dataclass(frozen=True)
class Crossing:
    """One imaginary-axis crossing of one eigenvalue branch.

    Attributes
    ----------
    V : float
        Speed index of the crossing (Brent root of Re λ, relative tolerance ``xtol_rel``).
    eigenvalue : complex
        λ of the branch at ``V`` (Re λ ≈ 0).
    omega : float
        Frequency ``|Im λ|`` [rad/s] at the crossing (0 for divergence).
    frequency_hz : float
        ``omega / 2π`` [Hz].
    branch : int
        Branch index in the :class:`EigenTracking`.
    origin_mode : int
        Structural mode (0-based) the branch comes from at the lowest V, or -1 when unknown.
    kind : str
        ``"flutter"`` (complex pair, Hopf) or ``"divergence"`` (real eigenvalue through 0).
    direction : str
        ``"destabilizing"`` (Re λ goes − → +) or ``"stabilizing"``.
    slope : float
        d Re λ / dV at the crossing (central difference).
    converged : bool
        True when Brent's method converged inside the bracket.
    bracket : tuple of float
        Grid interval that contained the sign change.
    """

    __repr__ = result_repr

    V: float
    eigenvalue: complex
    omega: float
    frequency_hz: float
    branch: int
    origin_mode: int
    kind: str
    direction: str
    slope: float
    converged: bool
    bracket: tuple


@dataclass(frozen=True)
class FlutterResult:
    """Outcome of :func:`find_flutter`.

    Attributes
    ----------
    status : str
        ``"flutter"`` when a destabilizing flutter crossing was found, otherwise
        ``"divergence"`` when only a destabilizing divergence was found, otherwise
        ``"no_crossing"``.  ``Vf`` is ``None`` unless status is ``"flutter"``.
    Vf : float or None
        Flutter speed index (first destabilizing flutter crossing).
    omega_f : float or None
        Flutter frequency [rad/s].
    frequency_hz : float or None
        Flutter frequency [Hz].
    flutter_mode : int or None
        Structural mode (0-based) the flutter branch comes from.
    flutter : Crossing or None
        The first destabilizing flutter crossing.
    divergence : Crossing or None
        The first destabilizing divergence crossing.
    crossings : tuple of Crossing
        Every crossing in the range, ordered by V (conjugate duplicates removed).
    unstable_at_start : bool
        True when some eigenvalue has Re λ > 0 at the lowest V (e.g. an unstable ROM):
        crossings are then not onsets of instability and ``message`` says so.
    spectral_abscissa_start : float
        max Re λ at the lowest V.
    tracking : EigenTracking
        The branch data (V–g / V–f, root loci).
    origin : ndarray of int
        Origin mode of every branch (-1 unknown).
    message : str
        Human-readable summary.
    """

    __repr__ = result_repr

    status: str
    Vf: float | None
    omega_f: float | None
    frequency_hz: float | None
    flutter_mode: int | None
    flutter: Crossing | None
    divergence: Crossing | None
    crossings: tuple
    unstable_at_start: bool
    spectral_abscissa_start: float
    tracking: EigenTracking
    origin: np.ndarray
    message: str

    @property
    def found(self) -> bool:
        """True when a flutter speed was found in the range."""
        return self.Vf is not None

    def onsets(self, speed_unit: str = "", time_unit: str = "s") -> str:
        """The open-loop instabilities in one line, numbers to 5 digits: each destabilising
        crossing (flutter with its frequency, divergence), and whether the system is
        unstable already at the low end of the range.

        Parameters
        ----------
        speed_unit, time_unit : str
            Units for the words (the speeds' and the frequencies' rad per time unit).

        Returns
        -------
        str
        """
        su = f" {speed_unit}" if speed_unit else ""
        words = [f"{c.kind} at {c.V:.5g}{su}" + (
            f" ({c.omega:.5g} rad/{time_unit})" if c.kind == "flutter" else "")
            for c in self.crossings if c.direction == "destabilizing"]
        text = "; ".join(words) or "no crossing into instability in the range"
        if self.unstable_at_start:
            text += (f"; unstable already at {self.tracking.V[0]:.5g}{su} (spectral "
                     f"abscissa {self.spectral_abscissa_start:.3g} /{time_unit})")
        return text


def origin_modes(tracking: EigenTracking, *, mode_states=None, omega=None) -> np.ndarray:
    """Structural mode each branch comes from, judged at the lowest V.

    With ``mode_states`` (state indices of each structural mode, as in
    :attr:`AeroelasticSystem.mode_states`, states ``[u_i, u̇_i]``), the branch's right
    eigenvector at ``V[0]`` is split into per-mode energies ``ω_i² |x_u|² + |x_u̇|²``
    (the two-state form; a plain squared norm otherwise) and the mode with the largest
    energy fraction (relative to the whole eigenvector, the non-structural states counted
    by their squared magnitude) is attributed to it, exactly two branches per mode (the
    assignment maximising the total fraction, :func:`scipy.optimize.linear_sum_assignment`);
    the remaining branches (aerodynamic lags of Σf) get -1.  Otherwise, with ``omega`` (natural frequencies), the mode whose
    ω_i is nearest to ``|λ|`` in relative terms is the origin.  Returns -1 for every branch
    when neither is given.
    """
    lam0 = tracking.eigenvalues[0]
    vec0 = tracking.eigenvectors[0]
    nb = lam0.size
    if mode_states is not None:
        om = None if omega is None else np.asarray(omega, dtype=float)
        E = np.zeros((len(mode_states), nb))
        for i, idx in enumerate(mode_states):
            idx = np.asarray(idx)
            comp = np.abs(vec0[idx, :]) ** 2
            if om is not None and idx.size == 2:
                comp = comp * np.array([[om[i] ** 2], [1.0]])
            E[i] = comp.sum(axis=0)
        idx_all = np.concatenate([np.asarray(i) for i in mode_states])
        rest = np.ones(vec0.shape[0], dtype=bool)
        rest[idx_all] = False
        frac = E / (E.sum(axis=0) + (np.abs(vec0[rest, :]) ** 2).sum(axis=0))
        # two branches (a conjugate pair, or two real roots) per structural mode
        rows, cols = linear_sum_assignment(-np.repeat(frac, 2, axis=0))
        out = -np.ones(nb, dtype=int)
        out[cols] = rows // 2
        return out
    if omega is not None:
        om = np.asarray(omega, dtype=float)
        rel = np.abs(np.abs(lam0)[None, :] - om[:, None]) / om[:, None]
        return np.argmin(rel, axis=0).astype(int)
    return -np.ones(nb, dtype=int)


def _refine(fn, tracking: EigenTracking, k: int, b: int, xtol_rel: float):
    """Brent root of Re λ_b on [V[k], V[k+1]] following branch b by eigenvectors."""
    Va, Vb = tracking.V[k], tracking.V[k + 1]
    lam_ref, R_ref = tracking.eigenvalues[k], tracking.eigenvectors[k]

    def branch(V):
        lam, _, _ = eig_sorted_by_reference(fn(V), R_ref, lam_ref)
        return lam[b]

    fa, fb = tracking.eigenvalues[k, b].real, tracking.eigenvalues[k + 1, b].real
    if fa == 0.0:
        return Va, tracking.eigenvalues[k, b], True
    if fb == 0.0:
        return Vb, tracking.eigenvalues[k + 1, b], True
    try:
        Vc, info = brentq(lambda V: branch(V).real, Va, Vb,
                          xtol=xtol_rel * max(abs(Va), abs(Vb)) * 1e-2, rtol=max(xtol_rel * 1e-2, 1e-15),
                          maxiter=200, full_output=True, disp=False)
        ok = bool(info.converged)
    except ValueError:  # sign not confirmed by the re-matched branch ends
        Vc, ok = 0.5 * (Va + Vb), False
    return float(Vc), complex(branch(Vc)), ok


def find_flutter(system, V_range=None, *, V_grid=None, n_grid: int = 101, mode_states=None,
                 omega=None, xtol_rel: float = 1e-10, min_score: float = 0.9,
                 max_refine: int = 8) -> FlutterResult:
    """Locate flutter (Hopf) and divergence speeds of ``A(V)`` in a range of V.

    Parameters
    ----------
    system : callable or object with ``state_matrix(V)``
        ``V -> A(V)``; an :class:`AeroelasticSystem` or a truth simulator also supplies
        ``mode_states`` and the structural ``omega`` for the origin-mode attribution.
    V_range : (float, float), optional
        Lowest and highest speed index; a uniform grid of ``n_grid`` points is used.
    V_grid : array_like, optional
        Explicit increasing grid (instead of ``V_range``).
    n_grid : int
        Points of the uniform grid.
    mode_states, omega :
        Origin-mode information, see :func:`origin_modes` (taken from ``system`` if it has
        ``mode_states`` / ``structure.omega`` / ``modal_structure().omega`` and these are
        not given).
    xtol_rel : float
        Relative tolerance of the Brent refinement on V (default 1e-10, i.e. well inside
        the 1e-8 target).
    min_score, max_refine :
        Passed to :func:`track_eigenvalues`.

    Returns
    -------
    FlutterResult
        ``status == "no_crossing"`` and ``Vf is None`` when nothing crosses in the range.

    See Also
    --------
    track_eigenvalues : the eigenvalue branches it follows.
    build_lft : the LFT at the flutter speed found here.
    lco_branch : the LCO branch from the Hopf point.

    Notes
    -----
    Crossings are detected as sign changes of Re λ of a branch between neighbouring grid
    points, so a branch that crosses and re-crosses inside one grid interval (a very narrow
    hump) is missed: use a grid finer than the narrowest hump of interest.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> f = cf.find_flutter(truth, (0.5, 3.0))
    >>> f.status, round(f.Vf, 4), round(f.omega_f, 4)
    ('flutter', 2.1704, 0.6443)
    """
    fn = as_matrix_fn(system)
    V_grid = _speed_grid(V_range, V_grid, n_grid)
    mode_states, omega = _origin_information(system, mode_states, omega)
    tr = track_eigenvalues(fn, V_grid, min_score=min_score, max_refine=max_refine)
    origin = origin_modes(tr, mode_states=mode_states, omega=omega)
    lam = tr.eigenvalues
    scale = max(float(np.max(np.abs(lam))), 1.0)
    sa0 = float(np.max(lam[0].real))
    unstable0 = sa0 > 1e-12 * scale
    crossings = _crossings(fn, tr, origin, scale, xtol_rel)
    flut = next((c for c in crossings if c.kind == "flutter" and c.direction == "destabilizing"), None)
    div = next((c for c in crossings if c.kind == "divergence" and c.direction == "destabilizing"), None)
    status, msg = _status_message(flut, div, tr)
    if unstable0:
        msg += (f"; WARNING: unstable already at V = {tr.V[0]:g} (spectral abscissa {sa0:.3g}), "
                "e.g. an unstable ROM: crossings are not instability onsets")
        warnings.warn(msg, RuntimeWarning, stacklevel=2)
    if any(not c.converged for c in crossings):
        msg += "; some crossings were not refined to tolerance (see Crossing.converged)"
    return FlutterResult(
        status=status, Vf=None if flut is None else flut.V,
        omega_f=None if flut is None else flut.omega,
        frequency_hz=None if flut is None else flut.frequency_hz,
        flutter_mode=None if flut is None else flut.origin_mode, flutter=flut, divergence=div,
        crossings=tuple(crossings), unstable_at_start=unstable0, spectral_abscissa_start=sa0,
        tracking=tr, origin=origin, message=msg)


def _speed_grid(V_range, V_grid, n_grid: int) -> np.ndarray:
    """The speed grid of :func:`find_flutter`: ``V_grid`` or ``n_grid`` points on
    ``V_range``."""
    if V_grid is not None:
        return V_grid
    if V_range is None or len(V_range) != 2 or not V_range[0] < V_range[1]:
        raise ConfigError("give V_range=(V_low, V_high) with V_low < V_high, or V_grid")
    if n_grid < 2:
        raise ConfigError(f"n_grid must be >= 2, got {n_grid}")
    return np.linspace(float(V_range[0]), float(V_range[1]), int(n_grid))


def _origin_information(system, mode_states, omega):
    """``mode_states`` and ``omega`` for :func:`origin_modes`: the given ones, else the
    system's (``mode_states``, ``structure.omega`` or a truth's ``modal_structure().omega``)."""
    if mode_states is None:
        mode_states = getattr(system, "mode_states", None)
    if omega is None and hasattr(system, "structure"):
        omega = system.structure.omega
    elif omega is None and hasattr(system, "modal_structure"):  # a truth simulator
        omega = system.modal_structure().omega
    return mode_states, omega


def _crossings(fn, tr: EigenTracking, origin, scale: float, xtol_rel: float) -> list:
    """Every imaginary-axis crossing of the tracked branches, refined by Brent's method and
    sorted by speed (one per conjugate pair)."""
    crossings = []
    re = tr.eigenvalues.real
    for b in range(tr.n_branches):
        s = np.sign(re[:, b])
        for k in np.flatnonzero(s[:-1] * s[1:] < 0):
            Vc, lc, ok = _refine(fn, tr, int(k), b, xtol_rel)
            divergence = abs(lc.imag) <= 1e-7 * scale
            if not divergence and lc.imag < 0:
                continue  # the conjugate partner reports this crossing
            h = 1e-6 * max(abs(Vc), 1.0)
            lo, hi = max(Vc - h, tr.V[k]), min(Vc + h, tr.V[k + 1])
            lam_ref, R_ref = tr.eigenvalues[k], tr.eigenvectors[k]
            slope = (eig_sorted_by_reference(fn(hi), R_ref, lam_ref)[0][b].real
                     - eig_sorted_by_reference(fn(lo), R_ref, lam_ref)[0][b].real) / (hi - lo)
            crossings.append(Crossing(
                V=Vc, eigenvalue=lc, omega=0.0 if divergence else abs(lc.imag),
                frequency_hz=0.0 if divergence else abs(lc.imag) / (2 * np.pi), branch=b,
                origin_mode=int(origin[b]), kind="divergence" if divergence else "flutter",
                direction="destabilizing" if re[k + 1, b] > re[k, b] else "stabilizing",
                slope=float(slope), converged=ok, bracket=(float(tr.V[k]), float(tr.V[k + 1]))))
    crossings.sort(key=lambda c: c.V)
    return crossings


def _status_message(flut, div, tr: EigenTracking) -> tuple[str, str]:
    """The status of :class:`FlutterResult` and its one-line summary."""
    if flut is not None:
        return "flutter", (
            f"flutter at V = {flut.V:.6g}, {flut.omega:.6g} rad/s ({flut.frequency_hz:.6g} Hz), "
            + (f"structural mode {flut.origin_mode + 1} (numbered from 1)"
               if flut.origin_mode >= 0 else f"branch {flut.branch} (not a structural mode)"))
    if div is not None:
        return "divergence", f"no flutter; static divergence at V = {div.V:.6g}"
    return "no_crossing", (f"no eigenvalue crosses the imaginary axis for V in [{tr.V[0]:g}, "
                           f"{tr.V[-1]:g}]; no flutter speed in this range (extend the range)")
