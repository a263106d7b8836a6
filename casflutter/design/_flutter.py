"""Flutter suppression over a speed interval (paper §III.B-C, eq. 8-16).

The paper designs ``K(s)`` on the LFT at the flutter speed Vf (eq. 14) so that
``‖T_w̄zf‖∞ < γ`` (eq. 16); the small-gain theorem then certifies ``|V² − Vf²| < 1/γ``, an
interval much narrower than the stable interval the paper reports, V ∈ (0, 2.4).  Here the
interval is made a design requirement:

* objective: γ of the LFT at Vf (eq. 14-16), the paper's robustness measure;
* constraints: the ROM loop ΣAE(V) (eq. 8-9) closed by ``K`` decays at a rate ``decay`` at
  ``n_speeds`` speeds spread over the interval, and the algebraic loop through the
  accelerometers' flap feed-through stays well posed (``1 − Dk D22(V) >= min_det``);
* flap rate (optional): the H∞ plants gain an output ``z_r = w v̇`` (the flap rate through a
  first-order filter of bandwidth ``a``, ``z_r = w a (v − x_r)``, ``ẋ_r = a (v − x_r)``),
  so the controller does not ask for more flap rate than a servo has: without it the
  paper's order-3 design holds the seed wing's established LCO only with a flap rate far
  beyond a wind-tunnel servo's, and a rate-saturated servo lets the LCO through;
* continuation in speed: starting from the paper's design at Vf, the upper end of the
  constrained interval is pushed a step ``ΔV`` beyond the edge where the current loop still
  decays (found by a dense eigenvalue scan), each design starting from the previous
  controller, so that every start is nearly feasible; the step grows after a success and
  halves after a failure.  A last design spends the full H∞ budget on the interval reached.

The controller acts on the physical sensors (``v = K zm``, the feed-through closed exactly),
so no loop shifting is needed.  The result states the interval actually reached; the exact
interval is for the independent verification layer to certify.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import Any, Mapping

import control
import numpy as np

from .._format import result_repr
from ..aeroelastic import AeroelasticLFT, AeroelasticSystem, build_lft
from ..errors import ConfigError, SynthesisError
from ._synthesis import SynthesisOptions, SynthesisResult, synthesize

__all__ = ["FlutterDesign", "design_flutter_controller", "loop_abscissa", "with_flap_rate"]

log = logging.getLogger("casflutter.design")


@dataclass(frozen=True)
class FlutterDesign:
    """Outcome of :func:`design_flutter_controller`.

    Attributes
    ----------
    controller : control.StateSpace
        ``K(s)`` on the physical sensors ``zm`` to the flap ``v`` (``v = K zm``).
    synthesis : SynthesisResult
        The last synthesis (γ at Vf, starts, statuses).
    lft : AeroelasticLFT
        The LFT at Vf (eq. 14) on which γ is measured.
    gamma : float
        ``‖T_w̄zf‖∞`` at Vf (eq. 16).
    target : tuple of float
        Requested speed interval ``(lo, hi)`` (``()`` for the paper's single-speed design).
    reached : tuple of float
        ``(lo, hi)`` of the last interval the design met on the dense scan (``()`` if none).
    speeds : tuple of float
        Speeds of the stability constraints of the last design.
    worst_abscissa : float
        Largest closed-loop spectral abscissa (rad/s) of ΣAE(V) on the dense scan of
        ``reached`` (negative: stable there).
    met : bool
        True when ``reached`` is the target.
    """

    __repr__ = result_repr

    controller: control.StateSpace
    synthesis: SynthesisResult
    lft: AeroelasticLFT
    gamma: float
    target: tuple
    reached: tuple
    speeds: tuple
    worst_abscissa: float
    met: bool


def loop_abscissa(system: AeroelasticSystem, K: control.StateSpace, speeds) -> np.ndarray:
    """Spectral abscissa of ΣAE(V) closed by ``v = K zm`` at each speed (``inf`` where the
    algebraic loop is singular)."""
    out = []
    for V in np.atleast_1d(speeds):
        try:
            A = system.closed_loop_state_matrix(float(V), K)
        except Exception:  # noqa: BLE001 - a singular algebraic loop
            out.append(np.inf)
            continue
        out.append(float(np.max(np.linalg.eigvals(A).real)))
    return np.array(out)


def with_flap_rate(P: control.StateSpace, nmeas: int, weight: float,
                   bandwidth: float) -> control.StateSpace:
    """``P`` with one more performance output, the weighted flap rate ``z_r = w v̇``.

    The rate is taken through a first-order filter, ``ẋ_r = a (v − x_r)``,
    ``z_r = w a (v − x_r)`` (``v̇`` below the bandwidth ``a``), inserted after the existing
    performance outputs; the measurements stay the last ``nmeas`` outputs and the flap
    ``v`` the last input, as :func:`synthesize` expects.

    Parameters
    ----------
    P : control.StateSpace
        Partitioned plant (inputs ``[w, v]``, outputs ``[z, zm]``), e.g. the LFT's ``P``
        (eq. 14).
    nmeas : int
        Number of measurements (the last outputs).
    weight : float
        ``w`` [1 / (rad per time unit)]: how much one unit of flap rate counts against the
        plant's performance outputs (> 0).
    bandwidth : float
        ``a`` [rad per time unit] (> 0), e.g. the flap servo's bandwidth.

    Returns
    -------
    control.StateSpace
        One state and one output more than ``P``.
    """
    if not (weight > 0 and bandwidth > 0):
        raise ConfigError(f"flap-rate weight {weight!r} and bandwidth {bandwidth!r} must be > 0")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (P.A, P.B, P.C, P.D))
    n, m, nz = A.shape[0], B.shape[1], C.shape[0] - nmeas
    ev = np.zeros((1, m))
    ev[0, -1] = 1.0                                       # the flap command v
    a, w = float(bandwidth), float(weight)
    Aa = np.block([[A, np.zeros((n, 1))], [np.zeros((1, n)), np.full((1, 1), -a)]])
    Ba = np.vstack([B, a * ev])
    Ca = np.vstack([np.hstack([C[:nz], np.zeros((nz, 1))]),
                    np.hstack([np.zeros((1, n)), np.full((1, 1), -w * a)]),
                    np.hstack([C[nz:], np.zeros((nmeas, 1))])])
    Da = np.vstack([D[:nz], w * a * ev, D[nz:]])
    return control.ss(Aa, Ba, Ca, Da)


def _speeds(lo: float, hi: float, n: int, Vf: float) -> np.ndarray:
    return np.unique(np.concatenate([np.linspace(lo, hi, n), [Vf]]))


def design_flutter_controller(system: AeroelasticSystem, Vf: float, order: int = 3, *,
                              speeds: tuple = (1.0,), interval: tuple = (), n_speeds: int = 40, decay: float = 0.05,
                              steps: int = 4, starts: int = 3, seed: int = 0,
                              options: SynthesisOptions | Mapping[str, Any] | None = None,
                              flap_rate_weight: float = 0.0,
                              flap_rate_bandwidth: float = 251.3) -> FlutterDesign:
    """Fixed-order flutter suppression controller, robust at Vf and stable over an interval.

    Parameters
    ----------
    system : AeroelasticSystem
        Σf and Σs: ΣAE(V) of eq. 8-9 at any speed index.
    Vf : float
        Flutter speed index (the LFT of eq. 14 is built there).
    order : int
        Controller order (paper: 3).
    speeds : tuple of float
        Nominal speeds of the H∞ plants as multiples of Vf (the worst-case γ over the LFTs
        built there is minimised; ``(1.0,)`` is the paper's).
    interval : (lo, hi), optional
        Speed-index interval over which the ROM loop must stay stable; empty: the paper's
        design on the LFT at Vf alone.
    n_speeds : int
        Stability constraints spread over the interval (the dense check uses 8x as many).
    decay : float
        Decay rate (rad/s) required of ΣAE(V) at those speeds.
    steps : int
        The first continuation step is ``(hi − Vf) / steps``; at most ``6 steps`` designs.
    starts, seed : int
        Random starts of the first design and their seed (same seed, same controller).
    options : SynthesisOptions or dict, optional
        Settings of :func:`synthesize` (``decay`` is set from the argument).
    flap_rate_weight : float
        ``w`` of :func:`with_flap_rate` on every H∞ plant (0: none, the paper's design).
        γ of the result is then the norm of the weighted plant; the verification layer
        measures the paper's γ on the LFT alone.
    flap_rate_bandwidth : float
        ``a`` of :func:`with_flap_rate` [rad per time unit].

    Returns
    -------
    FlutterDesign

    Raises
    ------
    ConfigError
        A bad interval, ``n_speeds`` or ``steps``.
    SynthesisError
        If not even the loop at Vf could be stabilised.
    """
    if isinstance(options, Mapping):
        options = SynthesisOptions(**options)
    opts = replace(options or SynthesisOptions(), decay=float(decay))
    lft = build_lft(system, Vf)
    if not speeds or any(not f > 0 for f in speeds):
        raise ConfigError(f"speeds = {list(speeds)!r}: positive multiples of Vf")
    if flap_rate_weight < 0:
        raise ConfigError(f"flap_rate_weight = {flap_rate_weight!r}: >= 0 (0: no penalty)")

    def plant_at(V: float) -> control.StateSpace:
        """The LFT at ``V`` in the form every plant of the design shares: the stability
        plants carry the flap-rate output too (it adds one stable filter state), so that
        all plants have the same ``w, z, u, y`` sizes."""
        P = build_lft(system, V).P
        if flap_rate_weight > 0:
            P = with_flap_rate(P, lft.nmeas, flap_rate_weight, flap_rate_bandwidth)
        return P

    hinf = [plant_at(float(f) * Vf) for f in speeds]
    if not interval:
        syn = synthesize(hinf, lft.nmeas, lft.ncon, order, starts=starts, seed=seed,
                         options=opts)
        return FlutterDesign(syn.controller, syn, lft, syn.gamma, (), (), (Vf,),
                             float(syn.spectral_abscissa), True)
    lo, hi = (float(x) for x in interval)
    if not (0 <= lo < Vf < hi):
        raise ConfigError(f"interval = {list(interval)!r}: need 0 <= lo < Vf = {Vf:.4g} < hi")
    if n_speeds < 2 or steps < 1:
        raise ConfigError(f"n_speeds = {n_speeds} (>= 2) and steps = {steps} (>= 1) required")
    # the paper's design at Vf starts the continuation
    syn = synthesize(hinf, lft.nmeas, lft.ncon, order, starts=starts, seed=seed, options=opts)
    K = syn.controller
    dense_n = 8 * n_speeds

    def edge(Kc) -> float:
        """Largest V <= hi such that ΣAE decays at the rate ``decay`` on [lo, V]."""
        grid = np.linspace(lo, hi, dense_n)
        bad = np.flatnonzero(loop_abscissa(system, Kc, grid) > -decay)
        return float(hi if bad.size == 0 else grid[max(bad[0] - 1, 0)])

    e = edge(K)
    best = (syn, e)
    dV = (hi - Vf) / steps
    log.info("interval design: the design at Vf decays on [%.4g, %.4g] (gamma %.5g)", lo, e,
             syn.gamma)
    rounds = 0
    while e < hi and dV > 1e-3 * hi and rounds < 6 * steps:
        rounds += 1
        top = min(hi, e + dV)
        speeds = _speeds(lo, top, n_speeds, Vf)
        stab = [plant_at(float(V)) for V in speeds]
        try:
            trial = synthesize(hinf, lft.nmeas, lft.ncon, order, starts=0, seed=seed,
                               initial=K, stability_plants=stab,
                               options=replace(opts, max_outer=max(1, opts.max_outer // 4)))
            e_new = edge(trial.controller)
        except SynthesisError:
            trial, e_new = None, e
        log.debug("interval design: target V = %.4g -> decays up to %.4g", top, e_new)
        if trial is not None and e_new > e:
            K, e, dV = trial.controller, e_new, 1.5 * dV
            best = (trial, e)
        else:
            dV *= 0.5
    # the last interval reached, then the full H∞ budget on it
    syn, e = best
    speeds = _speeds(lo, e, n_speeds, Vf)
    stab = [plant_at(float(V)) for V in speeds]
    try:
        final = synthesize(hinf, lft.nmeas, lft.ncon, order, starts=0, seed=seed,
                           initial=syn.controller, stability_plants=stab, options=opts)
        if edge(final.controller) >= e:
            syn = final
    except SynthesisError:
        pass
    worst = float(np.max(loop_abscissa(system, syn.controller, np.linspace(lo, e, dense_n))))
    best = (syn, (lo, e), tuple(speeds), worst)
    syn, reached, speeds, worst = best
    return FlutterDesign(syn.controller, syn, lft, syn.gamma, (lo, hi), reached, speeds,
                         worst, bool(reached[1] >= hi))
