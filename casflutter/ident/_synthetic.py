"""Known HWL models and their data, for checks, benchmarks and the demo."""

from __future__ import annotations

import numpy as np

from ..data import IOData, Record, chirp_excitation
from ._model import HWLModel, HWLStructure
from ._orders import HWLOrders

__all__ = ["random_hwl_model", "synthetic_data"]


def random_hwl_model(n_modes: int = 5, orders=(3, 1, 1, 1, 2, 2), *, has_u: bool = True,
                     has_v: bool = True, dt: float = 0.005, nonlinearity: float = 0.2,
                     ar_radius: float = 0.5, alpha_ratio: float = 0.25,
                     seed: int = 0) -> HWLModel:
    """A random, stable HWL model with every coupling present.

    The linear autoregression has spectral radius ``ar_radius`` (per AR lag), the higher
    polynomial coefficients are of size ``nonlinearity`` (relative to the unit linear
    coefficient; ``alpha_ratio`` times that for the output polynomials alpha, which act inside
    the feedback and would otherwise destabilise the recursion), so that unit-amplitude inputs give a visibly but mildly nonlinear response.
    """
    rng = np.random.default_rng(seed)
    o = HWLOrders.from_tuple(orders)
    N = n_modes
    structure = HWLStructure(o, N, has_u, has_v)
    def signed(shape, lo, hi):
        return rng.choice([-1.0, 1.0], size=shape) * rng.uniform(lo, hi, size=shape)
    A = np.zeros((o.na, N, N))
    for m in range(o.na):
        M = rng.normal(size=(N, N))
        A[m] = M * (ar_radius / max(np.abs(np.linalg.eigvals(M)).max(), 1e-12)) / max(o.na, 1)
    coeffs = {"A": A, "alpha": np.concatenate([np.ones((1, N, N)),
                                               signed((o.q - 1, N, N), 0.3, 1) * nonlinearity * alpha_ratio])}
    n_in = o.mu + o.nb + 1
    if has_u:
        HB = signed((n_in, N, N), 0.05, 0.2)
        coeffs.update(H=HB[:o.mu], B=HB[o.mu:],
                      gamma=np.concatenate([np.ones((1, N, N)),
                                            signed((o.p - 1, N, N), 0.3, 1) * nonlinearity]))
    if has_v:
        hb = signed((n_in, N), 0.05, 0.2)
        coeffs.update(h=hb[:o.mu], b=hb[o.mu:],
                      beta=np.concatenate([np.ones((1, N)),
                                           signed((o.p - 1, N), 0.3, 1) * nonlinearity]))
    return HWLModel(structure, structure.pack(coeffs), dt)


def synthetic_data(model: HWLModel, n_samples: int = 4000, *, n_records: int = 1,
                   band: tuple[float, float] | None = None, amplitude: float = 1.0,
                   noise: float = 0.0, seed: int = 0) -> IOData:
    """Chirp-excited records of ``model`` (free-run outputs), optionally with white
    measurement noise of standard deviation ``noise`` times each output's RMS."""
    rng = np.random.default_rng(seed)
    dt = model.dt
    if band is None:
        band = (0.005 / dt, 0.4 / dt)
    N = model.n_modes
    recs = []
    for rec in range(n_records):
        sub = int(rng.integers(2 ** 31))
        u = chirp_excitation(n_samples, dt, N, band=band, amplitude=amplitude, seed=sub) \
            if model.has_u else None
        v = chirp_excitation(n_samples, dt, 1, band=band, amplitude=amplitude,
                             seed=sub + 1)[:, 0] if model.has_v else None
        y = model.simulate(u, v, n_samples=n_samples)
        if noise:
            y = y + noise * np.sqrt(np.mean(y ** 2, axis=0)) * rng.normal(size=y.shape)
        recs.append(Record(y, u, v, f"synthetic[{rec}]"))
    return IOData(tuple(recs), dt, output_names=model.output_names, u_names=model.u_names)
