"""Bifurcation diagrams of LCO branches (:mod:`casflutter.lco`): LCO amplitude (and
frequency) against the speed, stable cycles solid, unstable dashed, folds and the Hopf point
marked, the equilibrium drawn along the axis.  Each function returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ._flutter_plots import speed_axes

__all__ = ["plot_bifurcation", "plot_bifurcation_pair", "draw_branch"]


def _runs(stable: np.ndarray):
    """Index ranges ``(i0, i1, stable)`` of equal stability, sharing their end points."""
    out, i0 = [], 0
    for i in range(1, stable.size + 1):
        if i == stable.size or stable[i] != stable[i0]:
            out.append((i0, min(i, stable.size - 1), bool(stable[i0])))
            i0 = i
    return out


def _speed_label(branch) -> str:
    if branch.speed_unit == "m/s":
        return "airspeed U [m/s]"
    return f"speed index ({branch.speed_unit})" if branch.speed_unit else "speed index V"


def _amp_label(branch, name: str) -> str:
    unit = branch.unit_of(name)
    if "[" in name:                       # the name carries its unit already
        return f"LCO amplitude, {name}"
    return f"LCO amplitude, {name}" + (f" [{unit}]" if unit else " [modal units]")


def draw_branch(branch, name: str, ax, *, color=None, label: str | None = None,
                equilibrium: bool = True):
    """Draw one output's amplitude along ``branch`` on ``ax`` (see the module docstring).

    Returns
    -------
    matplotlib.lines.Line2D
        The first line drawn (for legends).
    """
    V = branch.speed(branch.V)
    A = branch.amplitude(name)
    st = branch.stable
    h = branch.hopf
    Vh = float(branch.speed(h.V))
    first = None
    # the branch starts at the Hopf point (amplitude zero)
    V = np.concatenate([[Vh], V])
    A = np.concatenate([[0.0], A])
    st = np.concatenate([[st[0]], st])
    for i0, i1, s in _runs(st):
        line, = ax.plot(V[i0:i1 + 1], A[i0:i1 + 1], ls="-" if s else "--", color=color,
                        lw=1.8 if s else 1.3,
                        label=None if first is not None else label)
        color = line.get_color()
        first = first or line
    if equilibrium:
        lo, hi = (float(v) for v in branch.speed(np.array(branch.vrange)))
        rate = h.crossing_rate
        stable_side = (lo, Vh) if rate > 0 else (Vh, hi)
        unstable_side = (Vh, hi) if rate > 0 else (lo, Vh)
        ax.plot(stable_side, (0, 0), color="0.3", lw=1.8, solid_capstyle="butt")
        ax.plot(unstable_side, (0, 0), color="0.3", lw=1.3, ls="--")
    ax.plot([Vh], [0.0], "o", ms=7, mfc="white", mec=color, mew=1.6, zorder=5)
    for f in branch.folds:
        ax.plot([float(branch.speed(f.V))], [f.amplitude[name]], marker="^", ms=8, color=color,
                ls="none", zorder=5)
    settled = getattr(branch, "settled", None)
    if settled is not None and settled.points:
        Vs = branch.speed(np.array([p.V for p in settled.points]))
        As = np.array([p.amplitude[name] for p in settled.points])
        for k, (i0, i1, s) in enumerate(_runs(np.array([p.stable for p in settled.points]))):
            ax.plot(Vs[i0:i1 + 1], As[i0:i1 + 1], ls="-" if s else "--", color="C3",
                    lw=1.8 if s else 1.3,
                    label="cycle a simulation settles on" if k == 0 else None)
        for f in settled.folds:
            ax.plot([float(branch.speed(f.V))], [f.amplitude[name]], marker="^", ms=8,
                    color="C3", ls="none", zorder=5)
    return first


def plot_bifurcation(branch, outputs=None, *, frequency: bool = True, hb_points=None,
                     title: str | None = None, ax=None) -> Figure:
    """Bifurcation diagram of an LCO branch: amplitude of each output against the speed.

    Stable cycles are solid, unstable dashed; the Hopf point is an open circle on the
    speed axis (the equilibrium: solid where stable, dashed where unstable), folds of cycles
    are triangles.  Speeds in the problem's unit; amplitudes in the outputs' units.

    Parameters
    ----------
    branch : LCOBranch
    outputs : sequence of str, optional
        Outputs to draw, one panel each (default: the sensors, or the two largest outputs).
    frequency : bool
        Add a panel with the LCO frequency.
    hb_points : dict, optional
        ``{output name: (speeds, amplitudes)}`` drawn as crosses (e.g. harmonic balance).
    title : str, optional
    ax : sequence of Axes, optional
        Where to draw (one per panel); a new figure otherwise.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if outputs is None:
        outputs = _default_outputs(branch)
    outputs = list(outputs)
    n = len(outputs) + (1 if frequency else 0)
    if ax is None:
        fig, axes = plt.subplots(n, 1, sharex=True, figsize=(6.4, 2.6 * n + 0.6), squeeze=False)
        axes = list(axes[:, 0])
    else:
        axes = list(np.atleast_1d(ax))
        fig = axes[0].figure
    for a, name in zip(axes, outputs):
        draw_branch(branch, name, a)
        if hb_points and name in hb_points:
            Vs, As = hb_points[name]
            a.plot(Vs, As, "x", color="k", ms=6, label="harmonic balance")
            a.legend(loc="best", fontsize="small")
        a.set_ylabel(_amp_label(branch, name), fontsize="small")
        a.grid(alpha=0.3)
        a.set_ylim(bottom=0.0)
    if frequency:
        a = axes[len(outputs)]
        V = branch.speed(branch.V)
        f = branch.freq_hz
        for i0, i1, s in _runs(branch.stable):
            a.plot(V[i0:i1 + 1], f[i0:i1 + 1], ls="-" if s else "--", color="C0")
        settled = getattr(branch, "settled", None)
        if settled is not None and settled.points:
            Vs = branch.speed(np.array([p.V for p in settled.points]))
            fs = np.array([p.freq_hz for p in settled.points])
            for i0, i1, s in _runs(np.array([p.stable for p in settled.points])):
                a.plot(Vs[i0:i1 + 1], fs[i0:i1 + 1], ls="-" if s else "--", color="C3")
        a.plot([float(branch.speed(branch.hopf.V))], [branch.hopf.freq_hz], "o", mfc="white",
               mec="C0")
        unit = "Hz" if branch.time_unit == "s" else f"cycles per {branch.time_unit}"
        a.set_ylabel(f"LCO frequency [{unit}]", fontsize="small")
        a.grid(alpha=0.3)
    axes[n - 1].set_xlabel(_speed_label(branch))
    h = branch.hopf
    kind = f"{h.kind} {_point_name(branch)} at " \
           f"{float(branch.speed(h.V)):.4g} {branch.speed_unit if branch.speed_unit == 'm/s' else ''}"
    axes[0].set_title(title or f"{branch.problem}: {kind.strip()}", fontsize="medium")
    if branch.speed_unit == "m/s":
        speed_axes(axes[0], branch.speed_scale, "speed index V")
    _legend_proxies(axes[0], _point_name(branch))
    if ax is None:
        fig.tight_layout()
    return fig


def _default_outputs(branch):
    units = dict(zip(branch.outputs, branch.output_units))
    with_units = [n for n in branch.outputs if units[n]]
    if with_units:
        return with_units
    last = branch.points[-1].amplitude
    return sorted(branch.outputs, key=lambda n: -last[n])[:2]


def _point_name(branch) -> str:
    """The flutter point of a continuous system is a Hopf point; that of a sampled-data
    loop (a map) a Neimark–Sacker point."""
    return "Neimark–Sacker point" if branch.hopf.discrete else "Hopf point"


def _legend_proxies(ax, point: str = "Hopf point") -> None:
    handles = [Line2D([], [], color="0.2", lw=1.8, label="stable"),
               Line2D([], [], color="0.2", lw=1.3, ls="--", label="unstable"),
               Line2D([], [], color="0.2", marker="o", mfc="white", ls="none", label=point),
               Line2D([], [], color="0.2", marker="^", ls="none", label="fold")]
    old = ax.get_legend()
    extra = [h for h in (old.legend_handles if old is not None else [])]
    labels = {h.get_label() for h in extra}
    extra += [h for h in ax.get_lines()        # labelled lines not in a legend yet
              if not h.get_label().startswith("_") and h.get_label() not in labels]
    ax.legend(handles=handles + extra, loc="upper left", fontsize="x-small", ncol=2)


def plot_bifurcation_pair(truth_branch, rom_branch, outputs=None, *,
                          frequency: bool = True, speed_range=None) -> Figure:
    """The truth's and the ROM's bifurcation diagrams side by side (same outputs, same axes
    ranges), e.g. for the seed wing's report.

    Parameters
    ----------
    truth_branch, rom_branch : LCOBranch
        Their outputs must share the names in ``outputs``.
    outputs : sequence of str, optional
        Default: the outputs both branches have, sensors first.
    frequency : bool
        Add the frequency row.
    speed_range : (float, float), optional
        Speed axis limits in the problem's unit (default: both branches with a margin on
        each side).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if outputs is None:
        common = [n for n in _default_outputs(truth_branch) if n in rom_branch.outputs]
        outputs = common or [n for n in truth_branch.outputs if n in rom_branch.outputs][:2]
    outputs = list(outputs)
    n = len(outputs) + (1 if frequency else 0)
    fig, axes = plt.subplots(n, 2, sharex=False, sharey="row", figsize=(11.0, 2.6 * n + 0.8),
                             squeeze=False)
    for col, (br, label) in enumerate(((truth_branch, "truth"), (rom_branch, "ROM loop"))):
        unit = f" {br.speed_unit}" if br.speed_unit == "m/s" else ""
        plot_bifurcation(br, outputs, frequency=frequency, ax=axes[:, col],
                         title=f"{label}: {br.hopf.kind} {_point_name(br)} at "
                               f"{float(br.speed(br.hopf.V)):.4g}{unit}")
    if speed_range is None:
        speeds = [float(br.speed(v)) for br in (truth_branch, rom_branch)
                  for v in [br.hopf.V, *(p.V for p in br.points)]]
        span = max(speeds) - min(speeds)
        lo, hi = min(speeds) - 0.15 * span, max(speeds) + 0.1 * span
    else:
        lo, hi = (float(v) for v in speed_range)
    for a in axes.ravel():
        a.set_xlim(lo, hi)
    fig.tight_layout()
    return fig
