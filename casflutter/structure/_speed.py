"""What the speed index ``V`` of a problem means: one object for every conversion.

Every stage works in the problem's speed index ``V`` (eq. 6: the structure sees
``alpha V^2 y``) and in the problem's unit of time.  A :class:`SpeedConvention` says what
``V`` is (``definition``, e.g. ``"V = U / U_ref, U_ref = 28.9 m/s"``), the unit of time of
the problem's frequencies, and, when the problem knows them, the airspeed per unit speed
index ``U_ref`` (``U = V U_ref`` [m/s]) and the air density ``rho`` (``q = rho U^2 / 2``
[Pa]).  Every speed index, airspeed and dynamic pressure of the package is converted by it;
:class:`~casflutter.structure.ModalStructure` carries the problem's convention (``speed``),
so every stage that has the structure has it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError

__all__ = ["SpeedConvention", "AirspeedMixin"]


def _positive(name: str, value) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value <= 0:
        raise ConfigError(f"{name} = {value!r} must be a positive finite number (or None: "
                          "not known)")
    return float(value)


@dataclass(frozen=True)
class SpeedConvention:
    """The speed index of a problem, its unit of time, and its airspeed and dynamic pressure.

    Parameters
    ----------
    definition : str
        What the speed index is, e.g. ``"V = U / U_ref, U_ref = 28.9 m/s"``.
    time_unit : str
        Unit of time of the problem (frequencies are in rad per this unit).
    U_ref : float or tuple of float, optional
        Airspeed per unit speed index [m/s], ``U = V U_ref``; ``None``: the problem has no
        airspeed scale (a nondimensional section).  A tuple gives ``U_ref`` as the product
        of its factors (e.g. ``(b, omega_ref)`` for ``V = U / (b omega_ref)``), and
        :meth:`airspeed` multiplies ``V`` by them in that order, as the problem's own
        equations do; ``U_ref`` is then stored as their product.
    rho : float, optional
        Air density [kg/m^3] for the dynamic pressure ``q = rho U^2 / 2``; ``None``: not
        known.

    Raises
    ------
    ConfigError
        ``U_ref`` or ``rho`` not a positive finite number, or ``rho`` without ``U_ref``.

    Examples
    --------
    >>> from casflutter.structure import SpeedConvention
    >>> c = SpeedConvention("V = U / U_ref, U_ref = 28.9 m/s", "s", U_ref=28.9, rho=1.225)
    >>> c.airspeed(1.2), round(c.dynamic_pressure(1.2), 2), c.speed_index(28.9)
    (34.68, 736.65, 1.0)
    """

    definition: str = "V"
    time_unit: str = "s"
    U_ref: float | tuple | None = None
    rho: float | None = None

    def __post_init__(self):
        factors = self.U_ref if isinstance(self.U_ref, tuple) else (self.U_ref,)
        factors = tuple(_positive("U_ref", f) for f in factors)
        if None in factors and len(factors) > 1:
            raise ConfigError(f"U_ref = {self.U_ref!r}: give positive factors, or None")
        U_ref = None
        if factors != (None,):
            U_ref = factors[0]
            for f in factors[1:]:
                U_ref = U_ref * f
        object.__setattr__(self, "_factors", factors)
        object.__setattr__(self, "U_ref", U_ref)
        object.__setattr__(self, "rho", _positive("rho", self.rho))
        if self.rho is not None and self.U_ref is None:
            raise ConfigError("rho without U_ref: a dynamic pressure needs the airspeed scale "
                              "U_ref [m/s per unit speed index]")

    @property
    def has_airspeed(self) -> bool:
        """Whether the problem has an airspeed scale (``U_ref``)."""
        return self.U_ref is not None

    @property
    def has_dynamic_pressure(self) -> bool:
        """Whether the problem knows its air density (``rho``) as well."""
        return self.rho is not None

    def _need_airspeed(self) -> float:
        if self.U_ref is None:
            raise ConfigError(f"the speed index ({self.definition}) has no airspeed scale: "
                              "the problem gives no U_ref")
        return self.U_ref

    def airspeed(self, V: float) -> float:
        """Airspeed ``U = V U_ref`` [m/s] of a speed index.

        Raises
        ------
        ConfigError
            The problem has no airspeed scale.
        """
        self._need_airspeed()
        U = float(V)
        for f in self._factors:
            U = U * f
        return U

    def speed_index(self, U: float) -> float:
        """Speed index ``V = U / U_ref`` of an airspeed ``U`` [m/s].

        Raises
        ------
        ConfigError
            The problem has no airspeed scale.
        """
        return float(U) / self._need_airspeed()

    def dynamic_pressure(self, V: float) -> float:
        """Dynamic pressure ``q = rho (V U_ref)^2 / 2`` [Pa] at speed index ``V``.

        Raises
        ------
        ConfigError
            The problem gives no air density (or no airspeed scale).
        """
        if self.rho is None:
            raise ConfigError(f"the speed index ({self.definition}) has no dynamic pressure: "
                              "the problem gives no air density rho [kg/m^3]")
        return 0.5 * self.rho * self.airspeed(V) ** 2

    @property
    def speed_unit(self) -> str:
        """The unit in which speeds are shown: ``"m/s"`` with an airspeed scale, else the
        speed index's definition."""
        return "m/s" if self.has_airspeed else self.definition

    @property
    def display_scale(self) -> float:
        """Shown speed per unit speed index: ``U_ref`` with an airspeed scale, else 1."""
        return float(self.U_ref) if self.has_airspeed else 1.0

    @property
    def speed_index_label(self) -> str:
        """``"speed index (<definition>)"``."""
        return f"speed index ({self.definition})"

    @property
    def frequency_unit(self) -> str:
        """``"Hz"`` for a problem in seconds, else ``"cycles per time unit <unit>"``."""
        return "Hz" if self.time_unit == "s" else f"cycles per time unit {self.time_unit}"


class AirspeedMixin:
    """``airspeed(V)`` and ``speed_index(U)`` of a model whose ``speed`` (a
    :class:`SpeedConvention`) has an airspeed scale: the truths with one, the wing files,
    the RFA system."""

    speed: SpeedConvention

    def airspeed(self, V: float) -> float:
        """Airspeed [m/s] of a speed index (:meth:`SpeedConvention.airspeed`).

        Parameters
        ----------
        V : float
            Speed index (``speed.definition``).

        Returns
        -------
        float
            ``U = V U_ref`` [m/s].
        """
        return self.speed.airspeed(V)

    def speed_index(self, U: float) -> float:
        """Speed index of an airspeed (:meth:`SpeedConvention.speed_index`).

        Parameters
        ----------
        U : float
            Airspeed [m/s] (``speed.U_ref`` per unit speed index).

        Returns
        -------
        float
            ``V = U / U_ref``.
        """
        return self.speed.speed_index(U)
