"""Truth chirp records and the linear ROM identification used by the ROM flutter route.

The paper (§IV.A) drives a full-order CFD solver with band-limited chirps on the modal
displacements and records the generalised aerodynamic forces ``y``.  Here the truth
simulators of :mod:`casflutter.truth` play the CFD solver.

Grid velocities.  A CFD solver advances in time steps and computes the grid velocity and
acceleration of prescribed motion from the displacement samples by backward differences;
its force samples are therefore a *causal* function of the displacement samples.  The
truth's :meth:`aero_forces` instead takes exact derivatives; the sampled map is then
exactly non-causal (the apparent-mass term ``u''(t_k)`` needs future samples), and every
causal discrete model fitted to it by least squares places poles outside the unit circle
(measured: poles near ``z = -4`` on the typical section) to imitate the phase lead.  We
therefore pass the truth second-order backward-difference (BDF2) derivatives, as a
second-order implicit CFD code would, which keeps the data causal; the resulting
``O((omega dt)^2)`` derivative error is part of the measured ROM error.

Identification.  The truth aerodynamics are linear in ``u`` (no nonlinear coefficient can be
identified), so the HWL model is used with ``p = q = 1`` (the paper's ``p = q = 2`` adds
polynomial coefficients that the data determine as zero).  The Wagner lag states obey the
same two rates on every strip, so the aerodynamic transfer matrix has one scalar
denominator: the model's ``A^(m)`` are ``a_m I``.  With full ``N x N`` matrices ``A^(m)``
the regression is rank-deficient on the typical section (the lag enters through a rank-one
matrix; measured condition number ~1e16) and :func:`casflutter.ident.identify` refuses
it, correctly; lower orders are identified but inadequate (measured at V0 = 1.8 / 110 m/s
with these records: the paper's orders ``(3, 1, 1, 1, 2, 2)`` give an unstable Σf on both
problems; ``(1, 2, 2, 0, 1, 1)`` gives an unstable Σf on the typical section and, on the
Goland wing, a stable one with 0.025% prediction error whose flutter speed is nevertheless
16% below that of the frozen-aerodynamics truth it should reproduce).
:func:`identify_common_denominator` solves the constrained least-squares
problem (variable projection: the scalar ``a_m`` from the residual orthogonal to the input
regressors, then the input matrices) and returns a standard :class:`HWLModel` with
orders ``(mu, na, nb, r, p, q) = (1, na, nb - 1, 0, 1, 1)``.  On BDF2 data the fit is exact
to rounding (relative residual ~1e-14) for ``na = 2``, ``nb = 6``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..data import IOData, Record
from ..errors import ConfigError, DataError
from ..ident import HWLModel

__all__ = ["chirp_motion", "backward_derivatives", "truth_records", "RomIdentification",
           "identify_common_denominator"]


def chirp_motion(timepts, band: tuple[float, float], amplitude: float = 1.0,
                 taper: float = 0.1, phase: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A tapered linear chirp and its exact first and second derivatives.

    ``s(t) = amplitude w(t) sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)) + phase)`` with a
    raised-cosine taper ``w`` over the first and last ``taper`` fraction of the record
    (so the motion starts and ends at rest, smoothly).

    Parameters
    ----------
    timepts : array_like, shape (K,)
        Increasing sample times (the record starts at ``timepts[0]``).
    band : (float, float)
        Start and end frequency [Hz, i.e. cycles per time unit of the problem].
    amplitude : float
        Peak amplitude.
    taper : float
        Fraction of the record tapered at each end, in (0, 0.5].
    phase : float
        Phase offset [rad].

    Returns
    -------
    s, sdot, sddot : ndarray, shape (K,)
    """
    t = np.asarray(timepts, dtype=float).ravel()
    if t.size < 4 or np.any(np.diff(t) <= 0):
        raise DataError("timepts must hold at least 4 increasing samples")
    if not 0.0 < taper <= 0.5:
        raise ConfigError(f"taper={taper} must lie in (0, 0.5]")
    f0, f1 = map(float, band)
    if not 0.0 <= f0 < f1:
        raise ConfigError(f"chirp band {band} must satisfy 0 <= f_low < f_high [Hz]")
    t = t - t[0]
    Tr = t[-1]
    k = (f1 - f0) / Tr
    ph = 2 * np.pi * (f0 * t + 0.5 * k * t * t) + phase
    d1 = 2 * np.pi * (f0 + k * t)
    d2 = 2 * np.pi * k
    Tt = taper * Tr
    w, w1, w2 = np.ones_like(t), np.zeros_like(t), np.zeros_like(t)
    for mask, x, sgn in ((t < Tt, t, 1.0), (t > Tr - Tt, Tr - t, -1.0)):
        xx = np.pi * x[mask] / Tt
        w[mask] = 0.5 * (1.0 - np.cos(xx))
        w1[mask] = sgn * 0.5 * np.pi / Tt * np.sin(xx)
        w2[mask] = 0.5 * (np.pi / Tt) ** 2 * np.cos(xx)
    s, c = np.sin(ph), np.cos(ph)
    u = w * s
    ud = w1 * s + w * d1 * c
    udd = w2 * s + 2 * w1 * d1 * c + w * d2 * c - w * d1 * d1 * s
    return amplitude * u, amplitude * ud, amplitude * udd


def backward_derivatives(x, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Second-order backward differences (BDF2) of samples, at rest before the record.

    ``xdot(k) = (3 x_k - 4 x_{k-1} + x_{k-2}) / (2 dt)``,
    ``xddot(k) = (2 x_k - 5 x_{k-1} + 4 x_{k-2} - x_{k-3}) / dt^2``, with ``x_{k<0} = 0``:
    the grid velocity and acceleration of a second-order implicit CFD time step.
    """
    x = np.asarray(x, dtype=float)
    xp = np.concatenate([np.zeros((3,) + x.shape[1:]), x], axis=0)
    d1 = (3 * xp[3:] - 4 * xp[2:-1] + xp[1:-2]) / (2 * dt)
    d2 = (2 * xp[3:] - 5 * xp[2:-1] + 4 * xp[1:-2] - xp[:-3]) / dt ** 2
    return d1, d2


def truth_records(truth, V: float, *, dt: float, duration: float,
                  band: tuple[float, float], amplitude: float = 0.01, taper: float = 0.1,
                  flap: bool = True) -> IOData:
    """Chirp records of a truth simulator at speed index ``V`` (the paper's CFD runs).

    One record per input channel (each modal displacement, then the flap): that channel
    follows :func:`chirp_motion`, the others are held at zero, and the forces ``y`` come
    from ``truth.aero_forces`` with BDF2 grid velocities (module docstring).

    Parameters
    ----------
    truth : casflutter.truth.AeroelasticTruth
    V : float
        Speed index.
    dt, duration : float
        Sampling time and record length [time unit of the problem].
    band : (float, float)
        Chirp band [Hz of the problem's time unit].
    amplitude, taper : float
        Chirp amplitude (the aerodynamics are linear: it only sets the scale) and taper.
    flap : bool
        Also excite the flap (the ROM then has the input ``v``).

    Returns
    -------
    IOData
        ``N`` (or ``N + 1``) records of ``round(duration / dt)`` samples.
    """
    if not (np.isfinite(dt) and dt > 0 and np.isfinite(duration) and duration > 10 * dt):
        raise ConfigError(f"need dt > 0 and duration > 10 dt, got dt={dt}, duration={duration}")
    if band[1] >= 0.5 / dt:
        raise ConfigError(f"chirp band top {band[1]} Hz is above the Nyquist frequency "
                          f"{0.5 / dt:g} Hz of dt={dt}; lower it or sample faster")
    N = truth.n_modes
    K = int(round(duration / dt))
    t = np.arange(K) * dt
    s, _, _ = chirp_motion(t, band, amplitude, taper)
    names = truth.modal_structure().mode_names
    n_in = N + (1 if flap else 0)
    recs = []
    for j in range(n_in):
        w = np.zeros((K, N + 1))
        w[:, j] = s
        d1, d2 = backward_derivatives(w, dt)
        y = truth.aero_forces(t, w[:, :N], w[:, N], V, udot=d1[:, :N], uddot=d2[:, :N],
                              vdot=d1[:, N], vddot=d2[:, N])
        label = names[j] if j < N else "flap"
        recs.append(Record(y, w[:, :N], w[:, N] if flap else None, name=f"chirp {label}"))
    return IOData(tuple(recs), dt, output_names=tuple(f"y[{n}]" for n in names),
                  u_names=tuple(f"u[{n}]" for n in names), v_name="v",
                  meta={"V": float(V), "band": tuple(band), "derivatives": "BDF2"})


@dataclass(frozen=True)
class RomIdentification:
    """A linear HWL ROM identified with a common scalar denominator.

    Attributes
    ----------
    model : HWLModel
        Orders ``(1, na, nb - 1, 0, 1, 1)``, ``A^(m) = a_m I``.
    a : ndarray, shape (na,)
        Denominator ``1 + a_1 z^-1 + ... + a_na z^-na``.
    poles : ndarray
        Its roots (discrete poles of the aerodynamic lags).
    relative_residual : float
        ``||Y - Yhat||_F / ||Y||_F`` of the one-step equation error on the data.
    condition_number : float
        Of the column-normalised input regressor matrix.
    stable : bool
        All ``|poles| < 1``.
    V : float or None
        Speed index of the data (from ``data.meta``).
    wall_time : float
        Seconds.
    """

    model: HWLModel
    a: np.ndarray
    poles: np.ndarray
    relative_residual: float
    condition_number: float
    stable: bool
    V: float | None
    wall_time: float


def identify_common_denominator(data: IOData, na: int = 2, nb: int = 6) -> RomIdentification:
    """Least-squares HWL ROM with ``p = q = 1`` and ``A^(m) = a_m I`` (module docstring).

    ``y(k) = -sum_{m=1}^{na} a_m y(k-m) + sum_{l=0}^{nb} G_l [u; v](k-l)``; the scalars
    ``a_m`` are found by variable projection (the exact least-squares solution), then the
    ``G_l``.

    Parameters
    ----------
    data : IOData
        Records with inputs ``u`` (and optionally ``v``).
    na : int
        Denominator order (2 for Jones' two-lag Wagner function).
    nb : int
        Largest input lag (6 makes the BDF2 truth data exactly representable).

    Returns
    -------
    RomIdentification

    Raises
    ------
    DataError
        No ``u`` input, too few samples, or a rank-deficient (non-exciting) regression.
    """
    t0 = time.perf_counter()
    if not data.has_u:
        raise DataError("the aerodynamic ROM needs the modal-displacement input u")
    if not (isinstance(na, int) and na >= 1 and isinstance(nb, int) and nb >= 1):
        raise ConfigError(f"orders na={na!r}, nb={nb!r} must be integers >= 1")
    N = data.n_modes
    L = max(na, nb)
    W_rows, Y_rows, Ylag = [], [], [[] for _ in range(na)]
    for rec in data.records:
        w = rec.u if rec.v is None else np.column_stack([rec.u, rec.v])
        K = rec.n_samples
        if K <= L + 1:
            raise DataError(f"record {rec.name!r} has {K} samples, not more than the largest "
                            f"lag {L} + 1")
        W_rows.append(np.hstack([w[L - l:K - l] for l in range(nb + 1)]))
        Y_rows.append(rec.y[L:])
        for m in range(na):
            Ylag[m].append(rec.y[L - m - 1:K - m - 1])
    Wm = np.vstack(W_rows)
    Y = np.vstack(Y_rows)
    Yl = [np.vstack(b) for b in Ylag]
    if Wm.shape[0] < Wm.shape[1] + na:
        raise DataError(f"too few samples: {Wm.shape[0]} equations for {Wm.shape[1] + na} "
                        "unknowns per output; record longer data")
    cn = np.linalg.norm(Wm, axis=0)
    if np.any(cn == 0):
        raise DataError("non-exciting input: some input channel is identically zero; "
                        "excite every input or drop it")
    Q, R = np.linalg.qr(Wm / cn)
    sv = np.linalg.svd(R, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf
    if not cond < 1e12:
        raise DataError(f"non-exciting input: the input regression is rank-deficient "
                        f"(condition number {cond:.3g}); widen the chirp band or lower nb")

    def perp(M):
        return M - Q @ (Q.T @ M)

    Yp = perp(Y)
    Amat = np.column_stack([perp(M).ravel() for M in Yl])
    a = np.linalg.lstsq(Amat, -Yp.ravel(), rcond=None)[0]
    rhs = Y + sum(a[m] * Yl[m] for m in range(na))
    G = np.linalg.solve(R, Q.T @ rhs) / cn[:, None]
    resid = rhs - Wm @ G
    rel = float(np.linalg.norm(resid) / np.linalg.norm(Y))
    n_w = Wm.shape[1] // (nb + 1)
    Gl = G.reshape(nb + 1, n_w, N).transpose(0, 2, 1)  # (nb+1, N, n_w)
    orders = (1, na, nb - 1, 0, 1, 1)
    kw = {"A": np.array([a[m] * np.eye(N) for m in range(na)]), "alpha": np.ones((1, N, N)),
          "H": Gl[:1, :, :N], "B": Gl[1:, :, :N], "gamma": np.ones((1, N, N))}
    if data.has_v:
        kw.update(h=Gl[:1, :, N], b=Gl[1:, :, N], beta=np.ones((1, N)))
    model = HWLModel.from_coefficients(orders, dt=data.dt, output_names=data.output_names,
                                       u_names=data.u_names, v_name=data.v_name, **kw)
    poles = np.roots(np.r_[1.0, a])
    V = data.meta.get("V") if isinstance(data.meta, dict) else None
    return RomIdentification(model=model, a=np.asarray(a), poles=poles,
                             relative_residual=rel, condition_number=cond,
                             stable=bool(np.all(np.abs(poles) < 1.0)), V=V,
                             wall_time=time.perf_counter() - t0)
