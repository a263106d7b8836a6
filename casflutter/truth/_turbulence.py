"""Wind-tunnel turbulence and sensor noise for the truth's closed-loop runs (paper Fig. 11).

A wind tunnel is never quiet: its free stream carries turbulence and its sensors noise, so a
suppressed flutter mode keeps a residual response, and the attenuation of paper Fig. 11
("more than 90 %") is measured against that floor, not against the decay to rounding of a
noise-free simulation.

Gust.  A vertical gust velocity ``w_g(t)`` [m/s], uniform along the span, is a stationary
Gaussian process with the Dryden spectrum (MIL-F-8785C)

.. math:: \\Phi_w(\\omega) = \\sigma_w^2 \\frac{\\tau}{\\pi}
          \\frac{1 + 3 (\\tau \\omega)^2}{(1 + (\\tau \\omega)^2)^2},
          \\qquad \\tau = L_w / U,

whose shaping filter is ``H(s) = σ_w √(τ/π) (1 + √3 τ s) / (1 + τ s)²`` (rms ``σ_w``,
integral scale ``L_w``, airspeed ``U``).  :func:`dryden_gust` draws exact samples of it:
the filter driven by continuous white noise, discretised exactly (the state's transition and
the noise it collects over a sample, by Van Loan's matrix exponential), started from its
stationary distribution and scaled so that the stationary rms is exactly ``σ_w``.

Modal forces.  The gust changes each strip's angle of attack by ``w_g / U``; quasi-steady
strip theory turns it into the lift ``ρ U² b c_lα w_g / U`` per unit span at the elastic axis
(the quarter chord of a wing whose axis is there), so that the generalised-force coefficient
of eq. 6 is ``y_g,i = −c_lα (w_g / U) h̄_i`` with ``h̄_i`` the mean over the (equal) strips
of mode ``i``'s plunge (positive down).  It enters the structure as eq. 7's disturbance,
``w = V² y_g`` (:func:`gust_modal_forces`).  Linear, without the Küssner lag and without
spanwise correlation: a disturbance of the right size and spectrum, not a gust-load model.

Sensor noise.  Independent white Gaussian noise of rms ``noise`` on each sensor reading, in
the sensors' unit (m/s² for the seed wing's accelerometers).

Everything is drawn from ``numpy.random.default_rng(seed)``: one seed gives one record.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm, solve_discrete_lyapunov

from ..errors import ConfigError

__all__ = ["dryden_gust", "gust_modal_forces", "tunnel_disturbances"]


def dryden_gust(n: int, dt: float, sigma: float, tau: float,
                rng: np.random.Generator) -> np.ndarray:
    """Samples of the Dryden vertical gust (module docstring) every ``dt``.

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float
        Sample time [s].
    sigma : float
        Stationary rms of the gust ``σ_w`` (>= 0; 0 gives zeros).
    tau : float
        ``L_w / U`` [s] (> 0).
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    ndarray, shape (n,)
    """
    if sigma == 0:
        return np.zeros(n)
    # (1 + √3 τ s) / (1 + τ s)^2 in controllable form, unit white-noise input
    A = np.array([[0.0, 1.0], [-1.0 / tau ** 2, -2.0 / tau]])
    B = np.array([[0.0], [1.0 / tau ** 2]])
    C = np.array([[1.0, np.sqrt(3.0) * tau]])
    M = expm(np.block([[-A, B @ B.T], [np.zeros((2, 2)), A.T]]) * dt)
    Ad = M[2:, 2:].T
    Qd = Ad @ M[:2, 2:]
    P = solve_discrete_lyapunov(Ad, Qd)
    scale = sigma / np.sqrt((C @ P @ C.T).item())
    Lq = np.linalg.cholesky(Qd)
    x = np.linalg.cholesky(P) @ rng.standard_normal(2)
    out = np.empty(n)
    xi = rng.standard_normal((n, 2))
    for k in range(n):
        out[k] = C[0] @ x
        x = Ad @ x + Lq @ xi[k]
    return scale * out


def gust_modal_forces(truth, V: float) -> np.ndarray:
    """Eq. 7's disturbance per unit vertical gust velocity: ``w = V² y_g / w_g``.

    Parameters
    ----------
    truth : AeroelasticTruth
        A strip-theory truth with ``strip_shapes()``, ``airspeed(V)`` and ``params.lift_slope``
        (the seed wing).
    V : float
        Speed index.

    Returns
    -------
    ndarray, shape (N,)
        Per m/s of gust (module docstring).

    Raises
    ------
    ConfigError
        A truth without strip shapes or airspeed.
    """
    needed = ("strip_shapes", "airspeed")
    if not all(callable(getattr(truth, name, None)) for name in needed) or not hasattr(
            getattr(truth, "params", None), "lift_slope"):
        raise ConfigError(f"the gust acts through strip theory, and the truth "
                          f"{type(truth).__name__} has no strip shapes, airspeed and lift "
                          "slope; set gust_intensity = 0 for it")
    h = np.asarray(truth.strip_shapes()["h"], dtype=float)       # (N, strips), positive down
    U = float(truth.airspeed(V))
    return -float(V) ** 2 * float(truth.params.lift_slope) * h.mean(axis=1) / U


def tunnel_disturbances(truth, V: float, n: int, dt: float, *, gust_intensity: float,
                        gust_scale: float, noise: float, n_sensors: int,
                        seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The turbulence and the sensor noise of one run (module docstring).

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator (a strip-theory truth when ``gust_intensity > 0``).
    V : float
        Speed index.
    n : int
        Number of samples.
    dt : float
        Sample time [s].
    gust_intensity : float
        ``σ_w / U``, the turbulence intensity (0: no gust).
    gust_scale : float
        Integral scale ``L_w`` [m].
    noise : float
        Rms of each sensor's noise [sensor unit] (0: none).
    n_sensors : int
        Number of sensors.
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    w : ndarray, shape (n, N)
        Eq. 7's disturbance at the samples.
    sensor_noise : ndarray, shape (n, n_sensors)
    gust : ndarray, shape (n,)
        The gust velocity [m/s].
    """
    rng = np.random.default_rng(seed)
    N = truth.n_modes
    if gust_intensity > 0:
        b = gust_modal_forces(truth, V)
        U = float(truth.airspeed(V))
        gust = dryden_gust(n, dt, gust_intensity * U, gust_scale / U, rng)
        w = np.outer(gust, b)
    else:
        gust, w = np.zeros(n), np.zeros((n, N))
    sensor_noise = (noise * rng.standard_normal((n, n_sensors)) if noise > 0
                    else np.zeros((n, n_sensors)))
    return w, sensor_noise, gust
