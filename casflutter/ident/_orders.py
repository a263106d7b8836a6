"""Model orders of the HWL ROM (paper Table I: (mu, na, nb, r, p, q))."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import OrderError

__all__ = ["HWLOrders"]

_NAMES = ("mu", "na", "nb", "r", "p", "q")


def _as_int(name: str, value):
    """An order value as int; integer-valued floats and numeric strings are accepted."""
    if isinstance(value, (bool, np.bool_)):
        raise OrderError(f"order {name}={value!r} must be an integer, not a boolean")
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise OrderError(f"order {name}={value!r} is not a number: give an integer") from None
    if isinstance(value, (float, np.floating)):
        if not np.isfinite(value) or value != int(value):
            raise OrderError(f"order {name}={value!r} must be an integer (got a non-integer "
                             "or non-finite value)")
        return int(value)
    raise OrderError(f"order {name}={value!r} ({type(value).__name__}) must be an integer")


@dataclass(frozen=True)
class HWLOrders:
    """Orders ``(mu, na, nb, r, p, q)`` of the Hammerstein--Wiener-like model (eq. 1--3).

    Attributes
    ----------
    mu : int
        Number of Markov parameters (``mu >= 1``); ``mu = 1`` is the ARMA structure.
    na : int
        Autoregressive order (``na >= 0``); the output lags used are ``mu, ..., mu + na - 1``.
    nb : int
        Order of the input tail ``B, b`` (``nb >= 0``); ``nb + 1`` coefficients at lags
        ``r + mu, ..., r + mu + nb``.
    r : int
        Input delay (``r >= 0``); the Markov terms ``H, h`` act at lags ``r, ..., r + mu - 1``.
    p : int
        Degree of the input polynomials gamma and beta (``p >= 1``).
    q : int
        Degree of the output polynomials alpha (``q >= 1``).
    """

    mu: int = 3
    na: int = 1
    nb: int = 1
    r: int = 1
    p: int = 2
    q: int = 2

    def __post_init__(self):
        lower = {"mu": 1, "na": 0, "nb": 0, "r": 0, "p": 1, "q": 1}
        for name, lo in lower.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int):
                raise OrderError(f"order {name}={value!r} must be an integer >= {lo}")
            if value < lo:
                raise OrderError(f"order {name}={value} is out of range: {name} must be >= {lo}")
            if value > 50:
                raise OrderError(f"order {name}={value} is out of range: at most 50 is supported")

    @classmethod
    def from_tuple(cls, orders) -> "HWLOrders":
        """Build from ``(mu, na, nb, r, p, q)`` in the paper's order (Table I).

        Also accepts a mapping with those keys, a string ``"3,1,1,1,2,2"`` or an
        :class:`HWLOrders`.  Integer-valued floats are taken as integers.

        Parameters
        ----------
        orders : tuple, mapping, str or HWLOrders
            The six orders.


        Returns
        -------
        HWLOrders

        Raises
        ------
        OrderError
            ``None``, the wrong number of values, or a value that is not an integer in range.
        """
        if isinstance(orders, HWLOrders):
            return orders
        hint = "give six integers (mu, na, nb, r, p, q), e.g. (3, 1, 1, 1, 2, 2) as in the paper"
        if orders is None:
            raise OrderError(f"orders=None: {hint}")
        if isinstance(orders, dict):
            unknown = sorted(set(map(str, orders)) - set(_NAMES))
            if unknown:
                raise OrderError(f"orders has unknown key(s) {unknown}: the keys are {_NAMES}")
            return cls(**{k: _as_int(k, v) for k, v in orders.items()})
        if isinstance(orders, str):
            orders = [x for x in orders.replace(" ", "").split(",") if x != ""]
        try:
            values = tuple(orders)
        except TypeError:
            raise OrderError(f"orders={orders!r} is not a sequence: {hint}") from None
        if len(values) != 6:
            raise OrderError(f"orders must be (mu, na, nb, r, p, q): got {len(values)} values "
                             f"{values!r}; {hint}")
        return cls(*[_as_int(n, v) for n, v in zip(_NAMES, values)])

    def as_tuple(self) -> tuple[int, int, int, int, int, int]:
        """``(mu, na, nb, r, p, q)``.

        Returns
        -------
        tuple of int
        """
        return (self.mu, self.na, self.nb, self.r, self.p, self.q)

    @property
    def max_lag(self) -> int:
        """Largest delay in samples appearing in eq. 3."""
        ar = self.mu + self.na - 1 if self.na > 0 else 0
        return max(ar, self.r + self.mu + self.nb)

    def ar_lags(self) -> list[int]:
        """Output lags of the autoregressive terms ``A^(m)``, ``m = 1..na``: ``mu + m - 1``.

        Returns
        -------
        list of int
        """
        return [self.mu + m - 1 for m in range(1, self.na + 1)]

    def input_lags(self) -> list[int]:
        """Input lags of ``[H^(0..mu-1), B^(0..nb)]`` (the same for ``h, b``).

        Returns
        -------
        list of int
        """
        return [self.r + d for d in range(self.mu)] + [self.r + self.mu + d for d in range(self.nb + 1)]

    def __str__(self) -> str:
        return "(mu, na, nb, r, p, q) = ({}, {}, {}, {}, {}, {})".format(*self.as_tuple())
