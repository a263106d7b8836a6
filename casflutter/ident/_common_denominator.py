"""Identification of a linear HWL ROM with one scalar denominator (``A^(m) = a_m I``).

When the aerodynamics are linear in the motion (the truth simulators' Wagner lags) no
nonlinear coefficient can be identified, so the HWL model is used with ``p = q = 1``.  The
Wagner lag states obey the same rates on every strip, so the aerodynamic transfer matrix has
one scalar denominator: the model's ``A^(m)`` are ``a_m I``.  With full ``N x N`` matrices
``A^(m)`` the regression of :func:`casflutter.ident.identify` is rank-deficient for such data
(the lag enters through a rank-one matrix) and is refused.

:func:`identify_common_denominator` solves the constrained least-squares problem by variable
projection: the scalars ``a_m`` from the residual orthogonal to the input regressors, then
the input matrices.  It returns a standard :class:`~casflutter.ident.HWLModel` with orders
``(mu, na, nb, r, p, q) = (1, na, nb - 1, 0, 1, 1)``.  On records with BDF2 grid velocities
(:func:`casflutter.truth.truth_records`) the Jones two-lag aerodynamics are exactly such a
model with ``na = 2``, ``nb = 6``, so the fit is exact to rounding.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..data import IOData
from ..errors import ConfigError, DataError
from ._model import HWLModel
from ._regression import _dead_channels, _rank_hint

__all__ = ["CommonDenominatorResult", "identify_common_denominator"]


@dataclass(frozen=True)
class CommonDenominatorResult:
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

    __repr__ = result_repr

    model: HWLModel
    a: np.ndarray
    poles: np.ndarray
    relative_residual: float
    condition_number: float
    stable: bool
    V: float | None
    wall_time: float


def identify_common_denominator(data: IOData, na: int = 2,
                                nb: int = 6) -> CommonDenominatorResult:
    """Least-squares linear HWL ROM with one scalar denominator (module docstring).

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
    CommonDenominatorResult

    Raises
    ------
    DataError
        No ``u`` input, too few samples, or a rank-deficient (non-exciting) regression.

    See Also
    --------
    identify : the nonlinear HWL ROM.
    realize : Σf of the identified model.

    Examples
    --------
    >>> import casflutter as cf
    >>> data = cf.truth_records(cf.load_problem("typical_section"), V0=1.8, dt=0.1,
    ...                         duration=60.0, band=(0.002, 1.0))
    >>> cd = cf.identify_common_denominator(data, na=2, nb=6)
    >>> cd.stable, bool(cd.relative_residual < 1e-6)
    (True, True)
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
        n_w = Wm.shape[1] // (nb + 1)   # columns: the inputs [u; v] at lags 0..nb
        dead = _dead_channels(data, [("u", c % n_w) if c % n_w < N else ("v", 0)
                                     for c in np.flatnonzero(cn == 0)])
        raise DataError(f"non-exciting input: input channel(s) {dead} are identically zero "
                        "in every record; excite each input in some record, or leave it out "
                        "of the inputs (records.displacements/records.flap in a wing file, "
                        "--u/--v)")
    Q, R = np.linalg.qr(Wm / cn)
    sv = np.linalg.svd(R, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf
    if not cond < 1e12:
        raise DataError(f"non-exciting input: the input regression is rank-deficient "
                        f"(condition number {cond:.3g}); " + _rank_hint(
                            data, Wm.shape[0], Wm.shape[1] + na,
                            "widen the chirp band or lower nb"))

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
    return CommonDenominatorResult(model=model, a=np.asarray(a), poles=poles,
                             relative_residual=rel, condition_number=cond,
                             stable=bool(np.all(np.abs(poles) < 1.0)), V=V,
                             wall_time=time.perf_counter() - t0)
