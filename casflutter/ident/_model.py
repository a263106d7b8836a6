"""The MIMO Hammerstein--Wiener-like (HWL) model with mu-Markov structure (paper eq. 1--4).

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

import warnings
from dataclasses import dataclass, field, replace
from math import comb
from typing import Any

import casadi as ca
import numpy as np

from .._format import result_repr
from ..errors import DataError, DimensionError, OrderError
from ._kernels import free_run
from ._orders import HWLOrders

__all__ = ["HWLStructure", "HWLModel", "paper_parameter_count", "UnstableModelWarning"]


#: |y| above which a free run counts as diverged (its square still fits in a double)
_DIVERGED = 1e100


class UnstableModelWarning(UserWarning):
    """A free-run simulation of an HWL model diverged (the model is unstable for that input)."""


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


@dataclass(frozen=True)
class HWLModel:
    """An identified (or prescribed) HWL ROM of the aerodynamic response, eq. 4.

    Attributes
    ----------
    structure : HWLStructure
        Orders, N and which inputs exist.
    theta : ndarray
        Free parameters (see :meth:`HWLStructure.blocks`).
    dt : float
        Sampling time in seconds.
    output_names, u_names : tuple of str
        Channel names of y and u.
    v_name : str
        Name of the flap input.
    """

    __repr__ = result_repr

    structure: HWLStructure
    theta: np.ndarray
    dt: float = 1.0
    output_names: tuple[str, ...] = ()
    u_names: tuple[str, ...] = ()
    v_name: str = "v"
    _weights: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        theta = np.asarray(self.theta, dtype=float).ravel()
        if theta.size != self.structure.n_params:
            raise DimensionError(f"theta has {theta.size} entries, the structure "
                                 f"{self.structure.orders} with N={self.structure.n_modes} "
                                 f"needs {self.structure.n_params}")
        if not np.all(np.isfinite(theta)):
            raise DataError("HWL parameters contain NaN or inf")
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise DataError(f"sampling time dt={self.dt} must be positive")
        object.__setattr__(self, "theta", theta)
        N = self.structure.n_modes
        if not self.output_names:
            object.__setattr__(self, "output_names", tuple(f"y{i + 1}" for i in range(N)))
        if not self.u_names and self.structure.has_u:
            object.__setattr__(self, "u_names", tuple(f"u{i + 1}" for i in range(N)))
        object.__setattr__(self, "_weights", self.structure.weights(theta))

    # -- construction ---------------------------------------------------------------
    @classmethod
    def from_coefficients(cls, orders, *, A, alpha, H=None, B=None, gamma=None, h=None, b=None,
                          beta=None, c=None, dt: float = 1.0, **names) -> "HWLModel":
        """Build from coefficient arrays with the paper's names (shapes in the module doc).

        The polynomial arrays ``alpha``, ``gamma``, ``beta`` include their leading
        coefficient, which must be 1 (the normalisation).  ``c`` (N,) is the optional
        constant term.

        Parameters
        ----------
        orders : tuple or HWLOrders
            ``(mu, na, nb, r, p, q)``.
        A : array_like, shape (na, N, N)
            Autoregressive matrices ``A^(m)``.
        alpha : array_like, shape (q, N, N)
            Output polynomial ``alpha`` (leading coefficient 1).
        H, B : array_like, optional
            Modal-input Markov and lag matrices ``H (mu, N, N)``, ``B (nb+1, N, N)`` (with ``u``).
        gamma : array_like, optional
            Modal-input polynomial ``gamma (p, N, N)`` (with ``u``).
        h, b : array_like, optional
            Flap-input Markov and lag vectors ``h (mu, N)``, ``b (nb+1, N)`` (with ``v``).
        beta : array_like, optional
            Flap-input polynomial ``beta (p, N)`` (with ``v``).
        c : array_like, shape (N,), optional
            Constant term.
        dt : float
            Sampling time [s].
        **names
            ``output_names``, ``u_names``, ``v_name``.

        Returns
        -------
        HWLModel

        Raises
        ------
        DataError
            A polynomial whose leading coefficient is not 1.
        """
        A = np.asarray(A, dtype=float)
        N = A.shape[-1] if A.ndim == 3 and A.shape[0] else np.asarray(alpha).shape[-1]
        has_u, has_v = H is not None, h is not None
        structure = HWLStructure(HWLOrders.from_tuple(orders), N, has_u, has_v, c is not None)
        coeffs = {"A": A.reshape(structure.orders.na, N, N), "alpha": alpha}
        if has_u:
            coeffs.update(H=H, B=B, gamma=gamma)
        if has_v:
            coeffs.update(h=h, b=b, beta=beta)
        if c is not None:
            coeffs["c"] = np.asarray(c, dtype=float).reshape(N)
        for name in ("alpha", "gamma", "beta"):
            if name in coeffs and not np.allclose(np.asarray(coeffs[name])[0], 1.0):
                raise DataError(f"{name}[0] (the linear coefficient {name}^[1]) must be 1: "
                                "rescale the polynomial and its linear filter (see the "
                                "normalisation in casflutter.ident)")
        return cls(structure, structure.pack(coeffs), dt, **names)

    def coefficients(self) -> dict[str, np.ndarray]:
        """Coefficient arrays with the paper's names: ``A (na,N,N)``, ``H (mu,N,N)``,
        ``B (nb+1,N,N)``, ``h (mu,N)``, ``b (nb+1,N)``, ``alpha (q,N,N)``, ``gamma (p,N,N)``,
        ``beta (p,N)`` (the polynomial arrays include the leading 1), and ``c (N,)`` when
        the model has a constant term.

        Returns
        -------
        dict of str to ndarray
            The arrays by name.
        """
        c = self.structure.unpack(self.theta)
        out = {}
        for name, mats in c.items():
            arr = np.array([np.asarray(m, dtype=float) for m in mats])
            if name in ("h", "b", "beta"):
                arr = arr.reshape(len(mats), -1)
            out[name] = arr
        N = self.n_modes
        out["A"] = out["A"].reshape(self.orders.na, N, N)
        if "c" in out:
            out["c"] = out["c"].reshape(N)
        return out

    def with_theta(self, theta) -> "HWLModel":
        """The same structure with new parameters.

        Parameters
        ----------
        theta : array_like
            Free parameters in the order of :meth:`HWLStructure.blocks`.

        Returns
        -------
        HWLModel
        """
        return replace(self, theta=np.asarray(theta, dtype=float), _weights=None)

    # -- properties -----------------------------------------------------------------
    @property
    def orders(self) -> HWLOrders:
        return self.structure.orders

    @property
    def n_modes(self) -> int:
        return self.structure.n_modes

    @property
    def has_u(self) -> bool:
        return self.structure.has_u

    @property
    def has_v(self) -> bool:
        return self.structure.has_v

    @property
    def max_lag(self) -> int:
        return self.structure.max_lag

    @property
    def n_params(self) -> int:
        return self.structure.n_params

    # -- evaluation -------------------------------------------------------------------
    def _arrays(self, u, v, y, n_samples=None):
        N = self.n_modes
        if u is not None and v is None and self.has_v and not self.has_u:
            u, v = None, u   # a flap-only model: the one input given is v
        K = None
        for arr in (y, u, v):
            if arr is not None:
                K = np.asarray(arr).shape[0]
                break
        if K is None:
            K = n_samples
        if K is None:
            raise DataError("give at least one signal (or n_samples)")
        def as2d(x, cols, name):
            if x is None:
                return None
            x = np.asarray(x, dtype=float)
            x = x.reshape(-1, 1) if x.ndim == 1 else x
            if x.shape != (K, cols):
                raise DimensionError(f"{name} has shape {x.shape}, expected ({K}, {cols})")
            return x
        u = as2d(u, N, "u") if self.has_u else None
        v = as2d(v, 1, "v") if self.has_v else None
        if self.has_u and u is None:
            raise DataError("this model has a modal-displacement input u: pass u=")
        if self.has_v and v is None:
            raise DataError("this model has a flap input v: pass v=")
        y = as2d(y, N, "y")
        if K <= self.max_lag:
            raise DataError(f"{K} samples are not more than the model's largest lag "
                            f"{self.max_lag}")
        return u, v, y, K

    def predict(self, y, u=None, v=None) -> np.ndarray:
        """mu-step-ahead prediction: eq. 3 evaluated with the *measured* past outputs.

        Since the autoregressive terms start at lag ``mu``, ``y(k)`` is predicted from data up
        to ``k - mu`` (and inputs up to ``k - r``).

        Parameters
        ----------
        y : array_like, shape (K, N)
            Measured outputs.
        u : array_like, shape (K, N), optional
            Modal inputs (when the model has them).
        v : array_like, shape (K,), optional
            Flap input (when the model has it).

        Returns
        -------
        ndarray, shape (K, N)
            Predictions; the first ``max_lag`` rows (no prediction possible) are copied from ``y``.
        """
        u, v, y, K = self._arrays(u, v, y)
        L = self.max_lag
        out = np.array(y, dtype=float)
        out[L:] = _input_part(self.structure, self._weights, u, v, K) - (
            _ar_part(self.structure, self._weights, y, K) if self.orders.na else 0)
        return out

    def simulate(self, u=None, v=None, y0=None, n_samples: int | None = None) -> np.ndarray:
        """Free-run simulation of eq. 3 (the model's own past outputs fed back).

        Parameters
        ----------
        u : array (K, N), optional
            Modal displacements.  For a model whose only input is the flap, the first
            positional argument is taken as ``v`` (``model.simulate(v)``).
        v : array (K,), optional
            Flap deflection (for a model with the flap input).
        y0 : array (K0 >= max_lag, N), optional
            Initial outputs for the first ``max_lag`` samples (zeros when omitted).
        n_samples : int, optional
            Length when the model is driven by no signal at all (not needed otherwise).

        Returns
        -------
        ndarray, shape (K, N)
            When the model diverges (unstable free run: an output above ``1e100`` in magnitude
            or not finite) the samples from the divergence on are NaN and one
            :class:`UnstableModelWarning` names the sample.
        """
        u, v, _, K = self._arrays(u, v, None, n_samples)
        N, L = self.n_modes, self.max_lag
        y = np.zeros((K, N))
        if y0 is not None:
            y0 = np.asarray(y0, dtype=float).reshape(-1, N)
            if y0.shape[0] < L:
                raise DataError(f"y0 needs at least max_lag={L} rows, got {y0.shape[0]}")
            y[:L] = y0[:L]
        xin = np.ascontiguousarray(_input_part(self.structure, self._weights, u, v, K),
                                   dtype=float)
        lags = self.orders.ar_lags()
        if not lags:
            y[L:] = xin
            return y
        H = max(lags)
        ybuf, _, diverged = free_run(xin, ar_weight_array(self.structure, self._weights),
                                     np.asarray(lags, dtype=np.int64),
                                     np.ascontiguousarray(y[L - H:L]), np.zeros((1, N)), 0,
                                     _DIVERGED)
        y[L:] = ybuf[H:]
        if diverged >= 0:
            warnings.warn(f"the HWL model is unstable in free run: its output diverges at sample "
                          f"{L + diverged} of {K} (the rest is NaN); check its orders or "
                          "identify it with criterion='simulation'", UnstableModelWarning,
                          stacklevel=2)
        return y

    def step(self, y_hist, u_hist=None, v_hist=None) -> np.ndarray:
        """One output sample ``y(k)`` of eq. 3, for coupling with a structure model.

        Each history has ``max_lag + 1`` rows, row ``d`` holding the value at time ``k - d``
        (row 0 = time k; ``y_hist[0]`` is ignored).  ``v_hist`` has shape ``(max_lag + 1,)``.

        Parameters
        ----------
        y_hist : array_like, shape (max_lag + 1, N)
            Past outputs (row ``d`` at time ``k - d``).
        u_hist : array_like, shape (max_lag + 1, N), optional
            Past and present modal inputs.
        v_hist : array_like, shape (max_lag + 1,), optional
            Past and present flap inputs.

        Returns
        -------
        ndarray, shape (N,)
            ``y(k)``.
        """
        L = self.max_lag
        y_hist = np.asarray(y_hist, dtype=float).reshape(L + 1, self.n_modes)
        # reversed histories are chronological: row L is time k
        u = None if u_hist is None else np.asarray(u_hist, dtype=float).reshape(L + 1, -1)[::-1]
        v = None if v_hist is None else np.asarray(v_hist, dtype=float).reshape(L + 1, 1)[::-1]
        u, v, y, K = self._arrays(u, v, y_hist[::-1])
        val = _input_part(self.structure, self._weights, u, v, K)
        if self.orders.na:
            val = val - _ar_part(self.structure, self._weights, y, K)
        return np.asarray(val).ravel()

    # -- linear part ------------------------------------------------------------------
    def markov_parameters(self, n: int) -> np.ndarray:
        """Impulse response ``G[k]`` (k = 0..n-1), shape ``(n, N, n_inputs)``, of the
        linearisation about zero: the mu-Markov system ``{A, H, h, B, b}`` (paper §III.A.1).

        Inputs are ordered ``[u_1..u_N, v]`` (whichever exist).  ``G[r + d] = [H^(d), h^(d)]``
        for ``d < mu``: the Markov parameters are the model's own coefficients.

        Parameters
        ----------
        n : int
            Number of samples of the impulse response.

        Returns
        -------
        ndarray, shape (n, N, n_inputs)
        """
        c = self.coefficients()
        N = self.n_modes
        cols = []
        if self.has_u:
            cols.append(np.concatenate([c["H"], c["B"]], axis=0))
        if self.has_v:
            cols.append(np.concatenate([c["h"], c["b"]], axis=0)[:, :, None])
        num = np.concatenate(cols, axis=2)  # (mu+nb+1, N, m)
        m = num.shape[2]
        G = np.zeros((n, N, m))
        in_lags = self.orders.input_lags()
        ar_lags = self.orders.ar_lags()
        for k in range(n):
            acc = np.zeros((N, m))
            for d, lag in enumerate(in_lags):
                if lag == k:
                    acc += num[d]
            for mm, lag in enumerate(ar_lags):
                if k - lag >= 0:
                    acc -= c["A"][mm] @ G[k - lag]
            G[k] = acc
        return G

    def linear_model(self) -> "HWLModel":
        """The linearisation about zero as an HWL model with p = q = 1.

        Returns
        -------
        HWLModel
            ``{A, H, h, B, b}`` of this model with the polynomials reduced to their linear terms.
        """
        o = self.orders
        c = self.coefficients()
        lin = HWLOrders(o.mu, o.na, o.nb, o.r, 1, 1)
        kw = {"A": c["A"], "alpha": c["alpha"][:1]}
        if self.has_u:
            kw.update(H=c["H"], B=c["B"], gamma=c["gamma"][:1])
        if self.has_v:
            kw.update(h=c["h"], b=c["b"], beta=c["beta"][:1])
        if "c" in c:
            kw["c"] = c["c"]
        return HWLModel.from_coefficients(lin, dt=self.dt, output_names=self.output_names,
                                          u_names=self.u_names, v_name=self.v_name, **kw)

    def rescaled(self, y_scale, u_scale=None, v_scale=None) -> "HWLModel":
        """The same input--output map expressed in scaled signals
        ``y~ = y / y_scale``, ``u~ = u / u_scale``, ``v~ = v / v_scale``.

        The HWL class is closed under this change of units: with the normalisation
        ``alpha^[1] = 1``, ``A~_ij = A_ij s_yj / s_yi`` and ``alpha~^[l]_ij = alpha^[l]_ij
        s_yj^(l-1)`` (likewise for gamma, beta).  Used to identify on unit-RMS data.

        Parameters
        ----------
        y_scale : array_like, shape (N,)
            Output scales.
        u_scale : array_like, shape (N,), optional
            Modal-input scales.
        v_scale : float, optional
            Flap-input scale.

        Returns
        -------
        HWLModel
        """
        N = self.n_modes
        sy = np.broadcast_to(np.asarray(y_scale, float), (N,))
        su = np.broadcast_to(np.asarray(1.0 if u_scale is None else u_scale, float), (N,))
        sv = float(1.0 if v_scale is None else v_scale)
        c = self.coefficients()
        ratio_y = sy[None, :] / sy[:, None]           # s_yj / s_yi
        new = {"A": c["A"] * ratio_y,
               "alpha": c["alpha"] * np.array([sy[None, :] ** l for l in range(self.orders.q)])}
        if self.has_u:
            ratio_u = su[None, :] / sy[:, None]
            new["H"] = c["H"] * ratio_u
            new["B"] = c["B"] * ratio_u
            new["gamma"] = c["gamma"] * np.array([np.broadcast_to(su[None, :] ** l, (N, N))
                                                  for l in range(self.orders.p)])
        if self.has_v:
            new["h"] = c["h"] * sv / sy[None, :]
            new["b"] = c["b"] * sv / sy[None, :]
            new["beta"] = c["beta"] * np.array([[sv ** l] * N for l in range(self.orders.p)])
        if self.structure.constant:
            new["c"] = c["c"] / sy
        return replace(self, theta=self.structure.pack(new), _weights=None)

    def shifted(self, y_shift, u_shift=None, v_shift=None) -> "HWLModel":
        """The same input--output map expressed in shifted signals ``y' = y - y_shift``,
        ``u' = u - u_shift``, ``v' = v - v_shift``.

        Each polynomial of eq. 3 is re-expanded about the shift (binomial theorem) and
        renormalised so that its linear coefficient stays 1; the constants collect in the
        constant term ``c``, which the result always has.  A model identified on centred
        data is returned to raw units by ``shifted(-mean_y, -mean_u, -mean_v)``.

        Parameters
        ----------
        y_shift : array_like, shape (N,)
            Output shift.
        u_shift : array_like, shape (N,), optional
            Modal-input shift.
        v_shift : float, optional
            Flap-input shift.


        Returns
        -------
        HWLModel
            With a constant term.

        Raises
        ------
        DataError
            When a polynomial's slope vanishes at the shift (the normalisation cannot hold).
        """
        N = self.n_modes
        sy = np.broadcast_to(np.asarray(y_shift, float), (N,))
        su = np.broadcast_to(np.asarray(0.0 if u_shift is None else u_shift, float), (N,))
        sv = float(0.0 if v_shift is None else v_shift)
        c = self.coefficients()

        def expand(coef, shift, what):
            # coef (deg, ...) for powers 1..deg; returns e0 and the renormalised polynomial
            deg = coef.shape[0]
            e = np.zeros((deg + 1,) + coef.shape[1:])
            for lp in range(1, deg + 1):
                for l in range(0, lp + 1):
                    e[l] = e[l] + coef[lp - 1] * comb(lp, l) * shift ** (lp - l)
            if np.any(e[1] == 0):
                raise DataError(f"the {what} polynomial has zero slope at the shift: the model "
                                "cannot be normalised (alpha^[1] = 1) in the shifted signals")
            return e[0], e[1], e[1:] / e[1]

        const = -sy + (c["c"] if "c" in c else 0.0)
        e0, e1, alpha = expand(c["alpha"], sy[None, :], "alpha")
        new = {"A": c["A"] * e1, "alpha": alpha}
        const = const - np.einsum("mij,ij->i", c["A"], e0)
        if self.has_u:
            e0, e1, gamma = expand(c["gamma"], su[None, :], "gamma")
            new.update(H=c["H"] * e1, B=c["B"] * e1, gamma=gamma)
            const = const + np.einsum("dij,ij->i", np.concatenate([c["H"], c["B"]]), e0)
        if self.has_v:
            e0, e1, beta = expand(c["beta"], sv, "beta")
            new.update(h=c["h"] * e1, b=c["b"] * e1, beta=beta)
            const = const + np.concatenate([c["h"], c["b"]]).sum(axis=0) * e0
        new["c"] = const
        structure = replace(self.structure, constant=True)
        return replace(self, structure=structure, theta=structure.pack(new), _weights=None)

    # -- persistence ------------------------------------------------------------------
    def save(self, path) -> None:
        """Write the model to an ``.npz`` file (orders, N, inputs, theta, dt, names).

        Parameters
        ----------
        path : str or path
            The ``.npz`` file to write.
        """
        s = self.structure
        np.savez(path, format=np.array("casflutter.HWLModel/1"),
                 orders=np.array(s.orders.as_tuple()), n_modes=np.array(s.n_modes),
                 has_u=np.array(s.has_u), has_v=np.array(s.has_v),
                 constant=np.array(s.constant), theta=self.theta,
                 dt=np.array(self.dt), output_names=np.array(self.output_names),
                 u_names=np.array(self.u_names), v_name=np.array(self.v_name))

    @classmethod
    def load(cls, path) -> "HWLModel":
        """Read a model written by :meth:`save`.

        Parameters
        ----------
        path : str or path
            The ``.npz`` file.

        Returns
        -------
        HWLModel
        """
        with np.load(path, allow_pickle=False) as z:
            if "format" not in z.files or not str(z["format"]).startswith("casflutter.HWLModel"):
                raise DataError(f"{path} is not a casflutter HWL model file")
            structure = HWLStructure(HWLOrders.from_tuple(tuple(int(x) for x in z["orders"])),
                                     int(z["n_modes"]), bool(z["has_u"]), bool(z["has_v"]),
                                     bool(z["constant"]) if "constant" in z.files else False)
            return cls(structure, z["theta"], float(z["dt"]),
                       tuple(str(x) for x in z["output_names"]),
                       tuple(str(x) for x in z["u_names"]), str(z["v_name"]))

    def __str__(self) -> str:
        s = self.structure
        ins = [n for n, ok in (("u", s.has_u), ("v", s.has_v)) if ok]
        const = ", constant term" if s.constant else ""
        return (f"HWLModel(N={s.n_modes}, {s.orders}, inputs {'+'.join(ins)}{const}, "
                f"{s.n_params} parameters, dt={self.dt:g} s)")
