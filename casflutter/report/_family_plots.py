"""Figures of a plant family: V–g / V–f of its open-loop branches, in the family's units.

A family names its speed and time units and nothing about its modes, and an aeroservoelastic
model carries many branches that are not structural (aerodynamic lags, actuators, sensor
filters: real or heavily damped).  :func:`plot_family_vg_vf` draws the oscillatory, lightly
damped branches up to a decade above the crossings' frequencies (the ones flutter comes from
and their neighbours), each named by its frequency at the lowest speed, every branch that is
unstable somewhere in the range (a real one by its decay rate ``−Re λ`` on an axis of its
own), and says how many others it leaves out and why.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_family_vg_vf", "family_branches", "speed_label", "frequency_axis"]

#: Default frequency cut: this many times the highest frequency a crossing branch reaches.
_DECADES_ABOVE = 10.0
#: Default most lightly damped, stable oscillatory branches drawn (the lowest in frequency).
_MAX_BRANCHES = 16


def speed_label(family) -> str:
    """The speed axis label of a family (``"airspeed [m/s]"``, ``"speed index V"``).

    Parameters
    ----------
    family : PlantFamily
        Any family (its ``speed_unit``).

    Returns
    -------
    str
    """
    unit = str(family.speed_unit)
    return "speed index V" if unit.startswith("speed index") else f"speed [{unit}]"


def frequency_axis(family, hz: bool | None = None) -> tuple[float, str]:
    """Scale from rad per time unit to the plotted frequency, and its label.

    Parameters
    ----------
    family : PlantFamily
        Any family (its ``time_unit``).
    hz : bool, optional
        Cycles per time unit (Hz when time is in seconds) instead of radians; default: Hz
        when the time unit is ``"s"``.

    Returns
    -------
    (float, str)
    """
    tu = str(family.time_unit)
    hz = (tu == "s") if hz is None else bool(hz)
    if hz:
        return 1.0 / (2.0 * np.pi), "frequency [Hz]" if tu == "s" else f"frequency [1/{tu}]"
    return 1.0, f"frequency [rad/{tu}]"


@dataclass(frozen=True)
class _Selection:
    """Which branches a V–g figure draws, and how many it leaves out for which reason."""

    oscillatory: np.ndarray      # drawn as damping ratio and frequency
    real: np.ndarray             # drawn as decay rate −Re λ (frequency 0)
    unstable: np.ndarray         # bool per branch: Re λ > 0 somewhere in the range
    crossing: frozenset
    omega_max: float             # the frequency cut applied [rad per time unit]
    omega_rule: str              # "" (none), "given", or how the default was made
    real_stable: int             # left out: real, stable throughout
    well_damped: int             # left out: ζ ≥ max_damping throughout
    above: int                   # left out: lightly damped, above omega_max
    capped: int                  # left out: lightly damped, beyond max_branches
    cap_omega: float             # lowest frequency of a capped branch (nan without)


def _real_branches(lam: np.ndarray, scale: float) -> np.ndarray:
    """Branches real at every speed (up to rounding: a repeated real pole splits into a
    pair whose imaginary parts are rounding errors)."""
    return np.all(np.abs(lam.imag) <= 1e-3 * np.abs(lam) + 1e-9 * scale, axis=0)


def _select(result, max_damping: float, omega_max: float | None,
            max_branches: int) -> _Selection:
    tr = result.tracking
    lam = tr.eigenvalues
    scale = max(float(np.max(np.abs(lam))), 1.0)
    real = _real_branches(lam, scale)
    # the same threshold as family_flutter's "unstable already at the low end"
    unstable = np.max(lam.real, axis=0) > 1e-12 * scale
    cross = frozenset(int(c.branch) for c in result.crossings)
    candidates = sorted(set(int(b) for b in tr.upper_branches())
                        | set(int(b) for b in np.flatnonzero(real)))
    peak = np.max(np.abs(lam.imag), axis=0)
    rule = "given"
    if omega_max is None:
        osc_cross = [b for b in cross if not real[b]]
        if osc_cross:
            omega_max = _DECADES_ABOVE * max(float(peak[b]) for b in osc_cross)
            rule = f"{_DECADES_ABOVE:g} × the highest crossing frequency"
        else:
            omega_max, rule = np.inf, ""
    omega_max = float(omega_max)
    always = [b for b in candidates if unstable[b] or b in cross]
    light = np.min(tr.damping_ratio, axis=0) < max_damping
    f0 = np.abs(lam[0].imag)
    pool = [b for b in candidates if not real[b] and b not in always and light[b]]
    in_band = sorted((b for b in pool if f0[b] <= omega_max), key=lambda b: f0[b])
    room = max(int(max_branches) - sum(1 for b in always if not real[b]), 0)
    kept, capped = in_band[:room], in_band[room:]
    return _Selection(
        oscillatory=np.array(sorted([b for b in always if not real[b]] + kept), dtype=int),
        real=np.array([b for b in always if real[b]], dtype=int),
        unstable=unstable, crossing=cross, omega_max=omega_max, omega_rule=rule,
        real_stable=sum(1 for b in candidates if real[b] and b not in always),
        well_damped=sum(1 for b in candidates
                        if not real[b] and b not in always and not light[b]),
        above=sum(1 for b in pool if f0[b] > omega_max), capped=len(capped),
        cap_omega=float(f0[capped[0]]) if capped else float("nan"))


def family_branches(result, *, max_damping: float = 0.5, omega_max: float | None = None,
                    max_branches: int = _MAX_BRANCHES) -> np.ndarray:
    """The branches worth drawing: every branch that is unstable somewhere in the range or
    crosses (real ones included), and the oscillatory ones with damping ratio below
    ``max_damping`` somewhere in the range and frequency at most ``omega_max`` at the lowest
    speed (one of each conjugate pair, at most ``max_branches`` of them counting the
    unstable oscillatory ones, the lowest in frequency first).

    Parameters
    ----------
    result : FlutterResult
        From :func:`casflutter.aeroelastic.family_flutter`.
    max_damping : float
        Stable branches whose damping ratio stays at or above this are left out.
    omega_max : float, optional
        Highest frequency [rad per time unit] of a drawn stable branch at the lowest speed
        (default: ten times the highest frequency an oscillatory crossing branch reaches, a
        decade above the modes flutter comes from; no limit without such crossings).
    max_branches : int
        Most oscillatory branches drawn; unstable and crossing ones are drawn even beyond it.

    Returns
    -------
    ndarray of int
        Branch indices, sorted.
    """
    sel = _select(result, max_damping, omega_max, max_branches)
    return np.array(sorted(set(sel.oscillatory) | set(sel.real)), dtype=int)


def _rule_note(sel: _Selection, max_damping: float, fscale: float, unit: str) -> str:
    """The legend's account of the rule: what is drawn, what is left out and why."""
    band = (f" below {sel.omega_max * fscale:.3g} {unit}\n   ({sel.omega_rule})"
            if np.isfinite(sel.omega_max) else "")
    lines = ["drawn: every unstable or crossing branch,",
             f"   stable ones with ζ < {max_damping:g} somewhere{band}"]
    parts = []
    if sel.real_stable:
        parts.append(f"{sel.real_stable} real, stable")
    if sel.well_damped:
        parts.append(f"{sel.well_damped} well damped (ζ ≥ {max_damping:g} throughout)")
    if sel.above:
        parts.append(f"{sel.above} lightly damped above {sel.omega_max * fscale:.3g} {unit}")
    if sel.capped:
        parts.append(f"{sel.capped} lightly damped from {sel.cap_omega * fscale:.3g} {unit} "
                     f"up\n   (only the {len(sel.oscillatory)} lowest drawn)")
    lines.append("not drawn:" + ("" if parts else " none"))
    lines += [f" · {p}" for p in parts]
    return "\n".join(lines)


def _start_note(result, family, sel: _Selection, fscale: float, unit: str) -> str:
    """What is unstable at the lowest speed, in a few words (empty when nothing is)."""
    if not result.unstable_at_start:
        return ""
    tr = result.tracking
    lam0 = tr.eigenvalues[0]
    scale = max(float(np.max(np.abs(tr.eigenvalues))), 1.0)
    real = set(int(b) for b in sel.real)
    grow = [int(b) for b in np.argsort(-lam0.real)        # one of each pair
            if lam0[b].real > 1e-12 * scale and (int(b) in real or lam0[b].imag >= 0)]
    words = [f"real mode, Re λ = {lam0[b].real:+.3g} /{family.time_unit}" if b in real
             else f"{abs(lam0[b].imag) * fscale:.3g} {unit} mode, ζ = {tr.damping_ratio[0, b]:.3g}"
             for b in grow[:2]]
    more = f" and {len(grow) - 2} more" if len(grow) > 2 else ""
    return (f"unstable already at {tr.V[0]:.5g} {family.speed_unit}: " + "; ".join(words)
            + more)


def plot_family_vg_vf(result, family, *, branches=None, hz: bool | None = None,
                      max_damping: float = 0.5, omega_max: float | None = None,
                      max_branches: int = _MAX_BRANCHES, ax=None) -> Figure:
    """V–g and V–f of a plant family's open-loop branches, with its crossings marked.

    Oscillatory branches are drawn as damping ratio ``ζ = −Re λ / |λ|`` and frequency; real
    branches that are unstable somewhere in the range (or cross) as their decay rate
    ``−Re λ`` on a second axis on the right of the damping panel, its zero level with
    ``ζ = 0`` (below it they grow, as a branch with ``ζ < 0``), dash-dotted, and at
    frequency 0.  The title says when the family is unstable already at the lowest speed,
    and the legend how many branches are left out and by which rule.

    Parameters
    ----------
    result : FlutterResult
        From :func:`casflutter.aeroelastic.family_flutter` on ``family``.
    family : PlantFamily
        For the name and the units of speed and time.
    branches : sequence of int, optional
        Branches to draw (default :func:`family_branches`); the real ones among them are
        drawn by their decay rate.
    hz : bool, optional
        See :func:`frequency_axis`.
    max_damping, omega_max, max_branches : optional
        See :func:`family_branches`.
    ax : pair of Axes, optional
        Where to draw (damping, frequency); a new figure otherwise.

    Returns
    -------
    matplotlib.figure.Figure
        The real branches' decay rates are on the damping axes' twin (``ax[0]``'s
        ``twinx``), labelled ``"real mode, unstable ..."``.
    """
    tr = result.tracking
    sel = _select(result, max_damping, omega_max, max_branches)
    if branches is not None:
        bs = np.asarray(branches, dtype=int)
        lam = tr.eigenvalues
        real = _real_branches(lam, max(float(np.max(np.abs(lam))), 1.0))
        sel = _Selection(bs[~real[bs]], bs[real[bs]], sel.unstable, sel.crossing,
                         np.inf, "", 0, 0, 0, 0, float("nan"))
    if ax is None:
        fig, (ag, af) = plt.subplots(2, 1, sharex=True, layout="constrained",
                                     figsize=(10.0 if len(sel.real) else 9.0, 6.6))
    else:
        ag, af = ax
        fig = ag.figure
    fscale, flabel = frequency_axis(family, hz)
    su, tu = family.speed_unit, family.time_unit
    V, zeta, freq = tr.V, tr.damping_ratio, np.abs(tr.eigenvalues.imag) * fscale
    marker = dict(marker="o", ms=2.5) if V.size <= 80 else {}
    unit = "Hz" if flabel.endswith("[Hz]") else flabel.split("[")[-1].rstrip("]")
    order = sorted(sel.oscillatory, key=lambda b: freq[0, b])
    colors = plt.get_cmap("tab10").colors
    for i, b in enumerate(order):
        tag = (" (crosses)" if b in sel.crossing
               else " (unstable)" if sel.unstable[b] else "")
        lw = 2.2 if tag else 1.3
        # past ten branches the colours come round again, dashed with square markers
        style = dict(color=colors[i % 10], lw=lw, zorder=3, **marker)
        if i >= 10:
            style.update(ls=(0, (4, 1.5)), marker="s" if marker else None)
        ag.plot(V, zeta[:, b], label=f"{freq[0, b]:.3g} {unit}{tag}", **style)
        af.plot(V, freq[:, b], **style)
    agr = None
    if len(sel.real):
        agr = ag.twinx()
        greys = ["k", "0.45", "saddlebrown", "darkmagenta"]
        for i, b in enumerate(sel.real):
            re = tr.eigenvalues[:, b].real
            state = "unstable" if sel.unstable[b] else "stable"
            lab = (f"real mode, {state} (right axis):\n   Re λ = {re.min():+.2g} … "
                   f"{re.max():+.2g} /{tu}" if i < 6 else None)
            style = dict(color=greys[i % len(greys)], ls="-.", lw=2.0, marker="^", ms=3,
                         zorder=4)
            agr.plot(V, -re, label=lab, **style)
            af.plot(V, np.zeros_like(V), clip_on=False, **style)
        if len(sel.real) > 6:
            agr.plot([], [], " ", label=f"(and {len(sel.real) - 6} more real modes)")
        agr.set_ylabel(f"real modes: −Re λ [1/{tu}]")
    for c in result.crossings:
        style = "--" if c.kind == "flutter" else ":"
        for a in (ag, af):
            a.axvline(c.V, color="r" if c.direction == "destabilizing" else "g", ls=style,
                      lw=0.9)
        if c.kind == "flutter":
            af.plot(c.V, c.omega * fscale, "r*", ms=10, zorder=4)
    if result.Vf is not None:
        title = (f"{family.name}: flutter at {result.Vf:.5g} {su}, "
                 f"{result.omega_f * fscale:.4g} {unit}")
    else:
        title = f"{family.name}: {result.status.replace('_', ' ')} in the range"
    start = _start_note(result, family, sel, fscale, unit)
    if start:
        title += "\n" + start + ("\n(the crossings are not the onset of instability)"
                                 if result.crossings else "")
    ag.set_title(title, fontsize="medium", color="darkred" if start else "k")
    ag.axhline(0.0, color="k", lw=0.8)
    _limits(ag, af, agr, sel, zeta, freq, tr)
    ag.set_ylabel("damping ratio ζ = −Re λ / |λ|")
    af.set_ylabel(flabel)
    af.set_xlabel(speed_label(family))
    for a in (ag, af):
        a.grid(True, alpha=0.3)
    note = "" if branches is not None else _rule_note(sel, max_damping, fscale, unit)
    handles, labels = ag.get_legend_handles_labels()
    if agr is not None:
        h2, l2 = agr.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    if note:
        handles.append(plt.Line2D([], [], ls=" "))
        labels.append(note)
    if ax is None:                      # beside the panels, clear of the right-hand axis
        fig.legend(handles, labels, fontsize="small", loc="outside right upper",
                   title=f"branch: frequency at {V[0]:g} {su}", title_fontsize="small")
    else:
        ag.legend(handles, labels, fontsize="small", loc="best")
    return fig


def _limits(ag, af, agr, sel: _Selection, zeta, freq, tr) -> None:
    """Axis limits: every drawn branch in view, the decay-rate axis' zero level with ζ = 0."""
    osc = sel.oscillatory
    lo, hi = ((float(np.nanmin(zeta[:, osc])), float(np.nanmax(zeta[:, osc])))
              if len(osc) else (0.0, 0.1))
    if agr is not None:
        lo = min(lo, -0.3 * max(hi, 0.1))    # room below ζ = 0 for the growing real modes
    pad = 0.1 * max(hi - lo, 1e-3)
    a, b = min(lo, 0.0) - pad, max(hi, 0.0) + pad
    ag.set_ylim(a, b)
    top = 1.12 * float(np.nanmax(freq[:, osc])) if len(osc) else 0.0
    top = top if top > 0 else 1.0            # only real poles: a frequency axis still
    af.set_ylim(-0.02 * top if agr is not None else 0.0, top)
    if agr is not None:
        d = -tr.eigenvalues[:, sel.real].real
        s = max(float(np.min(d)) / a, float(np.max(d)) / b, 1e-300)
        agr.set_ylim(1.05 * s * a, 1.05 * s * b)
