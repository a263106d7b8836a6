"""Flutter and LCO figures: V–g / V–f, root locus, LCO history and spectrum (paper Fig. 9),
pole loci open vs closed loop (paper Fig. 10).  Each function returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from ._labels import label_unit

__all__ = ["plot_vg_vf", "plot_root_locus", "plot_lco", "plot_pole_loci", "speed_axes"]


def _tracking(obj):
    """Accept a FlutterResult or an EigenTracking."""
    return (obj.tracking, obj) if hasattr(obj, "tracking") else (obj, None)


def speed_axes(ax, scale: float, index_label: str | None) -> None:
    """A secondary speed-index axis on top of ``ax``, whose x axis is ``scale`` times the
    speed index (the airspeed in m/s); nothing when ``scale`` is 1 or no label is given.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The top panel of a figure drawn against the problem's speed.
    scale : float
        Problem speed per speed index (``airspeed(1.0)``).
    index_label : str or None
        Label of the secondary axis, e.g. ``"speed index V = U / U_ref"``.
    """
    if index_label is None or scale == 1.0:
        return
    sec = ax.secondary_xaxis("top", functions=(lambda x: x / scale, lambda v: v * scale))
    sec.set_xlabel(index_label, fontsize="small")
    sec.tick_params(labelsize="small")


def _mode_label(mode: int | None, mode_names) -> str:
    """``"mode 2 (torsion 1)"`` for the 0-based ``mode`` (numbered from 1 for a reader)."""
    if mode is None or mode < 0:
        return ""
    label = f"mode {mode + 1}"
    if mode_names is None or mode >= len(mode_names):
        return label
    name = str(mode_names[mode])
    # a name that already numbers the mode ("mode 1 (pitch)", a rig's) is taken as it is
    return name if name == label or name.startswith(label + " ") else f"{label} ({name})"


def plot_vg_vf(result, *, branches=None, hz: bool = True, ax=None, mode_names=None,
               speed_label: str = "speed index V", speed_scale: float = 1.0,
               speed_unit: str = "", index_label: str | None = None,
               frequency_unit: str | None = None) -> Figure:
    """V–g and V–f plot: damping ratio ``ζ = −Re λ/|λ|`` and frequency of every branch against
    the speed.

    With a :class:`~casflutter.aeroelastic.FlutterResult` the branches that grow out of a
    structural mode are drawn in that mode's colour (the same in every panel of a figure)
    and named once by their mode (numbered from 1); the branches of the aerodynamic lag
    states are drawn faint and grey, with one legend entry, and the axes are scaled to the
    structural branches (every mode's frequency in view).  The title names the flutter speed
    and frequency in the axes' units and the mode whose curve crosses zero.

    Parameters
    ----------
    result : FlutterResult or EigenTracking
        From :func:`casflutter.aeroelastic.find_flutter` / ``track_eigenvalues``.
    branches : sequence of int, optional
        Branches to draw (default: one of each conjugate pair and the real branches).
    hz : bool
        Frequency axis in Hz (else in rad per the problem's time unit).
    ax : pair of Axes, optional
        Where to draw (damping, frequency); a new figure otherwise.
    mode_names : sequence of str, optional
        Names of the structural modes, added to their legend entries.
    speed_label : str
        Label of the speed axis.
    speed_scale : float
        Speed on the axis per speed index of ``result`` (``airspeed(1.0)`` to draw against
        the airspeed in m/s; 1: the speed index itself).
    speed_unit : str
        Unit of the axis speed in the title (``"m/s"``; empty for the speed index).
    index_label : str, optional
        With ``speed_scale != 1``: label of a secondary axis on top with the speed index.
    frequency_unit : str, optional
        Unit of the frequency axis (default ``"Hz"``, or ``"rad/s"`` with ``hz=False``); a
        problem in nondimensional time gives its own (``"Ω/ω_θ"``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    tr, res = _tracking(result)
    if ax is None:
        fig, (ag, af) = plt.subplots(2, 1, sharex=True, figsize=(8.6, 6.4))
    else:
        ag, af = ax
        fig = ag.figure
    funit = frequency_unit or ("Hz" if hz else "rad/s")
    bs = tr.upper_branches() if branches is None else np.asarray(branches)
    freq = np.abs(tr.frequency_hz if hz else tr.frequency)
    zeta = tr.damping_ratio
    speed = tr.V * speed_scale
    structural, aero_drawn, named = [], False, set()
    for b in sorted(bs, key=lambda b: (res.origin[b] if res is not None and res.origin[b] >= 0
                                       else 10 ** 6, b)):
        origin = int(res.origin[b]) if res is not None else -2
        if origin == -1:            # an aerodynamic lag state: faint, one legend entry
            kw = dict(color="0.6", lw=0.7, alpha=0.5, zorder=1,
                      label=None if aero_drawn else "aerodynamic lag states")
            aero_drawn = True
            ag.plot(speed, zeta[:, b], **kw)
            af.plot(speed, freq[:, b], color="0.6", lw=0.7, alpha=0.5, zorder=1)
            continue
        structural.append(b)
        if origin >= 0:             # one colour and one legend entry per mode
            kw = dict(color=f"C{origin % 10}", lw=1.5 if origin not in named else 1.0,
                      label=None if origin in named else _mode_label(origin, mode_names))
            named.add(origin)
        else:
            kw = dict(lw=1.5, label=f"branch {b + 1}")
        line, = ag.plot(speed, zeta[:, b], zorder=3, **kw)
        af.plot(speed, freq[:, b], color=line.get_color(), lw=kw["lw"], zorder=3)
    ag.axhline(0.0, color="k", lw=0.8)
    if res is not None:
        for c in res.crossings:
            style = "--" if c.kind == "flutter" else ":"
            for a in (ag, af):
                a.axvline(c.V * speed_scale, color="r" if c.direction == "destabilizing"
                          else "g", ls=style, lw=0.8)
        if res.Vf is not None:
            mode = _mode_label(res.flutter_mode, mode_names)
            f = res.frequency_hz if funit == "Hz" else res.omega_f
            symbol = "U" if speed_unit == "m/s" else "V"
            ag.set_title(f"flutter: {symbol}f = {res.Vf * speed_scale:.4g}"
                         f"{' ' + speed_unit if speed_unit else ''}, {f:.4g} {funit}"
                         + (f", {mode}" if mode else ""), fontsize="medium")
        else:
            ag.set_title(res.status.replace("_", " "), fontsize="medium")
        if structural and aero_drawn:
            # the structural branches set the scales; the lag states may run far off
            fs, zs = freq[:, structural], zeta[:, structural]
            af.set_ylim(0.0, 1.12 * float(np.nanmax(fs)))
            lo, hi = float(np.nanmin(zs)), float(np.nanmax(zs))
            pad = 0.1 * max(hi - lo, 1e-3)
            ag.set_ylim(min(lo, 0.0) - pad, hi + pad)
    ag.set_ylabel("damping ratio ζ = −Re λ / |λ|")
    af.set_ylabel(f"frequency [{funit}]")
    af.set_xlabel(speed_label)
    speed_axes(ag, speed_scale, index_label)
    ag.grid(True, alpha=0.3)
    af.grid(True, alpha=0.3)
    if ax is None:     # the legend beside the plots, clear of the branches
        ag.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0)
        fig.tight_layout()
    else:
        ag.legend(fontsize="small", loc="best")
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


def _last_cycles(t, X, freq_hz: float, cycles: int):
    """The samples of the last ``cycles`` periods (all when the frequency is unknown)."""
    if not np.isfinite(freq_hz) or freq_hz <= 0:
        return t, X
    keep = t >= t[-1] - cycles / freq_hz
    return t[keep], X[keep]


def plot_lco(sim, *, which: str = "sensors", channels=None, fmax_hz: float | None = None,
             truth=None, labels=None, cycles: int = 6, title: str | None = None,
             speed_scale: float = 1.0, speed_unit: str = "", time_unit: str = "s") -> Figure:
    """LCO time history and spectrum (paper Fig. 9).

    One row per channel and a spectrum row.  With the truth's response the ROM's is drawn
    in the left column and the truth's in the right one, each over its own last ``cycles``
    periods (the whole record when it holds fewer, or the response is no cycle).  Where
    both are bounded the columns share the vertical scale per row, so that both wave forms
    and amplitudes can be read and compared; where one diverges, each column is scaled to
    its own signal (a shared scale would flatten the bounded one).  The spectrum axis runs
    to 4x the largest LCO frequency of the columns (each column's own where neither is an
    LCO).

    Parameters
    ----------
    sim : LoopSimulation
        From :func:`casflutter.aeroelastic.simulate_loop`.
    which : {"sensors", "modes"}
        Plot the sensor outputs zm or the modal displacements u.
    channels : sequence of int, optional
        0-based channels to draw (default all).
    fmax_hz : float, optional
        Upper limit of the spectrum axis (default 4× the largest LCO frequency drawn, else
        4× each column's own frequency).
    truth : casflutter.truth.TruthLco, optional
        The truth's own response beside the ROM's (sensor outputs only), from
        :func:`casflutter.truth.truth_lco`.
    labels : sequence of str, optional
        Axis label per channel with its unit (``"name [unit]"``; the unit also follows each
        amplitude); default ``sensor 1``, ``mode 1``, ...
    cycles : int
        Periods shown of each time history (the whole record when it has no frequency).
    title : str, optional
        Figure title.
    speed_scale : float
        Problem speed per speed index: with ``speed_unit`` the panels name the speed in
        that unit beside the speed index (``V = 1.248 (36.07 m/s)``).
    speed_unit : str
        Unit of ``speed_scale`` (``"m/s"``; empty: the speed index alone).
    time_unit : str
        The problem's time unit: time in it, frequencies in cycles per it (Hz for seconds).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if which not in ("sensors", "modes"):
        raise ValueError(f"which={which!r}; choose 'sensors' or 'modes'")
    X = sim.zm if which == "sensors" else sim.u
    an = sim.sensors if which == "sensors" else sim.modes
    chans = list(range(X.shape[1]) if channels is None else channels)
    word = "sensor" if which == "sensors" else "mode"
    labels = list(labels) if labels is not None else []
    names = [labels[j] if j < len(labels) else f"{word} {j + 1}" for j in chans]
    pairs = [("ROM loop", sim.timepts, X, an, sim.V)]
    if truth is not None and which == "sensors":
        pairs.append(("truth", truth.timepts, truth.zm, truth.analysis, truth.V))
    ncol = len(pairs)
    hz = "Hz" if time_unit == "s" else f"cycles per {time_unit}"
    fig, axes = plt.subplots(len(chans) + 1, ncol, figsize=(5.2 * ncol + 1.2, 2.1 * len(chans) + 2.6),
                             squeeze=False)
    kinds = [a.kind if a is not None else None for *_, a, _ in pairs]
    if ncol > 1 and "divergence" not in kinds:       # comparable: one vertical scale per row
        for row in range(len(chans) + 1):
            for col in range(1, ncol):
                axes[row, col].sharey(axes[row, 0])
    # the spectrum axis: up to 4x the largest LCO frequency drawn (the truth's and the ROM's
    # cycles both on it), else each column's own frequency
    lco_f = [a.frequency_hz for *_, a, _ in pairs
             if a is not None and a.kind == "lco" and np.isfinite(a.frequency_hz)
             and a.frequency_hz > 0]
    for col, (label, t, Z, a, V) in enumerate(pairs):
        f = a.frequency_hz if a is not None else float("nan")
        # the last periods of a cycle; the whole record of a divergence (its "frequency" is
        # no period) or of a record shorter than those periods
        tt, ZZ = _last_cycles(t, Z, f if a is not None and a.kind != "divergence"
                              else float("nan"), cycles)
        cut = tt.size < t.size
        air = f" ({V * speed_scale:.4g} {speed_unit})" if speed_unit else ""
        head = f"{label} at V = {V:.4g}{air}: {a.kind if a is not None else ''}"
        if a is not None and a.kind == "lco":
            head += f", {f:.3g} {hz}"
        axes[0, col].set_title(head, fontsize="medium")
        for row, j in enumerate(chans):
            ax = axes[row, col]
            ax.plot(tt, ZZ[:, j], color="C0" if col == 0 else "k", lw=1.0)
            if a is not None and j < len(a.amplitude) and a.kind == "lco":
                ax.text(0.99, 0.95,
                        f"amplitude {a.amplitude[j]:.4g} {label_unit(names[row])}".rstrip(),
                        transform=ax.transAxes,
                        ha="right", va="top", fontsize="small",
                        bbox=dict(fc="white", ec="none", alpha=0.8))
            if col == 0:
                ax.set_ylabel(names[row], fontsize="small")
            ax.grid(True, alpha=0.3)
        axes[len(chans) - 1, col].set_xlabel(
            f"time [{time_unit}]" + (f" (last {cycles} periods)" if cut else ""))
        afr = axes[len(chans), col]
        dom = a.dominant if a is not None else 0
        if a is not None and a.spectrum.size:
            afr.plot(a.spectrum_freq_hz, a.spectrum, color="C0" if col == 0 else "k", lw=0.9)
            if np.isfinite(f) and a.kind != "divergence":
                afr.axvline(f, color="r", ls="--", lw=0.8)
        own = 4 * f if np.isfinite(f) and f > 0 else None
        fmax = fmax_hz or (4 * max(lco_f) if lco_f else own)
        if fmax:
            afr.set_xlim(0, fmax)
        afr.set_xlabel(f"frequency [{hz}]")
        dom_name = names[chans.index(dom)] if dom in chans else f"{word} {dom + 1}"
        afr.set_ylabel("|FFT|", fontsize="small")
        afr.set_title(f"spectrum of {dom_name.split(' [')[0]}", fontsize="small")
        afr.grid(True, alpha=0.3)
    fig.suptitle(title or "Fig. 9: limit-cycle oscillation", fontsize="large")
    fig.tight_layout()
    return fig


def plot_pole_loci(system, V_grid, controller=None, *, ax=None) -> Figure:
    """Pole loci of ΣAE over V, open loop and (optionally) closed with ``v = K zm`` (Fig. 10).

    The closed-loop poles are coloured by V (colour bar), so the speed at which a branch
    crosses into the right half-plane can be read off.

    Parameters
    ----------
    system : casflutter.aeroelastic.LoopFamily
        Any loop family (ROM loop, ROM loop behind a servo, the truth's loop): it provides
        ``state_matrix(V)`` and ``closed_loop_state_matrix(V, K)``. For a controller
        designed with the flap behind a servo, pass the family with the servo
        (:meth:`~casflutter.aeroelastic.AeroelasticSystem.with_servo`).
    V_grid : array_like
        Speed indices.
    controller : control.StateSpace, optional
        Continuous controller K (sensors -> flap).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new figure otherwise.
    """
    V_grid = np.asarray(V_grid, dtype=float)
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 5.0))
    fig = ax.figure
    ol = np.array([np.linalg.eigvals(system.state_matrix(V)) for V in V_grid])
    ax.scatter(ol.real.ravel(), ol.imag.ravel(), s=8, marker="x", color="tab:red", label="open loop")
    if controller is not None:
        cl = [np.linalg.eigvals(system.closed_loop_state_matrix(V, controller)) for V in V_grid]
        speed = np.concatenate([np.full(len(p), V) for p, V in zip(cl, V_grid)])
        cl = np.concatenate(cl)
        pts = ax.scatter(cl.real, cl.imag, s=10, marker="o", c=speed, cmap="viridis",
                         label="closed loop")
        fig.colorbar(pts, ax=ax, label="V (closed loop)")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re λ [1/s]")
    ax.set_ylabel("Im λ [rad/s]")
    ax.set_title(f"pole loci, V in [{V_grid.min():g}, {V_grid.max():g}]")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return fig
