"""Scaled plant sets, controller (un)scaling, adaptive frequency selection, realisation.

Helpers of :mod:`._synthesis` (paper §III.C): the set of augmented plants in static-gain form
with its exact evaluation (eigenvalues, exact H∞ norm of every closed loop), the adaptive
frequency set built around the exact peaks, and the well-conditioned realisation of the
final controller.
"""

from __future__ import annotations

from typing import Sequence

import control
import numpy as np
import scipy.linalg as sla

from ._plant import (Partition, exact_hinf_norm, partition, sigma_max_grid,
                     spectral_abscissa)

__all__ = ["verify_closed_loop"]


def _balance(P: Partition) -> np.ndarray:
    """Diagonal similarity that balances ``A`` (LAPACK gebal, no permutation)."""
    if P.nx == 0:
        return np.eye(0)
    _, T = sla.matrix_balance(P.A, permute=False)
    return T


def _io_scales(parts: Sequence[Partition]) -> tuple[np.ndarray, np.ndarray]:
    nu, ny = parts[0].B2.shape[1], parts[0].C2.shape[0]
    su = np.zeros(nu)
    sy = np.zeros(ny)
    for P in parts:
        su = np.maximum(su, np.linalg.norm(np.vstack([P.B2, P.D12]), axis=0))
        sy = np.maximum(sy, np.linalg.norm(np.hstack([P.C2, P.D21]), axis=1))
    su = np.where(su > 0, 1.0 / np.where(su > 0, su, 1.0), 1.0)
    sy = np.where(sy > 0, sy, 1.0)
    return su, sy


class _Problem:
    """Scaled, augmented plant set with exact evaluation of a static gain."""

    def __init__(self, parts: Sequence[Partition], order: int, su, sy):
        self.order = order
        self.su, self.sy = su, sy
        self.parts = [P.transformed(_balance(P), su, sy) for P in parts]
        self.aug = [P.augmented(order) for P in self.parts]
        self.nu, self.ny = parts[0].B2.shape[1], parts[0].C2.shape[0]
        eigs = np.concatenate([np.abs(np.linalg.eigvals(P.A)) for P in parts if P.nx] + [[1.0]])
        self.wscale = float(max(np.max(eigs), 1e-3))
        nz_eigs = eigs[eigs > 1e-8 * self.wscale]
        self.wmin = float(np.min(nz_eigs)) if nz_eigs.size else self.wscale

    def alpha(self, K: np.ndarray) -> float:
        return max(spectral_abscissa(P.closed_loop(K)[0]) for P in self.aug)

    def exact(self, K: np.ndarray) -> tuple[float, list[float], list[float]]:
        """Worst-case exact γ, per-plant γ and peak frequencies (γ = inf if unstable)."""
        gams, peaks = [], []
        for P in self.aug:
            A, B, C, D = P.closed_loop(K)
            if spectral_abscissa(A) >= 0:
                return np.inf, [], []
            g, w = exact_hinf_norm(control.ss(A, B, C, D))
            gams.append(g)
            peaks.append(w if np.isfinite(w) else 1e3 * self.wscale)
        return max(gams), gams, peaks

    def to_controller(self, K: np.ndarray) -> tuple[np.ndarray, ...]:
        """Unscaled ``(Ak, Bk, Ck, Dk)`` from the scaled static gain."""
        nu, ny = self.nu, self.ny
        Dt, Ct, Bt, Ak = K[:nu, :ny], K[:nu, ny:], K[nu:, :ny], K[nu:, ny:]
        Dk = self.su[:, None] * Dt / self.sy[None, :]
        Ck = self.su[:, None] * Ct
        Bk = Bt / self.sy[None, :]
        return Ak, Bk, Ck, Dk

    def from_controller(self, Ak, Bk, Ck, Dk) -> np.ndarray:
        """Scaled static gain from an unscaled controller."""
        nu, ny, k = self.nu, self.ny, self.order
        K = np.zeros((nu + k, ny + k))
        K[:nu, :ny] = Dk * self.sy[None, :] / self.su[:, None]
        K[:nu, ny:] = Ck / self.su[:, None]
        K[nu:, :ny] = Bk * self.sy[None, :]
        K[nu:, ny:] = Ak
        return K

    def select_omegas(self, K: np.ndarray, peaks: Sequence[Sequence[float]],
                      nslots: int) -> list[np.ndarray]:
        """Adaptive frequency set per plant: exact peaks, local maxima, then a log grid."""
        out = []
        for j, P in enumerate(self.aug):
            A, B, C, D = P.closed_loop(K)
            ev = np.linalg.eigvals(A)
            mags = np.abs(ev)
            lo = max(1e-2 * min(self.wmin, np.min(mags[mags > 0], initial=self.wscale)),
                     1e-6 * self.wscale)
            hi = 1e2 * max(self.wscale, np.max(mags, initial=0.0))
            dense = np.unique(np.concatenate([[0.0], np.geomspace(lo, hi, 240),
                                              np.abs(ev.imag[ev.imag > 0])]))
            sv = sigma_max_grid(A, B, C, D, dense)
            chosen: list[float] = []

            def add(w: float) -> None:
                if len(chosen) < nslots and all(abs(w - c) > 5e-3 * max(abs(c), lo)
                                                for c in chosen):
                    chosen.append(float(w))

            for w in reversed(list(peaks[j])[-(nslots // 2):]):
                add(w)
            inner = (sv[1:-1] >= sv[:-2]) & (sv[1:-1] >= sv[2:])
            locmax = np.flatnonzero(inner) + 1
            ends = [i for i in (0, len(sv) - 1)]
            cand = sorted(set(locmax.tolist() + ends), key=lambda i: -sv[i])
            for i in cand[:4]:
                add(dense[i])
                for nb in (i - 1, i + 1):
                    if 0 <= nb < len(dense):
                        add(0.5 * (dense[i] + dense[nb]))
            for i in cand[4:]:
                add(dense[i])
            for w in np.geomspace(lo, hi, nslots):
                add(w)
            while len(chosen) < nslots:  # pragma: no cover - only with tiny grids
                chosen.append(chosen[-1] * 1.5 + 1e-3)
            out.append(np.array(chosen))
        return out


def _gain_scale(K: np.ndarray) -> np.ndarray:
    m = max(np.max(np.abs(K), initial=0.0), 1.0)
    return np.maximum(np.abs(K), 0.1 * m)


def verify_closed_loop(P: control.StateSpace, K: control.StateSpace, nmeas: int,
                       ncon: int) -> tuple[float, float, float]:
    """Independent check of one plant/controller pair.

    Closes the loop with ``casflutter.verify.lft_closed_loop`` when available (python-control
    arithmetic otherwise) and returns ``(gamma, omega_peak, spectral_abscissa)`` with the exact
    norm; ``gamma`` is ``inf`` for an unstable loop.
    """
    try:
        from ..verify import lft_closed_loop  # noqa: PLC0415
        cl = lft_closed_loop(P, K, nmeas, ncon)
    except ImportError:  # pragma: no cover - the verify layer is part of the package
        part = partition(P, nmeas, ncon)
        k = K.nstates
        Kbar = np.block([[np.asarray(K.D, float).reshape(ncon, nmeas),
                          np.asarray(K.C, float).reshape(ncon, k)],
                         [np.asarray(K.B, float).reshape(k, nmeas),
                          np.asarray(K.A, float).reshape(k, k)]])
        cl = control.ss(*part.augmented(k).closed_loop(Kbar))
    alpha = spectral_abscissa(np.asarray(cl.A))
    if alpha >= 0:
        return np.inf, np.nan, alpha
    g, w = exact_hinf_norm(cl)
    return g, w, alpha


def _realize(Ak, Bk, Ck, Dk) -> control.StateSpace:
    """Real-Schur form of ``Ak`` with a diagonal scaling that balances ``Bk`` rows and ``Ck``
    columns (orthogonal + diagonal similarity: well conditioned)."""
    k = Ak.shape[0]
    if k == 0:
        return control.ss([], [], [], Dk) if Dk.size else control.ss(Dk)
    Tk, Z = sla.schur(Ak, output="real")
    Bz, Cz = Z.T @ Bk, Ck @ Z
    rb, cc = np.linalg.norm(Bz, axis=1), np.linalg.norm(Cz, axis=0)
    ok = (rb > 0) & (cc > 0)
    d = np.ones(k)
    d[ok] = np.sqrt(rb[ok] / cc[ok])
    d = np.clip(d, 1e-6, 1e6)
    A2 = Tk * d[None, :] / d[:, None]
    return control.ss(A2, Bz / d[:, None], Cz * d[None, :], Dk)


