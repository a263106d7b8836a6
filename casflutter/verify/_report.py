"""One call that re-checks a controller: poles, exact H∞ norm, small-gain and exact
speed-index intervals (Lum et al. 2016, eq. 10-16).  Shares no code with
:mod:`casflutter.design`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np

from .._format import result_repr, sig
from ..errors import ConfigError, DimensionError
from ._common import NotHurwitzError, SystemLike, as_statespace, is_hurwitz, ssdata
from ._hinf import HinfNorm, hinf_norm
from ._interval import (StabilityInterval, feedback_stability_interval, small_gain_interval,
                        speed_interval)
from ._io import PlantData
from ._lft import lft_closed_loop

__all__ = ["VerificationReport", "verify_controller", "verify_lft", "delta_family"]


@dataclass(frozen=True)
class VerificationReport:
    """Independent verification of a controller on a partitioned plant.

    Attributes
    ----------
    closed_loop : control.StateSpace
        ``F_l(P, K)`` from ``w̄`` to ``z`` (state ``[x; xK]``).
    poles : numpy.ndarray
        Closed-loop poles (read-only), sorted by decreasing real part.
    stable : bool
        Whether the nominal closed loop is Hurwitz.
    spectral_abscissa : float
        Largest real part of the closed-loop poles.
    hinf : HinfNorm
        ``‖T_{w̄ z}‖∞`` of the whole closed loop (eq. 16), its peak frequency and method.
    Vf : float or None
        Nominal speed index (eq. 10) when the plant is an LFT in ΔV.
    n_delta : int or None
        Size of the ΔV channel: the first ``n_delta`` inputs (``wf``) and outputs (``zf``).
    hinf_delta : HinfNorm or None
        ``‖T_{wf zf}‖∞``, the channel the small-gain theorem needs (≤ ``hinf.gamma``).
    small_gain_dV, small_gain_V : tuple of float or None
        ``(-1/γ, 1/γ)`` and the speed-index interval from the paper's γ (whole ``w̄``).
    small_gain_dV_delta, small_gain_V_delta : tuple of float or None
        The same from ``hinf_delta`` (at least as large).
    exact : StabilityInterval or None
        Exact ΔV interval of closed-loop stability, ``A(ΔV) = Acl - ΔV B_wf C_zf`` (or its
        rational form when ``D_zf,wf != 0``).
    exact_V : tuple of float or None
        Exact speed-index interval, ``V = sqrt(Vf² + ΔV)``, ``V ≥ 0``.
    notes : tuple of str
        Why something was not computed, and other remarks.
    """

    __repr__ = result_repr

    closed_loop: control.StateSpace
    poles: np.ndarray
    stable: bool
    spectral_abscissa: float
    hinf: HinfNorm
    Vf: float | None = None
    n_delta: int | None = None
    hinf_delta: HinfNorm | None = None
    small_gain_dV: tuple[float, float] | None = None
    small_gain_V: tuple[float, float] | None = None
    small_gain_dV_delta: tuple[float, float] | None = None
    small_gain_V_delta: tuple[float, float] | None = None
    exact: StabilityInterval | None = None
    exact_V: tuple[float, float] | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def gamma(self) -> float:
        """``‖T_{w̄ z}‖∞`` (``inf`` for an unstable loop)."""
        return self.hinf.gamma

    def to_dict(self) -> dict:
        """JSON-serialisable summary; a non-finite number (the infinite γ of an unstable
        loop, an unbounded interval end) becomes ``None`` (``null``: strict JSON).

        Returns
        -------
        dict
        """
        def num(x):
            if x is None:
                return None
            x = float(x)
            return x if math.isfinite(x) else None

        def pair(t):
            return None if t is None else [num(t[0]), num(t[1])]

        def hn(h):
            return None if h is None else {
                "gamma": num(h.gamma), "omega_peak": num(h.omega_peak), "method": h.method,
                "stable": h.stable, "iterations": h.iterations, "tol": h.tol}

        out = {
            "nstates": self.closed_loop.nstates,
            "stable": self.stable,
            "spectral_abscissa": num(self.spectral_abscissa),
            "poles": [[num(p.real), num(p.imag)] for p in self.poles],
            "hinf": hn(self.hinf),
            "Vf": num(self.Vf),
            "n_delta": self.n_delta,
            "hinf_delta": hn(self.hinf_delta),
            "small_gain_dV": pair(self.small_gain_dV),
            "small_gain_V": pair(self.small_gain_V),
            "small_gain_dV_delta": pair(self.small_gain_dV_delta),
            "small_gain_V_delta": pair(self.small_gain_V_delta),
            "exact_dV": None if self.exact is None else [num(self.exact.lower),
                                                         num(self.exact.upper)],
            "exact_V": pair(self.exact_V),
            "exact_method": None if self.exact is None else self.exact.method,
            "notes": list(self.notes),
        }
        return out

    def format(self, max_poles: int = 8, *, speed_scale: float | None = None) -> str:
        """A readable multi-line report (numbers with 6 significant digits).

        Parameters
        ----------
        max_poles : int
            Number of rightmost closed-loop poles listed.
        speed_scale : float, optional
            Airspeed [m/s] per speed index (``U = speed_scale V``), when the plant's problem
            has one: the speed intervals are then given in m/s as well.

        Returns
        -------
        str
        """
        def f(x):
            return sig(x, 6)

        def iv(t):
            return "-" if t is None else f"({f(t[0])}, {f(t[1])})"

        def speeds(t):
            if t is None or not speed_scale:
                return iv(t)
            return f"{iv(t)}, U in {iv(tuple(speed_scale * v for v in t))} m/s"

        lines = ["casflutter verification report",
                 f"  closed loop: {self.closed_loop.nstates} states, "
                 f"{self.closed_loop.ninputs} inputs, {self.closed_loop.noutputs} outputs",
                 f"  nominal closed loop: {'STABLE' if self.stable else 'UNSTABLE'}, "
                 f"spectral abscissa {f(self.spectral_abscissa)}"]
        shown = self.poles[:max_poles]
        lines.append("  rightmost poles: " + ", ".join(
            f"{p.real:.4g}{p.imag:+.4g}j" for p in shown)
            + (" ..." if len(self.poles) > max_poles else ""))
        h = self.hinf
        lines.append(f"  H-inf norm ||T_wbar->z||: gamma = {f(h.gamma)} at omega = "
                     f"{f(h.omega_peak)} rad/s  [{h.method}]")
        if self.hinf_delta is not None:
            hd = self.hinf_delta
            lines.append(f"  H-inf norm ||T_wf->zf|| : gamma_f = {f(hd.gamma)} at omega = "
                         f"{f(hd.omega_peak)} rad/s  [{hd.method}]")
        if self.Vf is not None:
            air = f" (U = {f(speed_scale * self.Vf)} m/s)" if speed_scale else ""
            lines.append(f"  Vf = {f(self.Vf)}{air}, delta channel n_delta = {self.n_delta}; "
                         "dV = V² - Vf² (eq. 10), V the speed index")
            lines.append(f"  small gain (paper, whole wbar): dV in {iv(self.small_gain_dV)}"
                         f"  ->  V in {speeds(self.small_gain_V)}")
            lines.append(f"  small gain (wf->zf only)     : dV in "
                         f"{iv(self.small_gain_dV_delta)}  ->  V in "
                         f"{speeds(self.small_gain_V_delta)}")
            ex = None if self.exact is None else (self.exact.lower, self.exact.upper)
            lines.append(f"  exact stability ({'-' if self.exact is None else self.exact.method})"
                         f"  : dV in {iv(ex)}  ->  V in {speeds(self.exact_V)}")
        for n in self.notes:
            lines.append(f"  note: {n}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.format()


def delta_family(closed_loop: control.StateSpace, n_delta: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B_wf, C_zf, D_zf,wf)`` of the closed loop seen from the ΔV channel (eq. 15).

    Closing ``wf = -ΔV zf`` gives ``A(ΔV) = A - ΔV B_wf (I + ΔV D_zf,wf)⁻¹ C_zf``: affine
    (``A - ΔV B_wf C_zf``) when the closed-loop feedthrough vanishes (eq. 14 with state
    sensors: ``D11 = [0 Nw]``, ``D21 = 0``), rational otherwise (accelerometers with a
    controller feedthrough); :func:`feedback_stability_interval` handles both.

    Raises
    ------
    DimensionError
        If ``n_delta`` exceeds the closed loop's inputs or outputs.
    """
    A, B, C, D = ssdata(closed_loop)
    k_max = min(B.shape[1], C.shape[0])
    if isinstance(n_delta, bool) or not (isinstance(n_delta, (int, np.integer))
                                         and 0 < n_delta <= k_max):
        raise DimensionError(
            f"n_delta={n_delta!r} must be an integer in 1..{k_max} (closed loop has "
            f"{B.shape[1]} exogenous inputs and {C.shape[0]} outputs; the first n_delta "
            "of each are wf and zf)")
    return A, B[:, :n_delta], C[:n_delta, :], D[:n_delta, :n_delta]


def verify_controller(P: SystemLike | PlantData, K: SystemLike, nmeas: int | None = None,
                      ncon: int | None = None, *, Vf: float | None = None,
                      n_delta: int | None = None, delta_channel: int | None = None,
                      method: str = "auto", tol: float = 1e-10) -> VerificationReport:
    """Re-check a controller ``K`` on the partitioned plant ``P`` (eq. 14-16).

    Parameters
    ----------
    P : control.StateSpace or PlantData
        Plant, inputs ``[w̄; v]``, outputs ``[z; zm]`` (``control.hinfsyn`` convention); a
        :class:`PlantData` (:func:`load_plant`) brings its partition and ΔV channel, which
        the arguments below override.
    K : control.StateSpace or array_like
        Controller from the ``nmeas`` measurements to the ``ncon`` controls.
    nmeas, ncon : int
        Number of measurements and controls (from ``P`` when it is a :class:`PlantData`).
    Vf : float, optional
        Nominal speed index; with ``n_delta`` the ΔV intervals are computed.
    n_delta : int, optional
        The first ``n_delta`` inputs/outputs of ``P`` are ``wf``/``zf`` (eq. 13-15).
    delta_channel : int, optional
        Alias of ``n_delta``.
    method : {"auto", "slycot", "scipy"}
        H∞ norm implementation, see :func:`hinf_norm`.
    tol : float
        Relative tolerance of the H∞ norms.

    Returns
    -------
    VerificationReport
        For an unstable nominal loop: ``stable=False``, ``gamma = inf`` and no intervals
        (a note says why); this is a result, not an exception.

    Raises
    ------
    DimensionError
        Shapes of ``P`` and ``K`` that do not fit, or a bad ``n_delta``.
    IllPosedError
        Loop not well posed (``I - Dk D22`` singular).
    ConfigError
        ``Vf`` without ``n_delta`` (or the reverse), a discrete-time system, or no
        ``nmeas``/``ncon`` (neither given nor in the :class:`PlantData`).

    See Also
    --------
    speed_sweep : the closed-loop poles on a grid of speeds.
    synthesize : the controller design it checks.

    Examples
    --------
    >>> import control
    >>> import casflutter as cf
    >>> P = control.ss([[1.0]], [[1.0, 1.0]], [[1.0], [1.0]], [[0.0, 0.0], [0.0, 0.0]])
    >>> K = control.ss([], [], [], [[-3.0]])
    >>> rep = cf.verify_controller(P, K, nmeas=1, ncon=1)
    >>> rep.stable, round(rep.hinf.gamma, 4)
    (True, 0.5)
    """
    if isinstance(P, PlantData):      # the partition the file carries, unless overridden
        nmeas = P.nmeas if nmeas is None else nmeas
        ncon = P.ncon if ncon is None else ncon
        if Vf is None and n_delta is None and delta_channel is None:
            Vf, n_delta = P.Vf, P.n_delta
        P = P.sys
    if nmeas is None or ncon is None:
        raise ConfigError(f"nmeas = {nmeas!r}, ncon = {ncon!r}: give the number of "
                          "measurements and controls of the plant (or a PlantData that "
                          "holds them, e.g. load_plant('plant.json'))")
    n_delta = _delta_size(Vf, n_delta, delta_channel)
    P = as_statespace(P, "plant P")
    K = as_statespace(K, "controller K")
    cl = lft_closed_loop(P, K, nmeas, ncon)
    A, B, C, D = ssdata(cl)
    poles = np.linalg.eigvals(A) if A.size else np.zeros(0, complex)
    poles = poles[np.argsort(-poles.real, kind="stable")]
    poles.setflags(write=False)
    stable, alpha = is_hurwitz(A)
    hinf = hinf_norm(cl, method=method, tol=tol)
    notes: list[str] = []
    extra: dict = {}
    if Vf is not None:
        extra = _delta_intervals(cl, hinf, stable, alpha, Vf, n_delta, method, tol, notes)
    elif not stable:
        notes.append(f"nominal closed loop is unstable (spectral abscissa {alpha:.6g}); "
                     "the H-inf norm is infinite")
    return VerificationReport(closed_loop=cl, poles=poles, stable=stable,
                              spectral_abscissa=alpha, hinf=hinf, notes=tuple(notes), **extra)


def _delta_size(Vf, n_delta, delta_channel) -> int | None:
    """The size of the ΔV channel from ``n_delta`` or its alias ``delta_channel``, checked
    against ``Vf`` (both or neither)."""
    if delta_channel is not None:
        if n_delta is not None and n_delta != delta_channel:
            raise ConfigError(f"n_delta={n_delta} and delta_channel={delta_channel} differ; "
                              "give one of them")
        n_delta = delta_channel
    if (Vf is None) != (n_delta is None):
        raise ConfigError("give both Vf and n_delta (size of the ΔV channel, eq. 13-15) "
                          f"or neither; got Vf={Vf!r}, n_delta={n_delta!r}")
    if Vf is not None and not Vf >= 0:
        raise ConfigError(f"Vf must be >= 0, got {Vf!r}")
    return n_delta


def _delta_intervals(cl, hinf: HinfNorm, stable: bool, alpha: float, Vf, n_delta: int,
                     method: str, tol: float, notes: list) -> dict:
    """The fields of :class:`VerificationReport` about the ΔV channel: its norm, the
    small-gain intervals (eq. 16) and the exact interval of the loop ``A(ΔV)``; the reasons
    for any missing one are appended to ``notes``."""
    Ad, Bf, Cf, Dff = delta_family(cl, n_delta)
    hinf_d = hinf_norm(cl[:n_delta, :n_delta], method=method, tol=tol)
    extra = dict(Vf=float(Vf), n_delta=int(n_delta), hinf_delta=hinf_d)
    if not stable:
        notes.append("nominal closed loop is unstable (spectral abscissa "
                     f"{alpha:.6g} >= 0): gamma is infinite and no ΔV interval around "
                     "ΔV = 0 exists; the controller does not stabilise the plant at Vf")
        return extra
    for key, g in (("", hinf.gamma), ("_delta", hinf_d.gamma)):
        r = math.inf if g == 0 else 1.0 / g
        extra["small_gain_dV" + key] = (-r, r)
        extra["small_gain_V" + key] = small_gain_interval(g, Vf)
    try:
        ex = feedback_stability_interval(Ad, Bf, Cf, Dff)
    except NotHurwitzError as exc:  # pragma: no cover - guarded by `stable`
        notes.append(str(exc))
    else:
        extra.update(exact=ex, exact_V=speed_interval(ex.lower, ex.upper, Vf))
    if np.any(Dff):
        notes.append("closed-loop feedthrough D_zf,wf != 0: A(ΔV) is rational in "
                     "ΔV; the exact interval uses the rational (LFT) pencil")
    return extra


def verify_lft(lft, K: SystemLike, *, method: str = "auto",
               tol: float = 1e-10) -> VerificationReport:
    """:func:`verify_controller` for an object that carries its partition, such as
    :class:`casflutter.aeroelastic.AeroelasticLFT` (attributes ``P``, ``nmeas``,
    ``ncon``, ``Vf``, ``n_delta``; duck-typed).

    Raises
    ------
    ConfigError
        If an attribute is missing.
    """
    missing = [a for a in ("P", "nmeas", "ncon", "Vf", "n_delta") if not hasattr(lft, a)]
    if missing:
        raise ConfigError(f"{type(lft).__name__} lacks {missing}; pass the plant and its "
                          "partition to verify_controller(P, K, nmeas, ncon, Vf=, n_delta=)")
    return verify_controller(lft.P, K, lft.nmeas, lft.ncon, Vf=lft.Vf, n_delta=lft.n_delta,
                             method=method, tol=tol)
