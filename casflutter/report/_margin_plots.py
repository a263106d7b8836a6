"""Figures of a controller verified on a plant family (:func:`casflutter.verify.verify_family`):
loop-at-a-time gain and phase margins against the speed at the plant inputs and outputs, with
the thresholds and the absolute and robust flutter speeds marked, and the closed loop's
damping against the speed, and how far the design model's response lies from the plant's
(:func:`casflutter.verify.model_mismatch`).  Names and units are the family's.  Each function
returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from ._labels import frequency_unit

__all__ = ["plot_margins_vs_speed", "plot_closed_loop_damping", "plot_family_verification",
           "plot_model_mismatch"]

#: at most this many least-damped closed-loop eigenvalues are drawn per speed
_N_DAMPING = 12


def _speed_label(result) -> str:
    return f"speed [{result.speed_unit}]"


def _mark_speeds(ax, result, *, label: bool) -> None:
    """The absolute (solid red) and robust (dashed orange) flutter speeds."""
    robust = result.robust_flutter_speed
    if robust is not None:
        text = (f"margins below threshold from the range's start, {robust:.5g} "
                if robust <= result.speed_range[0] else f"robust flutter speed {robust:.5g} ")
        ax.axvline(robust, color="tab:orange", ls="--", lw=1.2,
                   label=text + result.speed_unit if label else None)
    if result.absolute_flutter_speed is not None:
        ax.axvline(result.absolute_flutter_speed, color="tab:red", lw=1.4,
                   label=(f"absolute flutter speed {result.absolute_flutter_speed:.5g} "
                          f"{result.speed_unit}") if label else None)


def _curves(ax, speeds, values, loops, threshold, unit: str, ceiling: float) -> None:
    """One line per loop (infinite margins clipped to the ceiling, as 'no crossover')."""
    for j, name in enumerate(loops):
        y = np.asarray(values[:, j], dtype=float)
        finite = np.isfinite(y)
        if not finite.any() and not np.isinf(y).any():
            continue
        if not finite.any():          # no crossover at any stable speed: no limit here
            ax.plot([], [], lw=1.3, label=f"{name} (no crossover)")
            continue
        ax.plot(speeds, np.where(np.isinf(y), ceiling, y), lw=1.3, marker=".", ms=3,
                label=name)
    ax.axhline(threshold, color="k", ls=":", lw=1.0, label="threshold")
    ax.annotate(f"{threshold:g} {unit}", (1.0, threshold), xycoords=("axes fraction", "data"),
                xytext=(-3, 3), textcoords="offset points", ha="right", va="bottom",
                fontsize="x-small")
    ax.set_ylim(0.0, ceiling)
    ax.grid(True, alpha=0.3)


def plot_margins_vs_speed(result, *, axes=None) -> Figure:
    """Loop-at-a-time gain and phase margins against the speed, plant inputs and outputs.

    Each loop is broken alone while the others stay closed; a margin is drawn only at the
    speeds where the closed loop is stable.  A margin without a crossover (no limit) is drawn
    at the top of its axis.

    Parameters
    ----------
    result : casflutter.verify.FamilyVerification
        From :func:`casflutter.verify.verify_family`.
    axes : 2 × 2 array of Axes, optional
        ``[[input gain, input phase], [output gain, output phase]]``; a new figure
        otherwise.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if axes is None:
        fig, axes = plt.subplots(2, 2, sharex=True, figsize=(11.0, 6.6))
    else:
        fig = axes[0][0].figure
    gm_top = max(3.0 * result.gain_margin_db, 12.0)
    pm_top = 180.0
    for row, table in enumerate((result.inputs, result.outputs)):
        where = "plant inputs" if table.side == "input" else "plant outputs"
        ag, ap = axes[row][0], axes[row][1]
        finite_g = table.gain_db[np.isfinite(table.gain_db)]
        top = max(gm_top, 1.1 * float(finite_g.max())) if finite_g.size and \
            finite_g.max() < 4 * gm_top else gm_top
        _curves(ag, table.speeds, table.gain_db, table.loops, result.gain_margin_db, "dB", top)
        _curves(ap, table.speeds, table.phase_deg, table.loops, result.phase_margin_deg,
                "deg", pm_top)
        ag.set_ylabel(f"gain margin [dB]\n({where})")
        ap.set_ylabel(f"phase margin [deg]\n({where})")
        for ax in (ag, ap):
            _mark_speeds(ax, result, label=(ax is ap))
        ap.legend(fontsize="x-small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0)
    for ax in axes[1]:
        ax.set_xlabel(_speed_label(result))
    fig.suptitle(f"{result.family}: loop-at-a-time margins (each loop broken, the others "
                 "closed; at the top of an axis: no crossover, no limit)", fontsize="medium")
    fig.tight_layout()
    return fig


def plot_closed_loop_damping(result, *, ax=None, n: int = _N_DAMPING) -> Figure:
    """Damping ratio ``ζ = −Re λ/|λ|`` of the closed loop's least-damped eigenvalues against
    the speed, coloured by frequency, with the crossings and the flutter speeds marked.

    Parameters
    ----------
    result : casflutter.verify.FamilyVerification
        From :func:`casflutter.verify.verify_family`.
    ax : Axes, optional
        Where to draw; a new figure otherwise.
    n : int
        Eigenvalues drawn per speed (the least damped, one of each complex pair; real
        eigenvalues, ζ = ±1, are left out: a divergence shows as its crossing's marker).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if ax is None:
        fig, ax = plt.subplots(figsize=(9.0, 4.2))
    else:
        fig = ax.figure
    V, lam = result.branch_speeds, result.branch_eigenvalues
    xs, zs, ws = [], [], []
    for v, row in zip(V, lam):
        row = row[np.isfinite(row)]
        row = row[row.imag > 1e-6 * np.abs(row)]        # one of each complex pair
        zeta = -row.real / np.abs(row)
        keep = np.argsort(zeta)[:n]
        xs.extend([v] * keep.size)
        zs.extend(zeta[keep])
        ws.extend(np.abs(row.imag[keep]))
    sc = ax.scatter(xs, zs, c=ws, s=7, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=f"frequency [rad/{result.time_unit}]")
    ax.axhline(0.0, color="k", lw=0.8)
    _mark_speeds(ax, result, label=True)
    for c in result.crossings:
        ax.plot(c.speed, 0.0, marker="v" if c.direction == "destabilizing" else "^",
                color="tab:red" if c.direction == "destabilizing" else "tab:green", ms=7)
    if zs:
        hi = float(np.quantile(zs, 0.9))
        lo = float(min(zs))
        pad = 0.08 * max(hi - lo, 1e-3)
        ax.set_ylim(min(lo, 0.0) - pad, hi + pad)
    ax.set_xlabel(_speed_label(result))
    ax.set_ylabel("closed-loop damping ratio ζ")
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="x-small", loc="best")
    iv = result.interval
    if iv.lower is None:
        title = f"{result.family}: closed loop, not stable at the range's start"
    else:
        title = (f"{result.family}: closed loop, certified stable on "
                 f"{'[' if iv.stable_at_start else '('}{iv.lower:.5g}, {iv.upper:.5g}"
                 f"{']' if iv.holds_range else ')'} {result.speed_unit}")
    ax.set_title(title, fontsize="medium")
    return fig


def plot_family_verification(result) -> Figure:
    """Margins at the plant inputs and outputs (gain, phase) and the closed-loop damping, in
    one figure (``casflutter verify FAMILY CONTROLLER --figure PATH``).

    Parameters
    ----------
    result : casflutter.verify.FamilyVerification
        From :func:`casflutter.verify.verify_family`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = plt.figure(figsize=(11.5, 10.0))
    grid = fig.add_gridspec(3, 2, height_ratios=(1.0, 1.0, 1.1))
    axes = [[fig.add_subplot(grid[r, c]) for c in range(2)] for r in range(2)]
    for a in axes[0]:
        a.tick_params(labelbottom=False)
    plot_margins_vs_speed(result, axes=axes)
    plot_closed_loop_damping(result, ax=fig.add_subplot(grid[2, :]))
    fig.tight_layout()
    return fig


def plot_model_mismatch(mismatch, *, crossings=(), ax=None) -> Figure:
    """The relative response error of a design model against a reference plant against the
    frequency, one line per speed.

    Parameters
    ----------
    mismatch : casflutter.verify.ModelMismatch
        The comparison.
    crossings : sequence of casflutter.verify.ClosedLoopCrossing, optional
        Where a controller's loop on the reference loses stability
        (:attr:`casflutter.verify.FamilyVerification.crossings`): each destabilising one is
        marked at its frequency (a real eigenvalue at the lowest frequency drawn), so that
        the error there can be read off.
    ax : matplotlib.axes.Axes, optional
        Where to draw (a new figure by default).

    Returns
    -------
    Figure
        ``σmax(G_ref − G) / σmax(G)`` on log axes, the band of the reference's lightly damped
        modes shaded and 10 % dotted.
    """
    if ax is None:
        fig, ax = plt.subplots(figsize=(9.0, 4.2))
    else:
        fig = ax.figure
    m = mismatch
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, len(m.speeds)))
    for k, V in enumerate(m.speeds):
        ax.loglog(m.omega, m.relative_error[k], color=colours[k], lw=1.2,
                  label=f"V = {V:.4g} {m.speed_unit}")
    ax.axvspan(*m.band, color="0.9", zorder=0, label="lightly damped modes")
    ax.axhline(0.1, color="0.3", ls=":", lw=1.0, label="10 %")
    lost = [c for c in crossings if c.direction == "destabilizing"]
    for j, c in enumerate(lost):
        w = max(float(c.omega), float(m.omega[0]))
        ax.axvline(w, color="tab:red", ls="--", lw=1.0,
                   label=f"closed loop on the {m.reference} goes unstable" if j == 0 else None)
        ax.annotate(f"V = {c.speed:.4g}", (w, 0.02), xycoords=("data", "axes fraction"),
                    rotation=90, va="bottom", ha="right", fontsize=7, color="tab:red")
    ax.set_xlabel(f"frequency [{frequency_unit(m.time_unit) or 'rad/s'}]")
    ax.set_ylabel("σmax(G_ref − G) / σmax(G)")
    ax.set_title(f"Response error of the {m.model} against the {m.reference}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig
