"""Figures of a plant family: V–g / V–f of its open-loop branches, in the family's units.

A family names its speed and time units and nothing about its modes, and an aeroservoelastic
model carries many branches that are not structural (aerodynamic lags, actuators, sensor
filters: real or heavily damped).  :func:`plot_family_vg_vf` draws the oscillatory, lightly
damped branches in the frequency band of the crossings (the ones flutter comes from), each
named by its frequency at the lowest speed, and says how many others it leaves out.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_family_vg_vf", "family_branches", "speed_label", "frequency_axis"]


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


def family_branches(result, *, max_damping: float = 0.5,
                    omega_max: float | None = None) -> np.ndarray:
    """The branches worth drawing: oscillatory, with damping ratio below ``max_damping``
    somewhere in the range and frequency below ``omega_max`` at the lowest speed, one of
    each conjugate pair, and every branch that crosses.

    Parameters
    ----------
    result : FlutterResult
        From :func:`casflutter.aeroelastic.family_flutter`.
    max_damping : float
        Branches whose damping ratio stays above this are left out.
    omega_max : float, optional
        Highest frequency [rad per time unit] of a drawn branch at the lowest speed
        (default: three times the highest frequency a crossing branch reaches, no limit
        without crossings).

    Returns
    -------
    ndarray of int
        Branch indices.
    """
    tr = result.tracking
    lam = tr.eigenvalues
    scale = max(float(np.max(np.abs(lam))), 1.0)
    cross = {int(c.branch) for c in result.crossings}
    if omega_max is None:
        omega_max = (3.0 * max(float(np.max(np.abs(lam[:, b].imag))) for b in cross)
                     if cross else np.inf)
    upper = tr.upper_branches()
    oscillatory = np.max(np.abs(lam.imag), axis=0) > 1e-9 * scale
    light = np.min(tr.damping_ratio, axis=0) < max_damping
    low = np.abs(lam[0].imag) <= omega_max
    keep = {int(b) for b in upper if oscillatory[b] and light[b] and low[b]} | cross
    return np.array(sorted(keep), dtype=int)


def plot_family_vg_vf(result, family, *, branches=None, hz: bool | None = None,
                      max_damping: float = 0.5, omega_max: float | None = None,
                      ax=None) -> Figure:
    """V–g and V–f of a plant family's open-loop branches, with its crossings marked.

    Parameters
    ----------
    result : FlutterResult
        From :func:`casflutter.aeroelastic.family_flutter` on ``family``.
    family : PlantFamily
        For the name and the units of speed and time.
    branches : sequence of int, optional
        Branches to draw (default :func:`family_branches`).
    hz : bool, optional
        See :func:`frequency_axis`.
    max_damping, omega_max : float, optional
        See :func:`family_branches`.
    ax : pair of Axes, optional
        Where to draw (damping, frequency); a new figure otherwise.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tr = result.tracking
    if ax is None:
        fig, (ag, af) = plt.subplots(2, 1, sharex=True, figsize=(8.6, 6.4))
    else:
        ag, af = ax
        fig = ag.figure
    bs = (family_branches(result, max_damping=max_damping, omega_max=omega_max)
          if branches is None else np.asarray(branches, dtype=int))
    fscale, flabel = frequency_axis(family, hz)
    crossing = {c.branch for c in result.crossings}
    su = family.speed_unit
    V, zeta, freq = tr.V, tr.damping_ratio, np.abs(tr.eigenvalues.imag) * fscale
    marker = dict(marker="o", ms=2.5) if V.size <= 80 else {}
    unit = "Hz" if flabel.endswith("[Hz]") else flabel.split("[")[-1].rstrip("]")
    order = sorted(bs, key=lambda b: freq[0, b])
    for b in order:
        lab = f"{freq[0, b]:.3g} {unit}" + (" (crosses)" if b in crossing else "")
        lw = 2.2 if b in crossing else 1.3
        line, = ag.plot(V, zeta[:, b], lw=lw, label=lab, zorder=3, **marker)
        af.plot(V, freq[:, b], color=line.get_color(), lw=lw, zorder=3, **marker)
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
    ag.set_title(title, fontsize="medium")
    ag.axhline(0.0, color="k", lw=0.8)
    if len(bs):
        zs = zeta[:, bs]
        lo, hi = float(np.nanmin(zs)), float(np.nanmax(zs))
        pad = 0.1 * max(hi - lo, 1e-3)
        ag.set_ylim(min(lo, 0.0) - pad, hi + pad)
        top = 1.12 * float(np.nanmax(freq[:, bs]))
        af.set_ylim(0.0, top if top > 0 else 1.0)    # only real poles: a frequency axis still
    ag.set_ylabel("damping ratio ζ = −Re λ / |λ|")
    af.set_ylabel(flabel)
    af.set_xlabel(speed_label(family))
    for a in (ag, af):
        a.grid(True, alpha=0.3)
    others = len(tr.upper_branches()) - len(set(bs) & set(tr.upper_branches()))
    if others:
        ag.plot([], [], " ", label=f"({others} real, well-damped (ζ ≥ {max_damping:g})\n"
                                   "or high-frequency branches not drawn)")
    if ax is None:
        ag.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0, title=f"branch: frequency at {V[0]:g} {su}",
                  title_fontsize="small")
        fig.tight_layout()
    else:
        ag.legend(fontsize="small", loc="best")
    return fig
