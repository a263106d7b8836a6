"""The parameterisation of the MIMO Hammerstein--Wiener-like (HWL) model (paper eq. 1--4):
its coefficient blocks, their packing into one parameter vector and the terms of eq. 3.

Index conventions (against eq. 3)
---------------------------------
For output ``i = 1..N`` (code: ``i = 0..N-1``)::

    y_i(k) = - sum_j sum_{m=1}^{na} A[m-1,i,j] * sum_{l=1}^{q} alpha[l-1,i,j] * y_j(k-mu-m+1)^l
             + sum_j sum_{d=0}^{mu-1} H[d,i,j] * sum_{l=1}^{p} gamma[l-1,i,j] * u_j(k-r-d)^l
             +       sum_{d=0}^{mu-1} h[d,i]   * sum_{l=1}^{p} beta[l-1,i]    * v(k-r-d)^l
             + sum_j sum_{d=0}^{nb}   B[d,i,j] * sum_{l=1}^{p} gamma[l-1,i,j] * u_j(k-r-mu-d)^l
             +       sum_{d=0}^{nb}   b[d,i]   * sum_{l=1}^{p} beta[l-1,i]    * v(k-r-mu-d)^l

so ``A[m-1] = A^(m)`` (m = 1..na), ``H[d] = H^(d)`` (d = 0..mu-1), ``B[d] = B^(d)``
(d = 0..nb), ``alpha[l-1] = alpha^[l]`` and so on.

*The typo in eq. 2.*  The paper prints ``A_ij(z^-1) = A^(1) z^-1 + ... + A^(na) z^(-mu+1)``
(and the same last exponent for ``B_ij``).  The last exponent must be ``z^-na`` (``z^-nb``
for ``B``): the coefficient index and the power of ``z^-1`` run together, and only then does the
prefactor ``z^(-mu+1)`` in eq. 2 give the output lags ``mu, ..., mu+na-1`` of the scalar
mu-Markov model eq. 1 (``y(k-mu+1-j)``, ``j = 1..na``), whose first ``mu`` impulse-response
samples are exactly the Markov parameters ``H``.  With ``z^(-mu+1)`` the degree of ``A_ij``
would not depend on ``na`` at all and the model would not reduce to eq. 1 for ``N = 1``.

*Normalisation.*  Each product ``A_ij(z)·alpha_ij``, ``[H_ij, B_ij](z)·gamma_ij`` and
``[h_i, b_i](z)·beta_i`` is bilinear, hence defined only up to a scale factor.  We fix
``alpha^[1] = gamma^[1] = beta^[1] = 1`` (the linear coefficient of every polynomial is one).
Then the linearisation about zero keeps exactly the mu-Markov system ``{A, H, h, B, b}``
(paper §III.A.1) and the higher polynomial coefficients measure the nonlinearity directly.
The normalisation needs a non-zero linear part; a purely nonlinear path cannot be represented.

The same formulas are evaluated by numpy and by CasADi (the twins in :mod:`._twins`): one
code path, so they agree to rounding.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import DimensionError, OrderError
from ._orders import HWLOrders

__all__ = ["HWLStructure", "paper_parameter_count"]


def paper_parameter_count(n_modes: int, orders: HWLOrders) -> int:
    """Parameter count printed in §II.C: ``N²(na+2mu+2(nb+1)) + 2N·mu + N²(q+2p)``.

    It counts more than the model has (eq. 3 has ``N²(na+mu+nb+1+q+p) + N(mu+nb+1+p)``
    coefficients, before normalisation): see :attr:`HWLStructure.n_coefficients`.
    """
    o = orders
    N = n_modes
    return N * N * (o.na + 2 * o.mu + 2 * (o.nb + 1)) + 2 * N * o.mu + N * N * (o.q + 2 * o.p)


@dataclass(frozen=True)
class HWLStructure:
    """Dimensions of an HWL model: orders, number of modes, which inputs exist.

    Knows how the free parameters are stacked into one vector ``theta`` (what the NLP
    optimises) and unpacks it into coefficient blocks for numpy or CasADi alike.

    Parameters
    ----------
    orders : HWLOrders
        ``(mu, na, nb, r, p, q)``.
    n_modes : int
        ``N``: number of outputs y (generalised forces) and, when present, of inputs u.
    has_u, has_v : bool
        Whether the modal-displacement input u and the flap input v exist.
    constant : bool
        Whether eq. 3 carries a constant term ``c`` (N values added to ``y(k)``); the
        paper's model has none.  Used for data with offsets (``identify(..., offset=True)``).
    """

    orders: HWLOrders
    n_modes: int
    has_u: bool = True
    has_v: bool = True
    constant: bool = False

    def __post_init__(self):
        object.__setattr__(self, "orders", HWLOrders.from_tuple(self.orders))
        if not isinstance(self.n_modes, (int, np.integer)) or self.n_modes < 1:
            raise OrderError(f"n_modes={self.n_modes!r} must be a positive integer")
        if not (self.has_u or self.has_v):
            raise OrderError("an HWL model needs at least one input: u (modal displacements) "
                             "or v (flap deflection)")

    # -- layout of theta ------------------------------------------------------------
    def blocks(self) -> list[tuple[str, tuple[int, ...]]]:
        """``(name, shape)`` of the free-parameter blocks, in the order they sit in theta."""
        o, N = self.orders, self.n_modes
        out: list[tuple[str, tuple[int, ...]]] = [("A", (o.na, N, N))]
        if self.has_u:
            out += [("H", (o.mu, N, N)), ("B", (o.nb + 1, N, N))]
        if self.has_v:
            out += [("h", (o.mu, N)), ("b", (o.nb + 1, N))]
        out.append(("alpha", (o.q - 1, N, N)))
        if self.has_u:
            out.append(("gamma", (o.p - 1, N, N)))
        if self.has_v:
            out.append(("beta", (o.p - 1, N)))
        if self.constant:
            out.append(("c", (1, N)))
        return out

    def index_map(self) -> dict[str, np.ndarray]:
        """Position in theta of every free coefficient, shaped like its block
        (``A[m, i, j]``, ``h[d, i]``, ``alpha[l-2, i, j]``, ``c[0, i]``, ...)."""
        out, pos = {}, 0
        for name, shape in self.blocks():
            size = int(np.prod(shape))
            if len(shape) == 3:
                # column-major within each (i, j) matrix, as in pack()
                idx = np.arange(size).reshape(shape[0], shape[2], shape[1]).transpose(0, 2, 1)
            else:
                idx = np.arange(size).reshape(shape)
            out[name] = idx + pos
            pos += size
        return out

    @property
    def n_params(self) -> int:
        """Number of free parameters after the normalisation ``alpha^[1]=gamma^[1]=beta^[1]=1``."""
        return int(sum(np.prod(shape) for _, shape in self.blocks()))

    @property
    def n_coefficients(self) -> int:
        """Number of coefficients in eq. 3 before normalisation."""
        o, N = self.orders, self.n_modes
        n = N * N * (o.na + o.q)
        if self.has_u:
            n += N * N * (o.mu + o.nb + 1 + o.p)
        if self.has_v:
            n += N * (o.mu + o.nb + 1 + o.p)
        return n + (N if self.constant else 0)

    @property
    def max_lag(self) -> int:
        """Largest delay in eq. 3, in samples."""
        return self.orders.max_lag

    def pack(self, coefficients: dict[str, np.ndarray]) -> np.ndarray:
        """Stack coefficient arrays (with the normalised leading polynomial coefficient)
        into the free-parameter vector theta."""
        parts = []
        for name, shape in self.blocks():
            arr = np.asarray(coefficients[name], dtype=float)
            if name in ("alpha", "gamma", "beta"):
                arr = arr[1:]
            if name == "c":
                arr = arr.reshape(1, -1)
            if arr.shape != shape:
                raise DimensionError(f"coefficient {name} has shape {arr.shape}, expected {shape}")
            # column-major within each (i, j) matrix so that numpy and CasADi agree
            parts.append(np.concatenate([np.ravel(a, order="F") for a in arr]) if arr.size else
                         np.zeros(0))
        return np.concatenate(parts) if parts else np.zeros(0)

    def unpack(self, theta) -> dict[str, list]:
        """Split theta into lists of matrices (numpy arrays or CasADi expressions).

        Vector-valued blocks (``h``, ``b``, ``beta``) become ``1 x N`` rows; the polynomial
        lists ``alpha``, ``gamma``, ``beta`` include the fixed leading coefficient 1.
        """
        is_ca = isinstance(theta, (ca.MX, ca.SX, ca.DM))
        N = self.n_modes
        out: dict[str, list] = {}
        pos = 0
        for name, shape in self.blocks():
            mats = []
            size = int(np.prod(shape[1:]))
            for _ in range(shape[0]):
                chunk = theta[pos:pos + size]
                pos += size
                if len(shape) == 3:
                    mats.append(ca.reshape(chunk, N, N) if is_ca
                                else np.reshape(chunk, (N, N), order="F"))
                else:
                    mats.append(ca.reshape(chunk, 1, N) if is_ca else np.reshape(chunk, (1, N)))
            out[name] = mats
        ones_sq = np.ones((N, N))
        ones_row = np.ones((1, N))
        out["alpha"] = [ones_sq] + out["alpha"]
        if self.has_u:
            out["gamma"] = [ones_sq] + out["gamma"]
        if self.has_v:
            out["beta"] = [ones_row] + out["beta"]
        return out

    def weights(self, theta) -> dict[str, list[list]]:
        """Products ``W[lag][l]`` of linear coefficients and polynomial coefficients.

        ``"ar"``: ``A^(m) ∘ alpha^[l]``; ``"u"``: ``[H,B]^(d) ∘ gamma^[l]``;
        ``"v"``: ``[h,b]^(d) ∘ beta^[l]`` (Hadamard products, eq. 2).  These are the entries of
        the over-parameterised linear regression of stage 1.
        """
        c = self.unpack(theta)
        W: dict[str, list[list]] = {"ar": [[a * al for al in c["alpha"]] for a in c["A"]]}
        if self.has_u:
            W["u"] = [[hb * g for g in c["gamma"]] for hb in c["H"] + c["B"]]
        if self.has_v:
            W["v"] = [[hb * be for be in c["beta"]] for hb in c["h"] + c["b"]]
        if self.constant:
            W["c"] = c["c"][0]
        return W


def _input_part(structure: HWLStructure, W, u, v, n_samples: int):
    """Sum of the input terms of eq. 3 for k = L..K-1 (rows), numpy or CasADi alike."""
    L = structure.max_lag
    K = n_samples
    lags = structure.orders.input_lags()
    total = 0
    if structure.has_u:
        for d, lag in enumerate(lags):
            block = u[L - lag:K - lag, :]
            for l, w in enumerate(W["u"][d], start=1):
                total = total + (block ** l) @ w.T
    if structure.has_v:
        for d, lag in enumerate(lags):
            block = v[L - lag:K - lag, :]
            for l, w in enumerate(W["v"][d], start=1):
                total = total + (block ** l) @ w
    if structure.constant:
        c = W["c"]
        if isinstance(c, (ca.MX, ca.SX, ca.DM)):
            total = total + ca.repmat(c, K - L, 1)
        else:
            total = total + np.broadcast_to(c, (K - L, structure.n_modes))
    return total


def ar_weight_array(structure: HWLStructure, W) -> np.ndarray:
    """The autoregressive weights ``A^(m) ∘ alpha^[l]`` as one array ``(na, q, N, N)``
    (numpy weights only), the form the compiled recursion takes."""
    o, N = structure.orders, structure.n_modes
    out = np.zeros((o.na, o.q, N, N))
    for m in range(o.na):
        for l in range(o.q):
            out[m, l] = W["ar"][m][l]
    return out


def _ar_part(structure: HWLStructure, W, y, n_samples: int):
    """Autoregressive terms of eq. 3 (without the minus sign) for k = L..K-1."""
    L = structure.max_lag
    K = n_samples
    total = 0
    for m, lag in enumerate(structure.orders.ar_lags()):
        block = y[L - lag:K - lag, :]
        for l, w in enumerate(W["ar"][m], start=1):
            total = total + (block ** l) @ w.T
    return total
