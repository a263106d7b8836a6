"""Figures of the end-to-end study (paper Fig. 7, 8 and 11); each returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_rom_fit", "plot_flap_pulses", "plot_gain_ramp", "plot_hankel"]


def plot_rom_fit(model, data, *, max_samples: int = 2000, fit=None, mode_names=None,
                 time_unit: str = "s") -> Figure:
    """ROM against the truth, one panel per mode (paper Fig. 7).

    Panel ``i`` shows the generalised force ``y_i`` on the record that excites mode ``i``
    (free-run simulation of the ROM from the record's inputs).  The error printed is the
    table's definition, ``100 ||y_i - ŷ_i|| / ||y_i||`` over the free run after the first
    ``max_lag`` samples: on the record shown and, when ``fit`` is given, over all records
    (the number in the run's table).

    Parameters
    ----------
    model : HWLModel
        The ROM.
    data : IOData
        The records.
    max_samples : int
        Samples drawn per panel.
    fit : FitReport, optional
        The free-run fit on all records (:func:`casflutter.ident.fit_report`).
    mode_names : sequence of str, optional
        Names of the modes (1-based numbers are used either way).
    time_unit : str
        The time axis' unit.

    Returns
    -------
    matplotlib.figure.Figure
    """
    N = model.n_modes
    fig, axes = plt.subplots(N, 1, sharex=False, figsize=(7.5, 1.6 * N + 0.9))
    axes = np.atleast_1d(axes)
    skip = model.max_lag
    for i, ax in enumerate(axes):
        rec = data.records[min(i, len(data.records) - 1)]
        ysim = model.simulate(rec.u, rec.v, y0=rec.y[:model.max_lag])
        k = min(rec.n_samples, max_samples)
        t = np.arange(k) * data.dt
        err = 100 * np.linalg.norm(ysim[skip:, i] - rec.y[skip:, i]) / np.linalg.norm(
            rec.y[skip:, i])
        ax.plot(t, rec.y[:k, i], "k", lw=1.4, label="truth")
        ax.plot(t, ysim[:k, i], "C1--", lw=1.0, label="ROM (free run)")
        name = f" ({mode_names[i]})" if mode_names is not None and i < len(mode_names) else ""
        ax.set_ylabel(f"$y_{{{i + 1}}}$ [-]")
        text = f"mode {i + 1}{name}, record {rec.name}: error {err:.3f} % on this record"
        if fit is not None:
            text += f", {float(fit.error_percent[i]):.3f} % on all (table)"
        ax.set_title(text, fontsize=8, loc="right")
    axes[0].legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel(f"time [{time_unit}]")
    fig.suptitle("Fig. 7: generalised forces, ROM vs truth; error = 100 ‖y − ŷ‖ / ‖y‖",
                 fontsize=10)
    fig.tight_layout()
    return fig


def plot_flap_pulses(t, truth_zm, rom_zm, v, sensor_labels=("Acc1", "Acc2"), *,
                     time_unit: str = "s") -> Figure:
    """Sensor response to a flap pulse sequence: ROM loop against the truth (paper Fig. 8).

    Parameters
    ----------
    t : ndarray
        Times.
    truth_zm, rom_zm : ndarray, shape (K, m)
        Sensor records.
    v : ndarray
        Flap angle [rad].
    sensor_labels : sequence of str
        Axis label per sensor, with its unit.
    time_unit : str
        The time axis' unit.

    Returns
    -------
    matplotlib.figure.Figure
    """
    m = truth_zm.shape[1]
    fig, axes = plt.subplots(m + 1, 1, sharex=True, figsize=(7.5, 2.0 * (m + 1)))
    axes[0].plot(t, np.degrees(v), "C2")
    axes[0].set_ylabel("flap [deg]")
    for j in range(m):
        axes[j + 1].plot(t, truth_zm[:, j], "k", lw=1.3, label="truth")
        axes[j + 1].plot(t, rom_zm[:, j], "C1--", lw=1.0, label="ROM + Σs")
        axes[j + 1].set_ylabel(sensor_labels[j] if j < len(sensor_labels) else
                               f"sensor {j + 1}", fontsize=8)
    axes[1].legend(fontsize=8)
    axes[-1].set_xlabel(f"time [{time_unit}]")
    fig.suptitle("Fig. 8: response to a flap pulse sequence", fontsize=10)
    fig.tight_layout()
    return fig


def plot_gain_ramp(t, zm, gain, v, sensor_labels=("Acc1", "Acc2"), *, phases=None,
                   open_loop_amplitude=None, dominant: int = 0, flap_limit_deg=None,
                   time_unit: str = "s", title: str | None = None, axes=None) -> Figure:
    """Closed-loop history with the controller gain ramped 0 -> 1 and released (Fig. 11).

    Parameters
    ----------
    t : ndarray
        Times.
    zm : ndarray, shape (K, m)
        Sensor records.
    gain : ndarray
        Gain schedule.
    v : ndarray
        Flap angle [rad].
    sensor_labels : sequence of str
        Axis label per sensor, with its unit.
    phases : (float, float, float), optional
        Ends of the open-loop, ramp and hold phases (shaded).
    open_loop_amplitude : float, optional
        The established LCO's amplitude of the ``dominant`` sensor (drawn as ±lines).
    dominant : int
        0-based dominant sensor.
    flap_limit_deg : float, optional
        Flap travel (drawn as ±lines).
    time_unit : str
        The time axis' unit.
    title : str, optional
    axes : sequence of matplotlib.axes.Axes, optional
        ``m + 2`` axes to draw into (a column of a larger figure, e.g. one per speed; the
        title then goes on the top one); default a figure of its own.

    Returns
    -------
    matplotlib.figure.Figure
    """
    m = zm.shape[1]
    own = axes is None
    if own:
        fig, axes = plt.subplots(m + 2, 1, sharex=True, figsize=(7.5, 1.8 * (m + 2) + 0.4))
    else:
        fig = axes[0].figure
    axes[0].plot(t, gain, "C3")
    axes[0].set_ylabel("controller gain")
    axes[1].plot(t, np.degrees(v), "C2", lw=0.8)
    if flap_limit_deg is not None:
        for sgn in (1, -1):
            axes[1].axhline(sgn * flap_limit_deg, color="C2", ls=":", lw=0.8)
    axes[1].set_ylabel("flap [deg]")
    for j in range(m):
        axes[j + 2].plot(t, zm[:, j], "k", lw=0.6)
        axes[j + 2].set_ylabel(sensor_labels[j] if j < len(sensor_labels) else
                               f"sensor {j + 1}", fontsize=8)
    if open_loop_amplitude is not None:
        for sgn in (1, -1):
            axes[dominant + 2].axhline(sgn * open_loop_amplitude, color="C0", ls="--", lw=0.8)
    if phases is not None:
        t0, t1, t2 = phases
        for a in axes:
            a.axvspan(t[0], t0, color="C3", alpha=0.07, lw=0)
            a.axvspan(t1, t2, color="C0", alpha=0.07, lw=0)
        axes[0].text(0.5 * (t[0] + t0), 0.5, "open loop\n(established LCO)", ha="center",
                     va="center", fontsize=7)
        axes[0].text(0.5 * (t1 + t2), 0.5, "full gain", ha="center", va="center", fontsize=7)
        axes[0].text(0.5 * (t2 + t[-1]), 0.5, "released", ha="center", va="center",
                     fontsize=7)
    axes[-1].set_xlabel(f"time [{time_unit}]")
    if not own:
        if title:
            axes[0].set_title(title, fontsize=9)
        return fig
    fig.suptitle(title or "Fig. 11: flutter suppression, gain ramp and release", fontsize=10)
    fig.tight_layout()
    return fig


def plot_hankel(hankel_sv, order: int, *, paper_order: int | None = 15, n: int = 40) -> Figure:
    """Hankel singular values of the linearised ROM and the chosen order of Σf."""
    S = np.asarray(hankel_sv, dtype=float)[:n]
    fig, ax = plt.subplots(figsize=(6, 3))
    ax.semilogy(np.arange(1, S.size + 1), S / S[0], "o-", ms=3)
    ax.axvline(order, color="C3", ls="--", label=f"nf = {order}")
    if paper_order and paper_order != order:
        ax.axvline(paper_order, color="C2", ls=":", label=f"paper nf = {paper_order}")
    ax.set_xlabel("index i")
    ax.set_ylabel(r"$\sigma_i/\sigma_1$")
    ax.set_title("Hankel singular values of the linearised ROM", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
