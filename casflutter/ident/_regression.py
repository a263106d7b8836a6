"""Stage 1: over-parameterised linear regression and rank-1 SVD factorisation.

E.-W. Bai, "An optimal two-stage identification algorithm for Hammerstein--Wiener
nonlinear systems", Automatica 34(3), 1998, extended to the MIMO HWL model (eq. 3) as
the paper says (§II.C).  Expanding the Hadamard products of eq. 3, every output ``y_i(k)``
is *linear* in the products

    A^(m)_ij alpha^[l]_ij,   [H,B]^(d)_ij gamma^[l]_ij,   [h,b]^(d)_i beta^[l]_i,

so one least-squares problem (shared regressor matrix, one right-hand side per output)
estimates them.  For each pair (i, j) the estimated products form a matrix
``Theta_ij[lag, l]`` that is rank one in the true model; its best rank-one approximation
(SVD, Frobenius-optimal) gives the linear filter and the polynomial, normalised so that the
polynomial's linear coefficient is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..data import IOData
from ..errors import DataError
from ._model import HWLModel
from ._structure import HWLStructure

__all__ = ["regressor_matrix", "regression_layout", "stage1", "Stage1Result"]


def regression_layout(structure: HWLStructure) -> list[tuple[str, int, int, int]]:
    """Column meaning of the regressor matrix: ``(kind, lag_index, power, channel)``.

    ``kind`` is ``"ar"`` (column holds ``-y_j(k-lag)^l``), ``"u"`` (``u_j(k-lag)^l``),
    ``"v"`` (``v(k-lag)^l``, channel 0) or ``"c"`` (ones: the constant term).
    """
    o, N = structure.orders, structure.n_modes
    cols = [("ar", m, l, j) for m in range(o.na) for l in range(1, o.q + 1) for j in range(N)]
    n_in = len(o.input_lags())
    if structure.has_u:
        cols += [("u", d, l, j) for d in range(n_in) for l in range(1, o.p + 1) for j in range(N)]
    if structure.has_v:
        cols += [("v", d, l, 0) for d in range(n_in) for l in range(1, o.p + 1)]
    if structure.constant:
        cols.append(("c", 0, 0, 0))
    return cols


def regressor_matrix(structure: HWLStructure, data: IOData) -> tuple[np.ndarray, np.ndarray]:
    """Regressor matrix Phi and targets Y over all records (rows k >= max_lag).

    Returns
    -------
    Phi : ndarray, shape (n_rows, n_columns)
        Columns as in :func:`regression_layout`.
    Y : ndarray, shape (n_rows, N)
    """
    o = structure.orders
    L = structure.max_lag
    ar_lags, in_lags = o.ar_lags(), o.input_lags()
    blocks, targets = [], []
    for rec in data.records:
        K = rec.n_samples
        cols = []
        for kind, d, l, j in regression_layout(structure):
            if kind == "ar":
                lag = ar_lags[d]
                cols.append(-rec.y[L - lag:K - lag, j] ** l)
            elif kind == "u":
                lag = in_lags[d]
                cols.append(rec.u[L - lag:K - lag, j] ** l)
            elif kind == "c":
                cols.append(np.ones(K - L))
            else:
                lag = in_lags[d]
                cols.append(rec.v[L - lag:K - lag] ** l)
        blocks.append(np.column_stack(cols))
        targets.append(rec.y[L:])
    return np.vstack(blocks), np.vstack(targets)


def weights_matrix(structure: HWLStructure, W) -> list:
    """The regression coefficients (one column per output) as a list of row blocks, in the
    column order of :func:`regression_layout`; works for numpy and CasADi weights."""
    o = structure.orders
    rows = []
    for m in range(o.na):
        for l in range(o.q):
            rows.append(W["ar"][m][l].T)
    n_in = len(o.input_lags())
    if structure.has_u:
        for d in range(n_in):
            for l in range(o.p):
                rows.append(W["u"][d][l].T)
    if structure.has_v:
        for d in range(n_in):
            for l in range(o.p):
                rows.append(W["v"][d][l])
    if structure.constant:
        rows.append(W["c"])
    return rows


@dataclass(frozen=True)
class Stage1Result:
    """Outcome of stage 1.

    Attributes
    ----------
    model : HWLModel
        Rank-one factorised model (normalised).
    theta_over : ndarray, shape (n_columns, N)
        Least-squares estimate of the over-parameterised products.
    condition_number : float
        2-norm condition number of the column-normalised regressor matrix.
    rank1_residual : float
        Largest relative Frobenius residual of the rank-one approximations (0 for data from
        an HWL model without noise).
    n_rows : int
        Number of regression equations.
    """

    __repr__ = result_repr

    model: HWLModel
    theta_over: np.ndarray
    condition_number: float
    rank1_residual: float
    n_rows: int


def _rank1(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Best rank-one factorisation ``M ~ a c^T`` with ``c[0] = 1``."""
    if M.shape[1] == 1:
        return M[:, 0].copy(), np.ones(1), 0.0
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    norm = np.linalg.norm(M)
    resid = float(np.sqrt(max(np.sum(s[1:] ** 2), 0.0)) / norm) if norm > 0 else 0.0
    v = Vt[0]
    if norm == 0 or abs(v[0]) < 1e-8 * np.linalg.norm(v):
        # no linear part along this path: keep the linear column, drop the polynomial
        c = np.zeros(M.shape[1])
        c[0] = 1.0
        return M[:, 0].copy(), c, resid
    a = s[0] * U[:, 0] * v[0]
    return a, v / v[0], resid


def _dead_channels(data: IOData, kinds_channels) -> list[str]:
    """Names of the channels behind identically zero regressor columns (``(kind, channel)``
    with kind ``"u"``, ``"v"`` or ``"ar"``), in order, each once."""
    names = []
    for kind, j in kinds_channels:
        name = (data.u_names[j] if kind == "u" else data.v_name if kind == "v"
                else data.output_names[j])
        if name not in names:
            names.append(name)
    return names


def _rank_hint(data: IOData, n_rows: int, n_unknowns: int, otherwise: str) -> str:
    """What to do about a rank-deficient regression: a record much shorter than the others
    (named, with its length: it cannot excite the inputs it carries), records that are short
    overall (equations per unknown; then also ``otherwise``), else ``otherwise``."""
    longest = max(data.records, key=lambda r: r.n_samples)
    short = [r for r in data.records if r.n_samples < 0.25 * longest.n_samples]
    if short:
        r = min(short, key=lambda r: r.n_samples)
        return (f"record {r.name!r} has only {r.n_samples} samples ({r.n_samples * data.dt:g} "
                f"s) against {longest.n_samples} in {longest.name!r}: too short to excite the "
                "inputs it carries; record it as long as the others, long enough to sweep "
                "the whole excitation band")
    if n_rows < 10 * n_unknowns:
        return (f"the records are short ({n_rows} equations for {n_unknowns} unknowns per "
                f"output, fewer than 10 per unknown): record longer data; else {otherwise}")
    return otherwise


def stage1(structure: HWLStructure, data: IOData, *, max_condition: float = 1e10) -> Stage1Result:
    """Linear least squares on the over-parameterised regression, then rank-one SVD.

    Raises
    ------
    DataError
        Fewer regression equations than unknowns, or a rank-deficient (non-exciting)
        regression, with its condition number.
    """
    o, N = structure.orders, structure.n_modes
    layout = regression_layout(structure)
    n_rows = sum(r.n_samples - structure.max_lag for r in data.records)
    if n_rows < len(layout):
        raise DataError(f"too few samples: {n_rows} usable samples (after the largest lag "
                        f"{structure.max_lag}) for {len(layout)} regression unknowns per output "
                        f"({structure.n_params} model parameters); record more data or lower "
                        "the orders")
    with np.errstate(over="ignore", invalid="ignore"):
        Phi, Y = regressor_matrix(structure, data)
        col_norm = np.linalg.norm(Phi, axis=0)
    if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(col_norm))):
        raise DataError(f"the regression overflows: the powers up to "
                        f"{max(structure.orders.p, structure.orders.q)} of the signals are not "
                        "finite in double precision; scale the data (scale_data=True) or lower "
                        "the polynomial degrees p, q")
    dead = [layout[c] for c in np.flatnonzero(col_norm == 0)]
    if dead:
        channels = _dead_channels(data, [(kind, j) for kind, _, _, j in dead if kind != "c"])
        raise DataError(f"non-exciting input: channel(s) {channels} never move in the records "
                        f"(regressor column(s) {dead[:4]} are identically zero); excite every "
                        "input in some record, or leave it out of the inputs (--u/--v, "
                        "records.displacements/records.flap in a wing file)")
    Phin = Phi / col_norm
    Q, R = np.linalg.qr(Phin)
    sv = np.linalg.svd(R, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf
    if not cond < max_condition:
        raise DataError(f"non-exciting input: the regression is rank-deficient (condition "
                        f"number {cond:.3g} > {max_condition:.1g}); " + _rank_hint(
                            data, n_rows, len(layout), "use a richer excitation (more "
                            "amplitude levels for the polynomial terms, wider band) or lower "
                            "the orders"))
    theta_over = np.linalg.solve(R, Q.T @ Y) / col_norm[:, None]
    # rank-one factorisation per (i, j)
    index = {key: c for c, key in enumerate(layout)}
    n_in = len(o.input_lags())
    coeffs = {"A": np.zeros((o.na, N, N)), "alpha": np.zeros((o.q, N, N))}
    coeffs["alpha"][0] = 1.0
    worst = 0.0
    for i in range(N):
        for j in range(N):
            if o.na:
                M = np.array([[theta_over[index["ar", m, l, j], i] for l in range(1, o.q + 1)]
                              for m in range(o.na)])
                a, c, res = _rank1(M)
                coeffs["A"][:, i, j], coeffs["alpha"][:, i, j] = a, c
                worst = max(worst, res)
    if structure.has_u:
        HB = np.zeros((n_in, N, N))
        gamma = np.zeros((o.p, N, N))
        for i in range(N):
            for j in range(N):
                M = np.array([[theta_over[index["u", d, l, j], i] for l in range(1, o.p + 1)]
                              for d in range(n_in)])
                a, c, res = _rank1(M)
                HB[:, i, j], gamma[:, i, j] = a, c
                worst = max(worst, res)
        coeffs.update(H=HB[:o.mu], B=HB[o.mu:], gamma=gamma)
    if structure.has_v:
        hb = np.zeros((n_in, N))
        beta = np.zeros((o.p, N))
        for i in range(N):
            M = np.array([[theta_over[index["v", d, l, 0], i] for l in range(1, o.p + 1)]
                          for d in range(n_in)])
            a, c, res = _rank1(M)
            hb[:, i], beta[:, i] = a, c
            worst = max(worst, res)
        coeffs.update(h=hb[:o.mu], b=hb[o.mu:], beta=beta)
    if structure.constant:
        coeffs["c"] = theta_over[index["c", 0, 0, 0], :]
    model = HWLModel(structure, structure.pack(coeffs), data.dt)
    return Stage1Result(model, theta_over, cond, worst, n_rows)
