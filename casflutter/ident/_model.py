"""The MIMO Hammerstein--Wiener-like (HWL) model with mu-Markov structure (paper eq. 1--4).

:class:`HWLModel` holds the parameters of an :class:`~._structure.HWLStructure` (its index
conventions against eq. 3, the typo of eq. 2 and the normalisation are in
:mod:`._structure`) and evaluates eq. 3-4: one-step prediction, free-run simulation, the
step of a loop, Markov parameters, the linear part, exact rescaling and shifting of the
channels, and the ``.npz`` file.

The same formulas are evaluated by numpy and by CasADi (the twins in :mod:`._twins`): one
code path, so they agree to rounding.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from math import comb
from typing import Any

import numpy as np

from .._format import result_repr
from ..errors import DataError, DimensionError, OrderError
from ._kernels import free_run
from ._orders import HWLOrders
from ._structure import HWLStructure, _ar_part, _input_part, ar_weight_array

__all__ = ["HWLModel", "UnstableModelWarning"]


#: |y| above which a free run counts as diverged (its square still fits in a double)
_DIVERGED = 1e100


class UnstableModelWarning(UserWarning):
    """A free-run simulation of an HWL model diverged (the model is unstable for that input)."""


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
    _step_op: Any = field(default=None, repr=False, compare=False)

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
        object.__setattr__(self, "_step_op", None)      # built by the first step()

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
        L, N = self.max_lag, self.n_modes
        if u_hist is not None and v_hist is None and self.has_v and not self.has_u:
            u_hist, v_hist = None, u_hist   # a flap-only model: the one input given is v
        if self.has_u and u_hist is None:
            raise DataError("this model has a modal-displacement input u: pass u_hist=")
        if self.has_v and v_hist is None:
            raise DataError("this model has a flap input v: pass v_hist=")
        if self._step_op is None:
            object.__setattr__(self, "_step_op", _StepOperator.of(self))
        op = self._step_op
        y_hist = np.asarray(y_hist, dtype=float).reshape(L + 1, N)
        parts = [] if op.ar_lags is None else [y_hist[op.ar_lags] ** op.ar_powers]
        if op.u_lags is not None:
            u = np.asarray(u_hist, dtype=float).reshape(L + 1, N)
            parts.append(u[op.u_lags] ** op.u_powers)
        if op.v_lags is not None:
            v = np.asarray(v_hist, dtype=float).reshape(L + 1)
            parts.append(v[op.v_lags] ** op.v_powers)
        return op.weights @ np.concatenate([x.ravel() for x in parts]) + op.constant

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

    def advanced(self, samples: int) -> "HWLModel":
        """The same coefficients with the input delay ``r`` lowered by ``samples``.

        Records whose forces lag the motion by a known number of samples (a loosely coupled
        CFD time march computes the flow of step ``k`` on the grid of step ``k - 1``:
        :attr:`casflutter.truth.RecordSettings.coupling_delay`) give a model whose ``r``
        holds that lag.  It belongs to the records, not to the flow: the model of the
        aerodynamics alone is the identified one with its inputs ``samples`` steps earlier,
        ``z^{-(r - samples)}`` in place of ``z^{-r}`` in eq. 2.

        Parameters
        ----------
        samples : int
            From 0 to ``r``.

        Returns
        -------
        HWLModel

        Raises
        ------
        OrderError
            ``samples`` negative or larger than the model's ``r``.
        """
        o = self.orders
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not (
                0 <= samples <= o.r):
            raise OrderError(f"samples = {samples!r}: the model's input delay is r = {o.r}; "
                             f"advance it by an integer from 0 to {o.r}")
        orders = replace(o, r=o.r - int(samples))
        return replace(self, structure=replace(self.structure, orders=orders), _weights=None)

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


@dataclass(frozen=True)
class _StepOperator:
    """Eq. 3 at one sample as one product: ``y(k) = weights @ phi + constant``, where
    ``phi`` gathers the powers ``1..q`` of the lagged outputs and ``1..p`` of the lagged
    inputs (each ``(powers, lags, channels)`` block flattened in that order) and
    ``weights`` the matching columns of ``-A^(m) ∘ alpha^[l]``, ``[H,B]^(d) ∘ gamma^[l]``
    and ``[h,b]^(d) ∘ beta^[l]`` (:meth:`HWLStructure.weights`).  Rows of the histories are
    lags (row ``d`` at time ``k - d``)."""

    weights: np.ndarray
    constant: np.ndarray | float
    ar_lags: np.ndarray | None
    ar_powers: np.ndarray | None
    u_lags: np.ndarray | None
    u_powers: np.ndarray | None
    v_lags: np.ndarray | None
    v_powers: np.ndarray | None

    @classmethod
    def of(cls, model: HWLModel) -> "_StepOperator":
        W, o, N = model._weights, model.orders, model.n_modes
        blocks, fields_ = [], {}

        def gather(name, lags, per_lag, sign, width):
            """Columns ``[l, d, j]`` (power, lag, channel) of one block."""
            p = len(per_lag[0])
            cols = np.zeros((N, p, len(lags), width))
            for d, ws in enumerate(per_lag):
                for l, w in enumerate(ws):
                    cols[:, l, d, :] = sign * np.asarray(w, dtype=float).reshape(N, width)
            blocks.append(cols.reshape(N, -1))
            shape = (-1, 1, 1) if width > 1 else (-1, 1)
            fields_[f"{name}_lags"] = np.asarray(lags, dtype=np.intp)
            fields_[f"{name}_powers"] = np.arange(1, p + 1, dtype=float).reshape(shape)

        for name in ("ar", "u", "v"):
            fields_[f"{name}_lags"] = fields_[f"{name}_powers"] = None
        if o.na:
            gather("ar", o.ar_lags(), W["ar"], -1.0, N)
        if model.has_u:
            gather("u", o.input_lags(), W["u"], 1.0, N)
        if model.has_v:
            gather("v", o.input_lags(), W["v"], 1.0, 1)
        constant = np.asarray(W["c"], dtype=float).reshape(N) if "c" in W else 0.0
        return cls(np.hstack(blocks), constant, **fields_)
