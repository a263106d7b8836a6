"""Flutter and LCO figures: V–g / V–f, root locus, LCO history and spectrum (paper Fig. 9),
pole loci open vs closed loop (paper Fig. 10).  Each function returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_vg_vf", "plot_root_locus", "plot_lco", "plot_pole_loci"]


def _tracking(obj):
    """Accept a FlutterResult or an EigenTracking."""
    return (obj.tracking, obj) if hasattr(obj, "tracking") else (obj, None)


def plot_vg_vf(result, *, branches=None, hz: bool = True, ax=None) -> Figure:
    """V–g and V–f plot: damping ratio ``ζ = −Re λ/|λ|`` and frequency of every branch against V.

    Parameters
    ----------
    result : FlutterResult or EigenTracking
        From :func:`casflutter.aeroelastic.find_flutter` / ``track_eigenvalues``.
    branches : sequence of int, optional
        Branches to draw (default: one of each conjugate pair and the real branches).
    hz : bool
        Frequency axis in Hz (else rad/s).
    ax : pair of Axes, optional
        Where to draw (damping, frequency); a new figure otherwise.

    Returns
    -------
    matplotlib.figure.Figure
    """
    tr, res = _tracking(result)
    if ax is None:
        fig, (ag, af) = plt.subplots(2, 1, sharex=True, figsize=(6.5, 6.0))
    else:
        ag, af = ax
        fig = ag.figure
    bs = tr.upper_branches() if branches is None else np.asarray(branches)
    freq = tr.frequency_hz if hz else tr.frequency
    for b in bs:
        lab = f"branch {b}"
        if res is not None:
            lab += f" (mode {res.origin[b] + 1})" if res.origin[b] >= 0 else " (aero)"
        line, = ag.plot(tr.V, tr.damping_ratio[:, b], label=lab)
        af.plot(tr.V, np.abs(freq[:, b]), color=line.get_color())
    ag.axhline(0.0, color="k", lw=0.8)
    if res is not None:
        for c in res.crossings:
            style = "--" if c.kind == "flutter" else ":"
            for a in (ag, af):
                a.axvline(c.V, color="r" if c.direction == "destabilizing" else "g", ls=style, lw=0.8)
        if res.Vf is not None:
            ag.set_title(f"Vf = {res.Vf:.6g}, {res.frequency_hz:.4g} Hz (mode {res.flutter_mode + 1})"
                         if res.flutter_mode is not None and res.flutter_mode >= 0
                         else f"Vf = {res.Vf:.6g}, {res.frequency_hz:.4g} Hz")
        else:
            ag.set_title(res.status.replace("_", " "))
    ag.set_ylabel("damping ratio ζ = −Re λ / |λ|")
    af.set_ylabel("frequency [Hz]" if hz else "frequency [rad/s]")
    af.set_xlabel("speed index V")
    ag.legend(fontsize="small")
    ag.grid(True, alpha=0.3)
    af.grid(True, alpha=0.3)
    return fig


def plot_root_locus(result, *, branches=None, ax=None) -> Figure:
    """Root loci: every tracked branch in the complex plane, coloured by V; crossings marked."""
    tr, res = _tracking(result)
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 5.0))
    fig = ax.figure
    bs = range(tr.n_branches) if branches is None else branches
    sc = None
    for b in bs:
        lam = tr.eigenvalues[:, b]
        ax.plot(lam.real, lam.imag, color="0.7", lw=0.8, zorder=1)
        sc = ax.scatter(lam.real, lam.imag, c=tr.V, s=6, cmap="viridis", zorder=2)
        ax.plot(lam.real[0], lam.imag[0], "kx", ms=5)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="speed index V")
    if res is not None:
        for c in res.crossings:
            ax.plot([0, 0], [c.eigenvalue.imag, -c.eigenvalue.imag], "ro", mfc="none", ms=8)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re λ [1/s]")
    ax.set_ylabel("Im λ [rad/s]")
    ax.set_title("root loci (x: lowest V)")
    ax.grid(True, alpha=0.3)
    return fig


def plot_lco(sim, *, which: str = "sensors", channels=None, fmax_hz: float | None = None,
             truth=None) -> Figure:
    """LCO time history and spectrum (paper Fig. 9).

    Parameters
    ----------
    sim : LoopSimulation
        From :func:`casflutter.aeroelastic.simulate_loop`.
    which : {"sensors", "modes"}
        Plot the sensor outputs zm or the modal displacements u.
    channels : sequence of int, optional
        Channels to draw (default all).
    fmax_hz : float, optional
        Upper limit of the spectrum axis (default 4× the fundamental).
    truth : casflutter.truth.TruthLco, optional
        The truth's own response beside the ROM's (sensor outputs only), from
        :func:`casflutter.truth.truth_lco`; drawn dashed.
    """
    if which not in ("sensors", "modes"):
        raise ValueError(f"which={which!r}; choose 'sensors' or 'modes'")
    X = sim.zm if which == "sensors" else sim.u
    an = sim.sensors if which == "sensors" else sim.modes
    chans = range(X.shape[1]) if channels is None else channels
    name = "zm" if which == "sensors" else "u"
    fig, (at, afr) = plt.subplots(2, 1, figsize=(7.0, 6.0))
    for j in chans:
        at.plot(sim.timepts, X[:, j], lw=0.8, label=f"{name}[{j}]")
    if an is not None and np.isfinite(an.window[0]):
        at.axvspan(an.window[0], an.window[1], color="0.9", zorder=0)
    at.set_xlabel("time [s]")
    at.set_ylabel(which)
    title = f"V = {sim.V:g}: {an.kind}" if an is not None else f"V = {sim.V:g}"
    if an is not None and an.kind == "lco":
        title += f", fundamental {an.frequency_hz:.4g} Hz"
    if truth is not None and which == "sensors":
        ta = truth.analysis
        for j in chans:
            at.plot(truth.timepts, truth.zm[:, j], lw=0.8, ls="--", label=f"truth zm[{j}]")
        title += f"; truth at V = {truth.V:.4g}: {ta.kind}"
        if ta.kind == "lco":
            title += f", {ta.frequency_hz:.4g} Hz"
        if truth.t_start > 0:
            title += f" (its last {truth.timepts[-1]:.3g} s after {truth.t_start:.3g} s)"
        if ta.spectrum.size:
            afr.plot(ta.spectrum_freq_hz, ta.spectrum, lw=0.9, ls="--", label="truth")
    at.set_title(title, fontsize="medium")
    at.legend(fontsize="small", ncol=3)
    if an is not None and an.spectrum.size:
        afr.plot(an.spectrum_freq_hz, an.spectrum, lw=0.9, label="ROM")
        if truth is not None:
            afr.legend(fontsize="small")
        if np.isfinite(an.frequency_hz):
            afr.axvline(an.frequency_hz, color="r", ls="--", lw=0.8)
            afr.set_xlim(0, fmax_hz or 4 * an.frequency_hz)
    afr.set_xlabel("frequency [Hz]")
    afr.set_ylabel(f"|FFT| of {name}[{an.dominant if an is not None else 0}] (window)")
    for a in (at, afr):
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def plot_pole_loci(system, V_grid, controller=None, *, ax=None) -> Figure:
    """Pole loci of ΣAE over V, open loop and (optionally) closed with ``v = K zm`` (Fig. 10).

    Parameters
    ----------
    system : AeroelasticSystem
        Provides ``state_matrix(V)`` and ``closed_loop_state_matrix(V, K)``.
    V_grid : array_like
        Speed indices.
    controller : control.StateSpace, optional
        Continuous controller K (sensors -> flap).
    """
    V_grid = np.asarray(V_grid, dtype=float)
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 5.0))
    fig = ax.figure
    ol = np.array([np.linalg.eigvals(system.state_matrix(V)) for V in V_grid])
    ax.scatter(ol.real.ravel(), ol.imag.ravel(), s=8, marker="x", color="tab:red", label="open loop")
    if controller is not None:
        cl = [np.linalg.eigvals(system.closed_loop_state_matrix(V, controller)) for V in V_grid]
        cl = np.concatenate(cl)
        ax.scatter(cl.real, cl.imag, s=8, marker="o", facecolors="none", edgecolors="tab:blue",
                   label="closed loop")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re λ [1/s]")
    ax.set_ylabel("Im λ [rad/s]")
    ax.set_title(f"pole loci, V in [{V_grid.min():g}, {V_grid.max():g}]")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return fig
