"""Classical loop-at-a-time and disk margins of a multi-loop closed loop.

With ``u = s K y`` (``s = ±1``) the loop broken at the plant inputs is, in the
negative-feedback convention of :func:`control.stability_margins` (closed loop
``L / (1 + L)``), ``L_in = -s K P`` (controls × controls), and at the plant outputs
``L_out = -s P K`` (measurements × measurements).  The loop-at-a-time margin of channel j
breaks that channel only: the others stay closed, ``L_j = e_jᵀ (I + L E_j)⁻¹ L e_j`` with
``E_j`` the identity without its j-th one (:func:`control.feedback`).

The margins are read as the Nyquist criterion reads them, which is what an unstable open loop
(a plant past its flutter speed) needs: with the nominal closed loop stable, a gain k or a
phase rotation φ in the broken channel moves a closed-loop pole onto the imaginary axis
exactly where ``k L_j(jω) = -1`` or ``e^{-jφ} L_j(jω) = -1``.  So

* the **gain margins** are the factors ``k = 1/|L_j(jω)|`` at the phase crossovers (``L_j(jω)``
  real and negative, ω = 0 and ω = ∞ included): the smallest one above 1 (how much the loop
  gain may grow) and the largest one below 1 (how much it may shrink, which is what an
  unstable open loop first runs out of); the margin in dB is the nearer of the two;
* the **phase margin** is the smallest ``|∠L_j(jω) + 180°|`` over the gain crossovers
  (``|L_j(jω)| = 1``), of either sign.

Both are then what :func:`control.stability_margins` returns for a stable open loop.  Its
polynomial method fails on loops of some fifty states (the transfer function's coefficients
overflow), so the crossovers are found in state space: ``L(jω)`` is real where
``L(s) - L(-s) = 2 s C (s²I - A²)⁻¹ B`` vanishes, i.e. at ω = 0 and at the transmission zeros
``μ = -ω²`` of ``(A², B, C)`` (:meth:`control.StateSpace.zeros`, SLICOT ``AB08ND``);
``|L(jω)| = 1`` where the Hamiltonian ``H(1)`` of Bruinsma & Steinbuch has the eigenvalue jω
(:mod:`casflutter.verify._hinf`).  Each candidate is confirmed on ``L(jω)`` evaluated
directly.

The optional disk margin is :func:`control.disk_margins` of the whole ``L_in`` or ``L_out``
(the multi-loop disk margin: simultaneous, independent gain and phase changes in every
channel; SLICOT ``AB13MD``'s upper bound of μ at each frequency), evaluated on a frequency grid
that holds every lightly damped pole's frequency: an estimate on that grid, not a bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg as sla

from .._format import result_repr
from ._common import ssdata
from ._hinf import _hamiltonian

__all__ = ["LoopMargins", "MarginTable", "loop_margins", "broken_loops", "disk_margin"]

#: a crossover candidate is kept when L(jω) is real (or |L(jω)| = 1) to this relative accuracy
_CONFIRM_TOL = 1e-6
#: an eigenvalue or zero counts as imaginary when |Re| <= this × max(1, |λ|)
_AXIS_TOL = 1e-6


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of one broken loop (module docstring).

    Attributes
    ----------
    gain_increase : float
        Smallest factor ``k > 1`` that makes the closed loop marginally stable (``inf`` when
        none).
    gain_decrease : float
        Largest factor ``k < 1`` that does (``0`` when none).
    phase : float
        Phase margin in degrees (``inf`` when ``|L(jω)|`` never equals 1).
    omega_gain : float
        Frequency of the limiting phase crossover (``nan`` when none; ``inf`` at ω = ∞).
    omega_phase : float
        Frequency of the limiting gain crossover (``nan`` when none).
    """

    __repr__ = result_repr

    gain_increase: float
    gain_decrease: float
    phase: float
    omega_gain: float
    omega_phase: float

    @property
    def gain_increase_db(self) -> float:
        """``20 log10(gain_increase)``."""
        return 20 * math.log10(self.gain_increase) if self.gain_increase < math.inf \
            else math.inf

    @property
    def gain_decrease_db(self) -> float:
        """``-20 log10(gain_decrease)``."""
        return -20 * math.log10(self.gain_decrease) if self.gain_decrease > 0 else math.inf

    @property
    def gain_db(self) -> float:
        """The gain margin in dB: the nearer of the two."""
        return min(self.gain_increase_db, self.gain_decrease_db)


class _Response:
    """``L(jω)`` of a SISO state-space loop (one linear solve per frequency: a loop is
    evaluated at a few frequencies only, where a Schur form would cost more)."""

    def __init__(self, A, B, C, D):
        self.A, self.b, self.c, self.d = A, B[:, 0], C[0], complex(D[0, 0])
        self.n = A.shape[0]
        self.eye = np.eye(self.n)

    def __call__(self, omega: float) -> complex:
        if math.isinf(omega) or not self.n:
            return self.d
        x = np.linalg.solve(1j * omega * self.eye - self.A, self.b)
        return complex(self.c @ x + self.d)


def _polish(L: _Response, w0: float) -> float:
    """A phase crossover near ``w0`` to full accuracy: secant steps on ``Im L(jω)``."""
    if w0 == 0.0 or math.isinf(w0):
        return w0
    w1, w2 = w0, w0 * (1 + 1e-7)
    f1, f2 = L(w1).imag, L(w2).imag
    for _ in range(6):
        if f2 == f1:
            break
        w1, w2, f1 = w2, w2 - f2 * (w2 - w1) / (f2 - f1), f2
        f2 = L(w2).imag
        if abs(w2 - w1) <= 1e-12 * abs(w2):
            break
    return w2 if abs(w2 - w0) <= 1e-2 * w0 else w0


def _axis(values: np.ndarray) -> np.ndarray:
    values = values[np.isfinite(values)]
    on = np.abs(values.real) <= _AXIS_TOL * np.maximum(1.0, np.abs(values))
    return np.unique(np.abs(values[on].imag))


def classical_margins(L: control.StateSpace) -> LoopMargins:
    """Gain and phase margins of a SISO loop transfer in the Nyquist reading.

    Parameters
    ----------
    L : control.StateSpace
        Continuous SISO loop transfer, negative-feedback convention; the closed loop
        ``L/(1+L)`` is assumed stable (otherwise there is no margin to speak of).

    Returns
    -------
    LoopMargins
    """
    A, B, C, D = ssdata(L)
    n = A.shape[0]
    if n:   # a diagonal similarity (balancing) keeps L and makes A² well scaled
        _, (scale, _) = sla.matrix_balance(A, permute=False, separate=True)
        A, B, C = A * scale[None, :] / scale[:, None], B / scale[:, None], C * scale[None, :]
    # phase crossovers: ω = 0, the zeros μ = -ω² of (A², B, C) polished on L, and ω = ∞
    w_pc = [0.0, math.inf]
    if n:
        z = control.ss(A @ A, B, C, np.zeros_like(D)).zeros()
        z = z[np.isfinite(z)]
        neg = (np.abs(z.imag) <= 1e-3 * np.maximum(1.0, np.abs(z))) & (z.real < 0)
        w_pc += list(np.sqrt(-z[neg].real))
    ev = _Response(A, B, C, D)
    ks = []
    for w in w_pc:
        try:
            v = ev(w)
            if v.real < 0 and 1e-10 * abs(v) < abs(v.imag) <= 1e-2 * abs(v):   # polish
                w = _polish(ev, w)
                v = ev(w)
        except np.linalg.LinAlgError:      # a pole on the axis
            continue
        if v.real < 0 and abs(v.imag) <= _CONFIRM_TOL * abs(v) and np.isfinite(v):
            ks.append((1.0 / abs(v), w))
    up = [(k, w) for k, w in ks if k > 1.0]
    low = [(k, w) for k, w in ks if k <= 1.0]
    k_up, w_up = min(up) if up else (math.inf, math.nan)
    k_low, w_low = max(low) if low else (0.0, math.nan)
    up_db = 20 * math.log10(k_up) if up else math.inf
    low_db = -20 * math.log10(k_low) if low and k_low > 0 else math.inf
    w_gain = w_up if up_db <= low_db else w_low
    # gain crossovers: |L(jω)| = 1, imaginary eigenvalues of the Hamiltonian H(1)
    pm, w_phase = math.inf, math.nan
    if n and abs(abs(D[0, 0]) - 1.0) > 1e-12:
        for w in _axis(sla.eigvals(_hamiltonian(A, B, C, D, 1.0), overwrite_a=True,
                                    check_finite=False)):
            try:
                v = ev(w)
            except np.linalg.LinAlgError:
                continue
            if abs(abs(v) - 1.0) <= _CONFIRM_TOL * 1e2:
                phi = abs(math.degrees(math.atan2(v.imag, v.real)))   # in [0, 180]
                margin = 180.0 - phi
                if margin < pm:
                    pm, w_phase = margin, float(w)
    return LoopMargins(float(k_up), float(k_low), float(pm), float(w_gain), w_phase)


def _series_loop(P: control.StateSpace, K: control.StateSpace, sign: float, side: str):
    """``(A, B, C, D)`` of ``L_in = -s K P`` or ``L_out = -s P K``."""
    A, B, C, D = ssdata(P)
    Ak, Bk, Ck, Dk = ssdata(K)
    n, nk = A.shape[0], Ak.shape[0]
    if side == "input":      # u -> P -> y -> K -> v
        AL = np.block([[A, np.zeros((n, nk))], [Bk @ C, Ak]])
        BL = np.vstack([B, Bk @ D])
        CL, DL = np.hstack([Dk @ C, Ck]), Dk @ D
    else:                    # y -> K -> u -> P -> z
        AL = np.block([[Ak, np.zeros((nk, n))], [B @ Ck, A]])
        BL = np.vstack([Bk, B @ Dk])
        CL, DL = np.hstack([D @ Ck, C]), D @ Dk
    return AL, BL, -sign * CL, -sign * DL


def broken_loops(P: control.StateSpace, K: control.StateSpace, sign: float, side: str,
                 channels=None) -> list:
    """The SISO loop transfers of each channel broken alone, the others closed.

    Parameters
    ----------
    P : control.StateSpace
        The plant from the controls to the measurements.
    K : control.StateSpace
        The controller, measurements to controls.
    sign : float
        ``s`` of ``u = s K y``.
    side : {"input", "output"}
        Break at the plant inputs (``L = -s K P``) or outputs (``L = -s P K``).
    channels : sequence of int, optional
        The channels to break (default all).

    Returns
    -------
    list of control.StateSpace or None
        ``L_j`` per channel, negative-feedback convention: ``e_jᵀ (I + L E_j)⁻¹ L e_j``, the
        loop closed through :func:`control.feedback` on the other channels; None for a
        channel the controller does not use (``L_j = 0``: no margin is limited there).
    """
    AL, BL, CL, DL = _series_loop(P, K, sign, side)
    L = control.ss(AL, BL, CL, DL)
    m = L.ninputs
    Ak, Bk, Ck, Dk = ssdata(K)
    used = (np.any(Ck, axis=1) | np.any(Dk, axis=1)) if side == "input" else \
        (np.any(Bk, axis=0) | np.any(Dk, axis=0))
    out = []
    for j in (range(m) if channels is None else channels):
        if not used[j]:
            out.append(None)
            continue
        E = np.eye(m)
        E[j, j] = 0.0
        A, B, C, D = ssdata(control.feedback(L, control.ss(np.zeros((0, 0)), np.zeros((0, m)),
                                                           np.zeros((m, 0)), E)))
        out.append(control.ss(A, B[:, [j]], C[[j], :], D[[j]][:, [j]]))
    return out


def _omega_grid(L: control.StateSpace, n: int = 400) -> np.ndarray:
    """Log grid over the poles' range, with every pole's frequency |Im p| and modulus."""
    return omega_grid_of(np.asarray(L.poles()), n)


def omega_grid_of(p: np.ndarray, n: int = 400) -> np.ndarray:
    """Log grid a decade either side of the moduli of the poles ``p``, with every pole's
    frequency |Im p| and modulus (where the responses peak)."""
    p = np.asarray(p)
    mag = np.abs(p[np.abs(p) > 0])
    lo = max(1e-3, 0.1 * float(mag.min())) if mag.size else 1e-2
    hi = 10.0 * float(mag.max()) if mag.size else 1e2
    w = np.concatenate([np.logspace(np.log10(lo), np.log10(hi), n), np.abs(p.imag), mag])
    return np.unique(w[(w >= lo) & (w <= hi)])


def disk_margin(P: control.StateSpace, K: control.StateSpace, sign: float, side: str
                ) -> tuple[float, float, float]:
    """Multi-loop disk margin (α, disk gain margin dB, disk phase margin deg) at one side.

    Parameters
    ----------
    P, K : control.StateSpace
        Plant (controls to measurements) and controller.
    sign : float
        ``s`` of ``u = s K y``.
    side : {"input", "output"}
        Where the simultaneous perturbations act.

    Returns
    -------
    tuple of float
        :func:`control.disk_margins` (balanced, skew 0) of the whole loop on the grid of
        :func:`_omega_grid`.
    """
    L = control.ss(*_series_loop(P, K, sign, side))
    alpha, dgm, dpm = control.disk_margins(L, _omega_grid(L))
    return float(alpha), float(dgm), float(dpm)


@dataclass(frozen=True)
class MarginTable:
    """Margins of every loop of one side at a list of speeds.

    Attributes
    ----------
    side : str
        ``"input"`` (broken at the plant inputs, the controls) or ``"output"`` (at the
        measurements).
    loops : tuple of str
        The channels, by name.
    speeds : ndarray, shape (k,)
        Speeds.
    stable : ndarray of bool, shape (k,)
        Whether the nominal closed loop is stable at each speed (margins are ``nan``
        where it is not).
    gain_db, gain_increase_db, gain_decrease_db : ndarray, shape (k, loops)
        Gain margins in dB (``inf`` where the loop has no phase crossover).
    phase_deg : ndarray, shape (k, loops)
        Phase margins in degrees.
    omega_gain, omega_phase : ndarray, shape (k, loops)
        Frequencies of the limiting crossovers (rad per time unit).
    disk_alpha, disk_gain_db, disk_phase_deg : ndarray, shape (k,), or None
        The multi-loop disk margin, when asked for.
    """

    __repr__ = result_repr

    side: str
    loops: tuple
    speeds: np.ndarray
    stable: np.ndarray
    gain_db: np.ndarray
    gain_increase_db: np.ndarray
    gain_decrease_db: np.ndarray
    phase_deg: np.ndarray
    omega_gain: np.ndarray
    omega_phase: np.ndarray
    disk_alpha: np.ndarray | None = None
    disk_gain_db: np.ndarray | None = None
    disk_phase_deg: np.ndarray | None = None

    def to_dict(self) -> dict:
        """JSON-ready lists (non-finite numbers as floats; the CLI writes them as null).

        Returns
        -------
        dict
        """
        def col(M, j):
            return [float(x) for x in M[:, j]]
        out = {"side": self.side, "speeds": [float(v) for v in self.speeds],
               "closed_loop_stable": [bool(b) for b in self.stable],
               "loops": {name: {"gain_margin_db": col(self.gain_db, j),
                                "gain_increase_db": col(self.gain_increase_db, j),
                                "gain_decrease_db": col(self.gain_decrease_db, j),
                                "phase_margin_deg": col(self.phase_deg, j),
                                "phase_crossover_omega": col(self.omega_gain, j),
                                "gain_crossover_omega": col(self.omega_phase, j)}
                         for j, name in enumerate(self.loops)}}
        if self.disk_alpha is not None:
            out["disk"] = {"alpha": [float(x) for x in self.disk_alpha],
                           "gain_margin_db": [float(x) for x in self.disk_gain_db],
                           "phase_margin_deg": [float(x) for x in self.disk_phase_deg]}
        return out


def loop_margins(P: control.StateSpace, K: control.StateSpace, sign: float, side: str,
                 channels=None) -> list[LoopMargins]:
    """Loop-at-a-time margins of every channel of one side (module docstring).

    Parameters
    ----------
    P : control.StateSpace
        Plant from the controls to the measurements.
    K : control.StateSpace
        Controller.
    sign : float
        ``s`` of ``u = s K y``.
    side : {"input", "output"}
        Plant inputs or outputs.
    channels : sequence of int, optional
        The channels (default all).

    Returns
    -------
    list of LoopMargins
    """
    unused = LoopMargins(math.inf, 0.0, math.inf, math.nan, math.nan)
    return [unused if L is None else classical_margins(L)
            for L in broken_loops(P, K, sign, side, channels)]


def margin_table(side: str, loops, speeds, stable, per_speed, disks=None) -> MarginTable:
    """Assemble a :class:`MarginTable` from per-speed lists of :class:`LoopMargins` (None
    where the loop is unstable) and optional per-speed disk margins."""
    k, nl = len(speeds), len(loops)
    arrays = {key: np.full((k, nl), np.nan) for key in
              ("gain_db", "gain_increase_db", "gain_decrease_db", "phase_deg",
               "omega_gain", "omega_phase")}
    for i, row in enumerate(per_speed):
        if row is None:
            continue
        for j, lm in enumerate(row):
            arrays["gain_db"][i, j] = lm.gain_db
            arrays["gain_increase_db"][i, j] = lm.gain_increase_db
            arrays["gain_decrease_db"][i, j] = lm.gain_decrease_db
            arrays["phase_deg"][i, j] = lm.phase
            arrays["omega_gain"][i, j] = lm.omega_gain
            arrays["omega_phase"][i, j] = lm.omega_phase
    disk = {}
    if disks is not None:
        d = np.array([(np.nan,) * 3 if x is None else x for x in disks], dtype=float)
        disk = dict(disk_alpha=d[:, 0], disk_gain_db=d[:, 1], disk_phase_deg=d[:, 2])
    return MarginTable(side, tuple(loops), np.asarray(speeds, dtype=float),
                       np.asarray(stable, dtype=bool), **arrays, **disk)
