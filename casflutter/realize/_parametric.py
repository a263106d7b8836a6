"""A parametric ROM: linear HWL ROMs identified at several speeds, interpolated in V.

The paper's conclusion names this as future work.  A ROM identified at one speed ``V0`` and
closed with the V² scaling of eq. 8 represents the aerodynamics frozen at ``V0``
(:func:`casflutter.truth.frozen_aero_truth`).  ROMs identified at speeds ``V_1..V_m``
(Chebyshev–Lobatto nodes over the analysis range, :func:`speed_nodes`) with one scalar
denominator (:func:`casflutter.ident.identify_common_denominator`) have the same structure;
their coefficients — the denominator ``a_m`` and the input matrices, the latter multiplied by
``V^2`` so that the interpolated quantity is the dimensional force operator, free of the
``1/V^2`` of the apparent mass — are interpolated in V by the barycentric polynomial through
the nodes (second barycentric form with weights computed in a fixed order, so that the same
ROMs give the same bits in every process: scipy's interpolator permutes the nodes at random
when it computes the weights).  The interpolated model is realised by the block observer-canonical form
(:func:`casflutter.realize.canonical_matrices`), a fixed-dimension realisation that is a
continuous function of the coefficients, and the inverse Tustin transform; ΣAE(V)
(:class:`casflutter.aeroelastic.ParametricSystem`) then has continuous eigenvalues and
eigenvectors and :func:`casflutter.aeroelastic.find_flutter` tracks it like any ``V -> A(V)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ..ident import CommonDenominatorResult, HWLModel
from ._canonical import canonical_matrices, canonical_realization, lag_coefficients
from ._realize import inverse_tustin, tustin_to_continuous

__all__ = ["ParametricROM", "speed_nodes"]


def speed_nodes(V_range, n: int) -> np.ndarray:
    """Chebyshev–Lobatto nodes of ``V_range``: the identification speeds of a parametric ROM.

    Parameters
    ----------
    V_range : (float, float)
        Lowest and highest speed index.
    n : int
        Number of nodes (at least 2).

    Returns
    -------
    ndarray, shape (n,)
        Increasing, both ends included.
    """
    if n < 2:
        raise ConfigError(f"n = {n}: a parametric ROM needs at least 2 speeds")
    lo, hi = map(float, V_range)
    x = np.cos(np.pi * np.arange(n)[::-1] / (n - 1))
    return lo + 0.5 * (hi - lo) * (x + 1.0)


class _Barycentric:
    """The polynomial through ``(x_j, y_j)`` (rows of ``y``), second barycentric form.

    The weights ``w_j = 1 / prod_{k != j} (x_j - x_k)`` are formed with the differences
    scaled by the capacity of the interval (``(max - min) / 4``), which keeps the products
    near one, in a fixed order; evaluation sums with numpy's (deterministic) reductions.
    """

    def __init__(self, x, y):
        self.x = np.asarray(x, dtype=float)
        self.y = np.asarray(y, dtype=float)
        d = (self.x[:, None] - self.x[None, :]) * (4.0 / (self.x[-1] - self.x[0]))
        np.fill_diagonal(d, 1.0)
        self.w = 1.0 / np.prod(d, axis=1)

    def __call__(self, t: float) -> np.ndarray:
        diff = float(t) - self.x
        hit = np.flatnonzero(diff == 0.0)
        if hit.size:
            return self.y[hit[0]].copy()
        c = self.w / diff
        return np.sum(c.reshape((-1,) + (1,) * (self.y.ndim - 1)) * self.y, axis=0) / np.sum(c)


@dataclass(frozen=True)
class ParametricROM:
    """Common-denominator ROMs identified at several speeds, interpolated in V.

    Attributes
    ----------
    speeds : ndarray
        Identification speed indices ``V_1..V_m`` (increasing, at least 2).
    identifications : tuple of CommonDenominatorResult
        One per speed, all of the same orders.

    Raises
    ------
    ConfigError
        Speeds not increasing, fewer than two, not one per identification, or ROMs of
        different orders.
    """

    __repr__ = result_repr

    speeds: np.ndarray
    identifications: tuple
    _interp: tuple = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        V = np.asarray(self.speeds, dtype=float)
        ids = tuple(self.identifications)
        if V.size != len(ids) or V.size < 2 or np.any(np.diff(V) <= 0):
            raise ConfigError("speeds must be increasing, at least 2, one per identification")
        if not all(isinstance(i, CommonDenominatorResult) for i in ids):
            raise ConfigError("identifications must be CommonDenominatorResult "
                              "(casflutter.ident.identify_common_denominator)")
        orders = {i.model.orders for i in ids}
        if len(orders) != 1:
            raise ConfigError(f"the ROMs have different orders {orders}; identify them alike")
        a = np.array([i.a for i in ids])
        theta = np.array([i.model.theta for i in ids])
        object.__setattr__(self, "speeds", V)
        object.__setattr__(self, "identifications", ids)
        # interpolate a_m, and V^2 times the input coefficients (dimensional forces)
        th_scaled = theta * V[:, None] ** 2
        object.__setattr__(self, "_interp", (_Barycentric(V, a), _Barycentric(V, th_scaled)))

    @property
    def template(self) -> HWLModel:
        """The ROM of the first speed (orders, names, sampling time)."""
        return self.identifications[0].model

    @property
    def n_modes(self) -> int:
        """Number of outputs ``N`` (modes)."""
        return self.template.n_modes

    def model_at(self, V: float) -> HWLModel:
        """The interpolated HWL ROM at speed index V (outside the nodes: extrapolated).

        Parameters
        ----------
        V : float
            Speed index at which the ROMs' coefficients are interpolated.

        Returns
        -------
        HWLModel
        """
        ia, ith = self._interp
        V = float(V)
        a = np.atleast_1d(ia(V)).ravel()
        theta = np.atleast_1d(ith(V)).ravel() / V ** 2
        # the A blocks of theta are a_m I; set them from the interpolated scalars exactly
        tmpl = self.template
        c = tmpl.with_theta(theta).coefficients()
        c["A"] = np.array([am * np.eye(tmpl.n_modes) for am in a])
        return tmpl.with_theta(tmpl.structure.pack(c))

    def sigma_f(self, V: float) -> control.StateSpace:
        """Σf at V (eq. 5): canonical realisation of :meth:`model_at` and inverse Tustin.

        Parameters
        ----------
        V : float
            Speed index, as in :meth:`model_at`.

        Returns
        -------
        control.StateSpace
        """
        return tustin_to_continuous(canonical_realization(self.model_at(V)))

    def sigma_f_matrices(self, V: float) -> tuple[np.ndarray, ...]:
        """``(Af, Bf, bf, Cf, Df, df)`` of Σf at V (eq. 5), computed directly in numpy.

        The same matrices as :meth:`sigma_f` (the canonical form of the interpolated
        coefficients, inverse Tustin) without building ``control.StateSpace`` objects: this
        is what a flutter search evaluates thousands of times.

        Parameters
        ----------
        V : float
            Speed index, as in :meth:`sigma_f`.

        Returns
        -------
        tuple of ndarray
            ``bf``, ``df`` are zero without a flap input.
        """
        ia, ith = self._interp
        V = float(V)
        a = np.atleast_1d(ia(V)).ravel()
        tmpl = self.template
        Abar, Bbar = lag_coefficients(tmpl.with_theta(np.atleast_1d(ith(V)).ravel() / V ** 2))
        Abar[1:len(a) + 1] = a[:, None, None] * np.eye(tmpl.n_modes)
        N, m = Bbar.shape[1], Bbar.shape[2]
        A, B, C, D = inverse_tustin(*canonical_matrices(Abar, Bbar), tmpl.dt)
        bf = B[:, N] if m > N else np.zeros(A.shape[0])
        df = D[:, N] if m > N else np.zeros(N)
        return A, B[:, :N], bf, C, D[:, :N], df
