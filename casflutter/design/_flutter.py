"""Flutter suppression over a speed interval (paper §III.B-C, eq. 8-16).

The paper designs ``K(s)`` on the LFT at the flutter speed Vf (eq. 14) so that
``‖T_w̄zf‖∞ < γ`` (eq. 16); the small-gain theorem then certifies ``|V² − Vf²| < 1/γ``, an
interval much narrower than the stable interval the paper reports, V ∈ (0, 2.4).  Here the
interval is made a design requirement:

* objective: γ of the LFT at Vf (eq. 14-16), the paper's robustness measure;
* constraints: the ROM loop ΣAE(V) (eq. 8-9) closed by ``K`` decays at a rate ``decay`` at
  ``n_speeds`` speeds spread over the interval, and the algebraic loop through the
  accelerometers' flap feed-through stays well posed (``1 − Dk D22(V) >= min_det``);
* continuation in speed: the upper end is raised in steps from just above Vf to the target,
  each design starting from the previous controller (a loop that is stable up to ``V`` is
  a good start for ``V + ΔV``); a dense eigenvalue scan after each design adds any speed
  where the loop misbehaves between the grid points and designs again.

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

from ..aeroelastic import AeroelasticLFT, AeroelasticSystem, build_lft
from ..errors import ConfigError, SynthesisError
from ._synthesis import SynthesisOptions, SynthesisResult, synthesize

__all__ = ["FlutterDesign", "design_flutter_controller", "loop_abscissa"]

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


def _speeds(lo: float, hi: float, n: int, Vf: float) -> np.ndarray:
    return np.unique(np.concatenate([np.linspace(lo, hi, n), [Vf]]))


def design_flutter_controller(system: AeroelasticSystem, Vf: float, order: int = 3, *,
                              speeds: tuple = (1.0,), interval: tuple = (), n_speeds: int = 40, decay: float = 0.05,
                              steps: int = 4, starts: int = 3, seed: int = 0,
                              options: SynthesisOptions | Mapping[str, Any] | None = None
                              ) -> FlutterDesign:
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
        Continuation steps of the upper end from ``1.1 Vf`` to ``hi``.
    starts, seed : int
        Random starts of the first design and their seed (same seed, same controller).
    options : SynthesisOptions or dict, optional
        Settings of :func:`synthesize` (``decay`` is set from the argument).

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
    hinf = [build_lft(system, float(f) * Vf).P for f in speeds]
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
    ends = np.linspace(min(1.1 * Vf, hi), hi, steps) if steps > 1 else np.array([hi])
    best: tuple | None = None
    initial = None
    for k, top in enumerate(ends):
        speeds = _speeds(lo, float(top), n_speeds, Vf)
        dense = np.linspace(lo, float(top), 8 * n_speeds)
        ok = False
        for refine in range(3):
            stab = [build_lft(system, float(V)).P for V in speeds]
            try:
                syn = synthesize(hinf, lft.nmeas, lft.ncon, order,
                                 starts=starts if initial is None else 1, seed=seed,
                                 initial=initial, stability_plants=stab, options=opts)
            except SynthesisError as exc:
                log.info("interval design up to V = %.4g: %s", top, exc)
                break
            a = loop_abscissa(system, syn.controller, dense)
            worst = float(np.max(a))
            log.info("interval design up to V = %.4g: gamma %.5g, worst abscissa %.4g rad/s "
                     "on the dense scan", top, syn.gamma, worst)
            initial = syn.controller
            if worst < 0:
                ok = True
                best = (syn, (lo, float(top)), tuple(speeds), worst)
                break
            speeds = np.unique(np.concatenate([speeds, dense[a >= -decay]]))
        if not ok:
            break
    if best is None:
        log.info("no interval design succeeded; the design on the LFT alone is returned")
        syn = synthesize(hinf, lft.nmeas, lft.ncon, order, starts=starts, seed=seed,
                         options=opts)
        return FlutterDesign(syn.controller, syn, lft, syn.gamma, (lo, hi), (), (Vf,),
                             float(syn.spectral_abscissa), False)
    syn, reached, speeds, worst = best
    return FlutterDesign(syn.controller, syn, lft, syn.gamma, (lo, hi), reached, speeds,
                         worst, bool(reached[1] >= hi))
