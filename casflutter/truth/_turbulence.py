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
strip theory turns it into the lift ``ρ U² b c_lα w_g / U`` per unit span (and its moment
about the elastic axis, none for the seed wing's quarter-chord axis), so that the
generalised-force coefficient of eq. 6 is ``y_g,i = −c_lα (w_g / U) h̄_i`` with ``h̄_i`` the
mean over the (equal) strips of mode ``i``'s plunge (positive down).  It enters the structure
as eq. 7's disturbance, ``w = V² y_g`` (:func:`gust_modal_forces`, through the truth's own
strip operator).  Linear, without the Küssner lag and without
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
    """Samples of the Dryden vertical gust every ``dt``.

    A stationary Gaussian process with the Dryden spectrum (MIL-F-8785C)
    ``Φ(ω) = σ² (τ/π) (1 + 3 (τω)²) / (1 + (τω)²)²``: its shaping filter
    ``(1 + √3 τ s) / (1 + τ s)²`` driven by white noise, discretised exactly (the transition
    and the noise collected over a sample by Van Loan's matrix exponential), started from its
    stationary distribution and scaled so that the stationary rms is exactly ``σ``.

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

    The gust changes each strip's angle of attack by ``w_g / U``, i.e. its downwash by
    ``w_g``; quasi-steady, it acts through the truth's own steady circulatory strip lift and
    moment (the ``W`` of :meth:`~casflutter.truth.AeroelasticTruth.aero_matrices`, one column
    per strip, per unit modal mass), ``w = W 1 w_g / α`` (``u'' += α w``, eq. 6-7).  With the
    elastic axis at the quarter chord (the seed wing) that is
    ``y_g,i = −c_lα (w_g / U) h̄_i``, ``h̄_i`` the mean over the equal strips of mode ``i``'s
    plunge (positive down).  A uniform gust without the Küssner lag or spanwise correlation:
    a disturbance of the right size and spectrum rather than a gust-load model.

    Parameters
    ----------
    truth : AeroelasticTruth
        A strip-theory truth: ``strip_shapes()``, ``airspeed(V)`` and an aerodynamic operator
        with one downwash per strip (the seed wing).
    V : float
        Speed index.

    Returns
    -------
    ndarray, shape (N,)
        Per m/s of gust.

    Raises
    ------
    ConfigError
        A truth without strips or airspeed.
    """
    strips = getattr(truth, "strip_shapes", None)
    W = None
    if callable(strips) and getattr(getattr(truth, "speed", None), "has_airspeed", False):
        W = np.asarray(truth.aero_matrices(V).W, dtype=float)
        if W.shape[1] != np.size(strips()["y"]):
            W = None
    if W is None:
        raise ConfigError(f"the gust acts through strip theory, and the truth "
                          f"{type(truth).__name__} has no aerodynamic strips with an airspeed; "
                          "set gust_intensity = 0 for it")
    return W.sum(axis=1) / float(truth.alpha)


def tunnel_disturbances(truth, V: float, n: int, dt: float, *, gust_intensity: float,
                        gust_scale: float, noise: float, n_sensors: int,
                        seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The turbulence and the sensor noise of one run: a Dryden gust of rms
    ``gust_intensity U`` and time constant ``gust_scale / U`` (:func:`dryden_gust`) through
    :func:`gust_modal_forces`, and independent white noise of rms ``noise`` on each sensor,
    all drawn from ``numpy.random.default_rng(seed)`` (one seed, one record).

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
