"""Chirp records of a truth simulator: the paper's CFD runs (§IV.A) on a stand-in.

The paper drives a full-order CFD solver with band-limited chirps on the modal
displacements and records the generalised aerodynamic forces ``y``.  Here a truth simulator
plays the CFD solver: one record per input channel (each modal displacement, then the flap),
that channel following :func:`casflutter.data.chirp_motion` (or the same chirp at several
amplitudes in turn) and the others at rest.

Grid velocities.  A CFD solver advances in time steps and computes the grid velocity and
acceleration of prescribed motion from the displacement samples by backward differences;
its force samples are therefore a *causal* function of the displacement samples.  The
truth's :meth:`~casflutter.truth.AeroelasticTruth.aero_forces` with exact derivatives would
make the sampled map non-causal (the apparent-mass term ``u''(t_k)`` needs future samples),
and every causal discrete model fitted to such data by least squares places poles outside
the unit circle to imitate the phase lead.  The records therefore use second-order
backward-difference (BDF2) derivatives (:func:`casflutter.data.backward_derivatives`), as a
second-order implicit CFD code would; the resulting ``O((omega dt)^2)`` derivative error is
part of the ROM error.

Amplitude range.  A linear aerodynamic operator makes the chirp amplitude a scale only, but
the polynomial terms of a nonlinear ROM (paper eq. 2-4) are fitted where the records move:
records of small amplitude leave them free to do anything at the amplitude of an LCO.
:attr:`RecordSettings.levels` repeats each record's chirp at several amplitudes
(:func:`casflutter.data.stepped_chirp_motion`), and :attr:`RecordSettings.amplitude` may
differ per channel, so that each modal displacement is driven up to and past its amplitude
on the LCO the ROM is meant to reproduce.

Coupling delay.  In a loosely coupled CFD time march the flow of step ``k`` sees the grid of
step ``k - 1``: the force lags the motion by one sample, the reason for the paper's input
delay ``r = 1``.  :attr:`RecordSettings.coupling_delay` delays the forces by that many samples.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .._settings import finite_numbers
from ..data import IOData, Record, backward_derivatives, check_band, stepped_chirp_motion
from ..errors import ConfigError, DataWarning

__all__ = ["RecordSettings", "truth_records"]


@dataclass(frozen=True)
class RecordSettings:
    """How the chirp records of a truth are taken (defaults: the paper's §IV.A records of the
    seed wing, without coupling delay).

    Speeds are speed indices of the problem; times in its time unit.
    """

    V0: float = 0.69
    """Speed index at which the records are taken (Table I: 0.69)."""
    dt: float = 0.002
    """Sampling time."""
    duration: float = 8.0
    """Length of each chirp (at least 200 samples); a record holds one chirp per level."""
    band: tuple = (0.2, 60.0)
    """Chirp band ``(f_low, f_high)`` [cycles per time unit], below the Nyquist frequency."""
    amplitude: float | tuple = 0.01
    """Chirp amplitude of the modal displacements [per unit modal coordinate] and the flap
    [rad]: one number for every channel, or one per channel (the modes in order, then the
    flap).  The linear aerodynamics make it a scale only; a nonlinear truth's records should
    reach the amplitudes of the response the ROM must reproduce (module docstring)."""
    levels: tuple = (1.0,)
    """Amplitude factors of consecutive chirps in each record: the record holds
    ``len(levels)`` chirps of ``duration`` each, chirp ``k`` at ``levels[k] * amplitude``
    (:func:`casflutter.data.stepped_chirp_motion`)."""
    taper: float = 0.1
    """Raised-cosine taper fraction at each end of a record, in (0, 0.5]."""
    flap: bool = True
    """Also record the flap input ``v`` (the ROM then has the input ``v``)."""
    coupling_delay: int = 0
    """Samples between a motion and the force it produces (module docstring): 1 models the
    loosely coupled CFD time march of the paper."""

    def __post_init__(self):
        for name in ("V0", "dt", "duration"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or not value > 0:
                raise ConfigError(f"{name} = {value!r}: must be > 0")
            object.__setattr__(self, name, float(value))
        amp = self.amplitude
        if isinstance(amp, (list, tuple, np.ndarray)):
            amp = finite_numbers("amplitude", list(amp), len(amp),
                                 what="one amplitude per channel (modes, then the flap)")
            if not amp or not all(a > 0 for a in amp):
                raise ConfigError(f"amplitude = {list(self.amplitude)!r}: every amplitude "
                                  "must be > 0")
        elif isinstance(amp, bool) or not isinstance(amp, (int, float)) \
                or not math.isfinite(amp) or not amp > 0:
            raise ConfigError(f"amplitude = {amp!r}: must be > 0 (one number, or one per "
                              "channel: the modes, then the flap)")
        else:
            amp = float(amp)
        object.__setattr__(self, "amplitude", amp)
        levels = self.levels
        if not isinstance(levels, (list, tuple, np.ndarray)) or len(levels) == 0:
            raise ConfigError(f"levels = {levels!r}: give a list of amplitude factors, e.g. "
                              "[0.25, 0.5, 1.0]")
        levels = finite_numbers("levels", list(levels), len(levels), what="amplitude factors > 0")
        if not all(x > 0 for x in levels):
            raise ConfigError(f"levels = {list(self.levels)!r}: every factor must be > 0")
        object.__setattr__(self, "levels", levels)
        band = finite_numbers("band", self.band, 2, what="[f_low, f_high] in Hz")
        check_band(band, self.dt)
        object.__setattr__(self, "band", band)
        if self.duration / self.dt < 200:
            raise ConfigError(f"duration / dt = {self.duration / self.dt:.0f} samples: at least "
                              "200 are needed; lengthen duration or lower dt")
        if not 0.0 < self.taper <= 0.5:
            raise ConfigError(f"taper = {self.taper!r}: must lie in (0, 0.5]")
        d = self.coupling_delay
        if isinstance(d, bool) or not isinstance(d, int) or d < 0:
            raise ConfigError(f"coupling_delay = {d!r}: must be an integer >= 0")
        if d >= self.n_samples:
            raise ConfigError(f"coupling_delay = {d}: must be an integer from 0 to "
                              f"{self.n_samples - 1} samples (shorter than the record: "
                              f"duration / dt = {self.n_samples} samples); it counts steps "
                              "of dt, not seconds")

    @property
    def n_samples(self) -> int:
        """Samples per record, ``len(levels) * round(duration / dt)``."""
        return len(self.levels) * int(round(self.duration / self.dt))

    def channel_amplitudes(self, n_channels: int) -> tuple[float, ...]:
        """Peak chirp amplitude of each of ``n_channels`` channels (before the levels).

        Parameters
        ----------
        n_channels : int
            Number of excited channels (the modes, then the flap).

        Returns
        -------
        tuple of float
            One amplitude per channel.

        Raises
        ------
        ConfigError
            Per-channel amplitudes whose number is not ``n_channels``.
        """
        if isinstance(self.amplitude, tuple):
            if len(self.amplitude) != n_channels:
                raise ConfigError(f"amplitude has {len(self.amplitude)} entries for "
                                  f"{n_channels} channels (the modes, then the flap): give "
                                  f"{n_channels} or one number")
            return self.amplitude
        return (self.amplitude,) * n_channels


def _check_lowest_mode(truth, s: RecordSettings) -> None:
    """Warn when the records cannot see the lowest structural mode (see :func:`truth_records`),
    the mark of settings in another time unit than the problem's."""
    ms = truth.modal_structure()
    k = int(np.argmin(ms.omega))
    f = float(ms.omega[k]) / (2 * np.pi)          # cycles per time unit
    if not f > 0:
        return
    unit = ms.time_unit
    misses = []
    if not s.band[0] <= f <= s.band[1]:
        misses.append(f"the chirp band {list(s.band)} cycles per {unit} does not hold it")
    if s.duration * f < 2.0:
        misses.append(f"a record of duration {s.duration:g} holds {s.duration * f:.2g} of its "
                      "periods")
    if misses:
        hint = "" if unit == "s" else ", not seconds"
        warnings.warn(f"records of {type(truth).__name__}: its lowest structural mode "
                      f"({ms.mode_names[k]}) is at {f:.4g} cycles per {unit}; "
                      + " and ".join(misses) + f". dt, duration and band are in the problem's "
                      f"time unit ({unit}{hint}): give a band around its modes and records of "
                      "many periods (e.g. problems/<name>/flutter.toml)",
                      DataWarning, stacklevel=3)


def truth_records(truth, settings: RecordSettings | None = None, **changes) -> IOData:
    """Chirp records of a truth simulator at the speed index ``settings.V0``.

    One record per input channel (each modal displacement, then the flap): that channel
    follows :func:`casflutter.data.stepped_chirp_motion` (one chirp per level, at its
    amplitude times each level), the others are held at zero, and the
    forces ``y`` come from ``truth.aero_forces`` with BDF2 grid velocities, delayed by
    ``coupling_delay`` samples (module docstring).

    Parameters
    ----------
    truth : casflutter.truth.AeroelasticTruth
        The simulator.
    settings : RecordSettings, optional
        Default :class:`RecordSettings()`.
    **changes
        Fields of :class:`RecordSettings` changed on top of ``settings`` (``V0=2.0``).

    Returns
    -------
    IOData
        ``N`` (or ``N + 1`` with the flap) records of ``settings.n_samples`` samples;
        ``meta`` holds ``V``, ``band``, ``derivatives``, ``amplitude`` (per channel) and
        ``levels``.

    Warns
    -----
    DataWarning
        A chirp band that misses the problem's lowest structural mode, or records shorter
        than two of its periods: ``dt``, ``duration`` and ``band`` are in the problem's time
        unit (``1/omega_theta`` for the typical section, not seconds).

    Raises
    ------
    ConfigError
        An invalid setting (named), e.g. a band above the Nyquist frequency or a number of
        per-channel amplitudes that is not the number of channels.

    See Also
    --------
    identify : the HWL ROM from such records.
    identify_common_denominator : the linear ROM from such records.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> data = cf.truth_records(truth, V0=1.8, dt=0.1, duration=60.0, band=(0.002, 1.0))
    >>> len(data.records), data.n_modes, data.has_v
    (3, 2, True)
    """
    s = replace(settings or RecordSettings(), **changes) if changes else (
        settings or RecordSettings())
    _check_lowest_mode(truth, s)
    N = truth.n_modes
    K, dt = s.n_samples, s.dt
    t = np.arange(K) * dt
    n_in = N + (1 if s.flap else 0)
    amps = s.channel_amplitudes(n_in)
    chirp, _, _ = stepped_chirp_motion(t, s.band, s.levels, s.taper)
    names = truth.modal_structure().mode_names
    recs = []
    for j in range(n_in):
        w = np.zeros((K, N + 1))
        w[:, j] = amps[j] * chirp
        d1, d2 = backward_derivatives(w, dt)
        y = truth.aero_forces(t, w[:, :N], w[:, N], s.V0, udot=d1[:, :N], uddot=d2[:, :N],
                              vdot=d1[:, N], vddot=d2[:, N])
        if s.coupling_delay:
            y = np.vstack([np.zeros((s.coupling_delay, N)), y[:-s.coupling_delay]])
        label = names[j] if j < N else "flap"
        recs.append(Record(y, w[:, :N], w[:, N] if s.flap else None, name=f"chirp {label}"))
    return IOData(tuple(recs), dt, output_names=tuple(f"y[{n}]" for n in names),
                  u_names=tuple(f"u[{n}]" for n in names), v_name="v",
                  meta={"V": float(s.V0), "band": tuple(s.band), "derivatives": "BDF2",
                        "amplitude": tuple(float(a) for a in amps),
                        "levels": tuple(s.levels)})
