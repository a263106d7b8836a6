"""A cantilever wing with several trailing-edge flaps, rate gyros and accelerometers.

The multi-input, multi-output plant family of the size an aircraft's aeroservoelastic model
has: the Goland wing's structure and strip theory (:class:`casflutter.truth.GolandWing`:
assumed bending and torsion modes of a uniform cantilever, Theodorsen's strip coefficients
with R. T. Jones' two-lag Wagner function, one lag pattern per assumed mode and per flap),
with

* **flap segments** along the span, ``[y_a, y_b]`` each (fractions of the semispan), of one
  chord fraction.  The flap terms of strip theory are integrals over the flap's span and
  linear in it, so a segment's terms are those of a flap from ``y_a`` to the tip minus those
  of a flap from ``y_b`` to the tip (the Goland wing's own flap terms); each segment gets its
  own lag pattern;
* a **second-order actuator** behind every flap, ``β̈ = ω_a² (β_c − β) − 2 ζ_a ω_a β̇``; the
  inputs are the commands ``β_c`` [rad];
* **rate gyros** measuring the twist rate ``θ̇(y)`` [rad/s] at spanwise stations, each
  behind a first-order low-pass filter (a sensor's bandwidth);
* **accelerometers** at a front and a rear chordwise position of spanwise stations,
  measuring ``ḧ(y) + x θ̈(y)`` [m/s²] (positive down, the plunge direction; ``x`` aft of the
  elastic axis), with the exact feed-through of the commands (through the actuators'
  accelerations and the flaps' apparent mass).

The states are ``[u, u̇, z1, z2, β, β̇, g]``: the in-vacuo modal coordinates and velocities,
the two Jones lag blocks (one state per assumed mode and per flap each), the flap angles and
rates, and the gyro filters.  The default (four bending and four torsion modes, four flaps,
two gyros, six accelerometers) has ``16 + 24 + 8 + 2 = 50`` states, 4 inputs and 8 outputs.
The speed is the airspeed ``U`` in m/s; the state matrix is a quadratic polynomial in ``U``
(lag rates ∝ U, circulatory and flap-hinge forces ∝ U and U²), so the family's
``speed_degree`` is 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ..truth import JONES_A, GolandParams, GolandWing
from ..truth._goland import _bending_shapes
from ._family import FamilySignals, MatrixFamily
from ._loop import check_servo

__all__ = ["FlapWingFamily"]


def _default_params() -> GolandParams:
    return GolandParams(n_bending=4, n_torsion=4, zeta=0.01, flap_chord=0.2)


def _station(y: float) -> str:
    return f"{round(100 * y):d}"


@dataclass(frozen=True)
class FlapWingFamily(MatrixFamily):
    """The Goland wing with flap segments, actuators, rate gyros and accelerometers.

    See the module docstring for the model.  The default instance is the 50-state,
    4-input, 8-output family of ``problems/goland_4flaps``.

    Parameters
    ----------
    params : casflutter.truth.GolandParams, optional
        Structure, air and flap chord (default: the Goland wing with four bending and four
        torsion modes, 1 % modal damping, flaps of 20 % chord); its single-flap span
        fields are not used.
    flap_segments : tuple of (float, float)
        Spanwise extent of each flap, fractions of the semispan, ``0 <= y_a < y_b <= 1``.
    actuator_omega, actuator_zeta : float
        Natural frequency [rad/s] and damping ratio of every flap actuator.
    gyro_stations : tuple of float
        Spanwise stations of the rate gyros (fractions of the semispan).
    gyro_bandwidth_hz : float
        Corner frequency of each gyro's first-order filter [Hz].
    accel_stations : tuple of float
        Spanwise stations of the accelerometer pairs.
    accel_chord : tuple of float
        Chordwise positions of the front and rear accelerometer of each station (fractions
        of the chord from the leading edge).
    speed_range : tuple of float
        Airspeeds [m/s] of the family.
    name : str
        For messages and files.
    feedback : {"negative", "positive"}
        The convention a controller of this family uses.

    Raises
    ------
    ConfigError
        Overlapping or out-of-range segments or stations, an actuator out of range, a
        bad speed range.

    Examples
    --------
    >>> from casflutter.aeroelastic import FlapWingFamily
    >>> fam = FlapWingFamily()
    >>> P = fam.plant(120.0)
    >>> P.nstates, P.ninputs, P.noutputs
    (50, 4, 8)
    """

    __repr__ = result_repr

    params: GolandParams = field(default_factory=_default_params)
    flap_segments: tuple = ((0.2, 0.4), (0.4, 0.6), (0.6, 0.8), (0.8, 1.0))
    actuator_omega: float = 2.0 * math.pi * 25.0
    actuator_zeta: float = 0.7
    gyro_stations: tuple = (0.5, 1.0)
    gyro_bandwidth_hz: float = 30.0
    accel_stations: tuple = (1.0 / 3.0, 2.0 / 3.0, 1.0)
    accel_chord: tuple = (0.15, 0.65)
    speed_range: tuple = (60.0, 200.0)
    name: str = "goland_4flaps"
    feedback: str = "negative"

    speed_unit = "m/s"
    time_unit = "s"
    speed_degree = 2

    def __post_init__(self):
        if not isinstance(self.params, GolandParams):
            raise ConfigError(f"params must be a casflutter.truth.GolandParams, got "
                              f"{type(self.params).__name__}")
        segs = tuple(tuple(float(x) for x in s) for s in self.flap_segments)
        if not segs or any(len(s) != 2 or not 0.0 <= s[0] < s[1] <= 1.0 for s in segs):
            raise ConfigError(f"flap_segments = {self.flap_segments!r}: give one or more "
                              "(y_a, y_b) with 0 <= y_a < y_b <= 1 (fractions of the semispan)")
        ordered = sorted(segs)
        if any(a[1] > b[0] for a, b in zip(ordered, ordered[1:])):
            raise ConfigError(f"flap_segments = {self.flap_segments!r} overlap; each part of "
                              "the span has at most one flap")
        check_servo(self.actuator_omega, self.actuator_zeta,
                    ("actuator_omega", "actuator_zeta"))
        for key in ("gyro_stations", "accel_stations", "accel_chord"):
            vals = tuple(float(x) for x in getattr(self, key))
            if not vals or any(not 0.0 < x <= 1.0 for x in vals):
                raise ConfigError(f"{key} = {getattr(self, key)!r}: give fractions in (0, 1]")
            object.__setattr__(self, key, vals)
        if not (math.isfinite(self.gyro_bandwidth_hz) and self.gyro_bandwidth_hz > 0):
            raise ConfigError(f"gyro_bandwidth_hz = {self.gyro_bandwidth_hz!r} must be > 0")
        lo, hi = (float(x) for x in self.speed_range)
        if not (0.0 < lo < hi and math.isfinite(hi)):
            raise ConfigError(f"speed_range = {self.speed_range!r}: give 0 < lo < hi [m/s]")
        if self.feedback not in ("negative", "positive"):
            raise ConfigError(f"feedback = {self.feedback!r}: 'negative' or 'positive'")
        object.__setattr__(self, "flap_segments", segs)
        object.__setattr__(self, "speed_range", (lo, hi))

    # ------------------------------------------------------------------ the pieces
    @cached_property
    def _wings(self) -> dict[float, GolandWing]:
        """A Goland wing with its flap from each segment end to the tip (none from the tip)."""
        ends = sorted({y for s in self.flap_segments for y in s if y < 1.0})
        return {y: GolandWing(self.params.with_updates(flap_span_start=y)) for y in ends}

    @cached_property
    def _structure(self):
        wing = next(iter(self._wings.values()))
        ms = wing.modal_structure()
        return wing, ms.omega, ms.zeta, np.asarray(ms.shapes, float)

    @property
    def n_modes(self) -> int:
        """Number of in-vacuo modes N."""
        return int(self._structure[1].size)

    @cached_property
    def _sensor_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Twist rows at the gyro stations and ``h + x θ`` rows at the accelerometers, on the
        modal coordinates."""
        p, (_, _, _, Phi) = self.params, self._structure
        L, nt = p.semispan, p.n_torsion
        gam = (2 * np.arange(1, nt + 1) - 1) * np.pi / (2 * L)

        def rows(y, x):
            phi, _ = _bending_shapes(np.array([y * L]), L, p.n_bending)
            return np.concatenate([phi[:, 0], x * np.sin(gam * y * L)])

        gyro = np.array([rows(y, 1.0) * np.r_[np.zeros(p.n_bending), np.ones(nt)]
                         for y in self.gyro_stations])
        acc = np.array([rows(y, (xc - p.ea_chord) * p.chord)
                        for y in self.accel_stations for xc in self.accel_chord])
        return gyro @ Phi, acc @ Phi

    def _flap_terms(self, V: float):
        """The segments' flap terms ``(Fv, Fv1, Fv2, W_f)`` (columns per segment) and the
        modes' aerodynamic operator at speed index ``V``."""
        ams = {y: w.aero_matrices(V) for y, w in self._wings.items()}
        base = next(iter(ams.values()))
        n = base.Cx.shape[0]

        def column(am, key):
            return getattr(am, key) if key != "W" else am.W[:, n]

        cols = {key: [] for key in ("Fv", "Fv1", "Fv2", "W")}
        for ya, yb in self.flap_segments:
            for key in cols:
                c = column(ams[ya], key)
                cols[key].append(c - column(ams[yb], key) if yb < 1.0 else c)
        return base, {key: np.column_stack(v) for key, v in cols.items()}

    # --------------------------------------------------------------------- the model
    @property
    def signals(self) -> FamilySignals:
        """Inputs ``flap_1..`` (actuator commands, rad), outputs ``gyro_<station>`` (rad/s)
        and ``acc_<front|rear>_<station>`` (m/s², positive down); all controls and
        measurements."""
        nf = len(self.flap_segments)
        outs = [f"gyro_{_station(y)}" for y in self.gyro_stations]
        tags = ("front", "rear") if len(self.accel_chord) == 2 else tuple(
            f"x{_station(x)}" for x in self.accel_chord)
        outs += [f"acc_{t}_{_station(y)}" for y in self.accel_stations for t in tags]
        return FamilySignals([f"flap_{j + 1}" for j in range(nf)], outs,
                             input_units=("rad",) * nf,
                             output_units=("rad/s",) * len(self.gyro_stations)
                             + ("m/s^2",) * (len(outs) - len(self.gyro_stations)))

    def matrices(self, U: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` at airspeed U (module docstring for the states).

        Parameters
        ----------
        U : float
            Airspeed [m/s] inside :attr:`speed_range`.

        Returns
        -------
        tuple of ndarray
        """
        U = self.check_speed(U, "U")
        wing, omega, zeta, Phi = self._structure
        am, f = self._flap_terms(wing.speed_index(U))
        P, N, n = Phi.T, omega.size, Phi.shape[0]
        nf, ngy = len(self.flap_segments), len(self.gyro_stations)
        ng = n + nf
        a0 = 1.0 - sum(JONES_A)
        W = np.hstack([am.W[:, :n], f["W"]])                     # lag patterns: modes, flaps
        Gx = np.vstack([am.Gx[:n], np.zeros((nf, n))])
        Gx1 = np.vstack([am.Gx1[:n], np.zeros((nf, n))])
        Gv, Gv1 = np.zeros((ng, nf)), np.zeros((ng, nf))
        Gv[n:, :], Gv1[n:, :] = am.Gv[n] * np.eye(nf), am.Gv1[n] * np.eye(nf)
        Minv = np.linalg.inv(np.eye(N) - P @ am.Mx @ Phi)
        Ku = -np.diag(omega ** 2) + P @ (am.Kx + a0 * W @ Gx) @ Phi
        Cu = -np.diag(2.0 * zeta * omega) + P @ (am.Cx + a0 * W @ Gx1) @ Phi
        Bv = [P @ (f["Fv"] + a0 * W @ Gv), P @ (f["Fv1"] + a0 * W @ Gv1), P @ f["Fv2"]]
        wa, za = float(self.actuator_omega), float(self.actuator_zeta)
        tau = 1.0 / (2.0 * math.pi * self.gyro_bandwidth_hz)
        iu, iud = slice(0, N), slice(N, 2 * N)
        iz = [slice(2 * N + j * ng, 2 * N + (j + 1) * ng) for j in range(2)]
        ib = slice(2 * N + 2 * ng, 2 * N + 2 * ng + nf)
        ibd = slice(ib.stop, ib.stop + nf)
        ig = slice(ibd.stop, ibd.stop + ngy)
        nx = ig.stop
        A, B = np.zeros((nx, nx)), np.zeros((nx, nf))
        A[iu, iud] = np.eye(N)
        A[iud, iu], A[iud, iud] = Minv @ Ku, Minv @ Cu
        for j, (Aj, lam) in enumerate(zip(JONES_A, am.lams)):
            A[iud, iz[j]] = Minv @ (Aj * lam * P @ W)
            A[iz[j], iu], A[iz[j], iud] = Gx @ Phi, Gx1 @ Phi
            A[iz[j], iz[j]] = -lam * np.eye(ng)
            A[iz[j], ib], A[iz[j], ibd] = Gv, Gv1
        # flap accelerations β̈ = wa² (β_c − β) − 2 za wa β̇ enter through Bv[2]
        A[iud, ib] = Minv @ (Bv[0] - wa * wa * Bv[2])
        A[iud, ibd] = Minv @ (Bv[1] - 2.0 * za * wa * Bv[2])
        B[iud] = Minv @ Bv[2] * wa * wa
        A[ib, ibd] = np.eye(nf)
        A[ibd, ib], A[ibd, ibd] = -wa * wa * np.eye(nf), -2.0 * za * wa * np.eye(nf)
        B[ibd] = wa * wa * np.eye(nf)
        gyro, acc = self._sensor_rows
        A[ig, iud], A[ig, ig] = gyro / tau, -np.eye(ngy) / tau
        C = np.vstack([np.hstack([np.zeros((ngy, ig.start)), np.eye(ngy)]), acc @ A[iud]])
        D = np.vstack([np.zeros((ngy, nf)), acc @ B[iud]])
        return A, B, C, D

    @property
    def n_states(self) -> int:
        """``4 N + 4 n_flaps + n_gyros`` (``2N`` structure, ``2 (N + n_flaps)`` lags,
        ``2 n_flaps`` actuators)."""
        return 4 * self.n_modes + 4 * len(self.flap_segments) + len(self.gyro_stations)
