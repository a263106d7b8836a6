"""Figures of the end-to-end study (paper Fig. 7, 8 and 11); each returns a Figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_rom_fit", "plot_flap_pulses", "plot_gain_ramp", "plot_hankel"]


def plot_rom_fit(model, data, *, max_samples: int = 2000) -> Figure:
    """ROM against the truth, one panel per mode (paper Fig. 7).

    Panel ``i`` shows the generalised force ``y_i`` on the record that excites mode ``i``
    (free-run simulation of the ROM from the record's inputs) with the error in percent.
    """
    N = model.n_modes
    fig, axes = plt.subplots(N, 1, sharex=False, figsize=(7.5, 1.6 * N + 0.6))
    axes = np.atleast_1d(axes)
    for i, ax in enumerate(axes):
        rec = data.records[min(i, len(data.records) - 1)]
        ysim = model.simulate(rec.u, rec.v, y0=rec.y[:model.max_lag])
        k = min(rec.n_samples, max_samples)
        t = np.arange(k) * data.dt
        err = 100 * np.linalg.norm(ysim[:, i] - rec.y[:, i]) / np.linalg.norm(rec.y[:, i])
        ax.plot(t, rec.y[:k, i], "k", lw=1.4, label="truth")
        ax.plot(t, ysim[:k, i], "C1--", lw=1.0, label="ROM")
        ax.set_ylabel(f"$y_{i + 1}$")
        ax.set_title(f"{rec.name}: error {err:.3f} %", fontsize=8, loc="right")
    axes[0].legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("ROM vs truth per mode (paper Fig. 7)", fontsize=10)
    fig.tight_layout()
    return fig


def plot_flap_pulses(t, truth_zm, rom_zm, v, sensor_names=("Acc1", "Acc2")) -> Figure:
    """Sensor response to a flap pulse sequence: ROM loop against the truth (paper Fig. 8)."""
    m = truth_zm.shape[1]
    fig, axes = plt.subplots(m + 1, 1, sharex=True, figsize=(7.5, 2.0 * (m + 1)))
    axes[0].plot(t, np.degrees(v), "C2")
    axes[0].set_ylabel("flap [deg]")
    for j in range(m):
        axes[j + 1].plot(t, truth_zm[:, j], "k", lw=1.3, label="truth")
        axes[j + 1].plot(t, rom_zm[:, j], "C1--", lw=1.0, label="ROM + Σs")
        axes[j + 1].set_ylabel(sensor_names[j] if j < len(sensor_names) else f"z{j + 1}")
    axes[1].legend(fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("response to a flap pulse sequence (paper Fig. 8)", fontsize=10)
    fig.tight_layout()
    return fig


def plot_gain_ramp(t, zm, gain, v, sensor_names=("Acc1", "Acc2")) -> Figure:
    """Closed-loop history with the controller gain ramped 0 -> 1 and released (Fig. 11)."""
    m = zm.shape[1]
    fig, axes = plt.subplots(m + 2, 1, sharex=True, figsize=(7.5, 1.8 * (m + 2)))
    axes[0].plot(t, gain, "C3")
    axes[0].set_ylabel("gain")
    axes[1].plot(t, np.degrees(v), "C2", lw=0.8)
    axes[1].set_ylabel("flap [deg]")
    for j in range(m):
        axes[j + 2].plot(t, zm[:, j], "k", lw=0.7)
        axes[j + 2].set_ylabel(sensor_names[j] if j < len(sensor_names) else f"z{j + 1}")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("flutter suppression: gain ramp and release (paper Fig. 11)", fontsize=10)
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
    ax.set_xlabel("index")
    ax.set_ylabel(r"$\sigma_i/\sigma_1$")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
