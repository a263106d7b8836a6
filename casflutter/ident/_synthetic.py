"""Known HWL models and their data, for checks, benchmarks and the demo, and the small ROM
of the documentation's examples (:func:`example_rom`)."""

from __future__ import annotations

import numpy as np

from scipy.signal import butter, sosfiltfilt

from ..data import IOData, Record, chirp_excitation
from ..errors import ConfigError
from ..truth import load_problem, truth_records
from ._common_denominator import identify_common_denominator
from ._kernels import duffing_rk4
from ._model import HWLModel
from ._orders import HWLOrders
from ._structure import HWLStructure

__all__ = ["random_hwl_model", "synthetic_data", "duffing_data", "example_rom"]


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


def duffing_data(n_samples: int = 65000, *, f0: float = 1.0, oversampling: float = 10.0,
                 zeta: float = 0.1, cubic: float = 0.05, band: float = 3.0,
                 amplitude: float = 1.0, noise: float = 0.01, offset: float = 0.0,
                 seed: int = 0) -> IOData:
    """A single-input single-output record of a Duffing-type oscillator (cubic stiffness in
    the feedback), a stand-in for measured nonlinear benchmark records such as Silverbox.

    The system ``y'' + 2 zeta w0 y' + w0^2 (y + cubic y^3) = w0^2 u(t)`` (``w0 = 2 pi f0``,
    unit static gain of the linear part) is driven by Gaussian noise low-pass filtered to
    ``band * f0`` (zero phase, RMS ``amplitude``), integrated by Runge--Kutta with 20 steps
    per sample and the input held between samples, and sampled at ``oversampling * f0``.
    White noise of ``noise`` times the output RMS is added to the output, and ``offset`` to
    both signals (a sensor bias).

    Returns
    -------
    IOData
        One record, ``u`` the input and ``y`` the output (``N = 1``).
    """
    for name, value, ok in (("n_samples", n_samples, isinstance(n_samples, int) and n_samples > 10),
                            ("oversampling", oversampling, oversampling > 2 * band),
                            ("zeta", zeta, zeta > 0), ("f0", f0, f0 > 0)):
        if not ok:
            raise ConfigError(f"duffing_data {name}={value!r} is not allowed (n_samples > 10, "
                              "f0 > 0, zeta > 0, oversampling > 2 band)")
    rng = np.random.default_rng(seed)
    dt = 1.0 / (oversampling * f0)
    w0 = 2 * np.pi * f0
    sos = butter(6, band / (oversampling / 2), output="sos")
    u = sosfiltfilt(sos, rng.normal(size=n_samples + 400))[200:-200]
    u *= amplitude / np.sqrt(np.mean(u ** 2))
    y = duffing_rk4(w0 ** 2 * u, dt, w0, zeta, w0 ** 2 * cubic, 20)
    y = y + noise * np.sqrt(np.mean(y ** 2)) * rng.normal(size=n_samples)
    return IOData.from_arrays(y=y[:, None] + offset, u=u[:, None] + offset, dt=dt,
                              name="duffing", output_names=("y",), u_names=("u",))


def example_rom():
    """The linear ROM of the typical section that the examples of the later stages start from.

    Chirp records of the typical section (Hodges & Pierce HP-1) at the speed index
    ``V0 = 1.8`` (``dt = 0.1``, 60 time units, band 0.002-1 cycles per time unit), identified
    by :func:`identify_common_denominator`: a two-mode model that identifies in about a
    second and carries the section's flutter, so the realisation, the loop, the flutter
    search, the LFT and the loop simulation can be tried on it.

    Returns
    -------
    HWLModel
        The identified model (a new one at every call).

    See Also
    --------
    identify_common_denominator : how it is identified.
    realize : its continuous Σf (eq. 5).

    Examples
    --------
    >>> import casflutter as cf
    >>> rom = cf.example_rom()
    >>> rom.n_modes, rom.dt
    (2, 0.1)
    """
    truth = load_problem("typical_section")
    data = truth_records(truth, V0=1.8, dt=0.1, duration=60.0, band=(0.002, 1.0))
    return identify_common_denominator(data).model
