"""The established LCO of a ROM loop, and the speed-following ROM's LCO beside the wing's.

An LCO just above its flutter point grows slowly: :func:`established_loop_lco` releases the
sampled-data ROM loop from a deflected mode and continues it while its modal displacements
still grow, as :func:`casflutter.truth.truth_lco` does for the truth.  :func:`compare_lco`
puts the LCO of the ROM that follows the wing over speed
(:class:`~casflutter.aeroelastic.SpeedFollowingROM`) beside the wing's own, at the same
multiples of the wing's flutter speed and on the same sensors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..aeroelastic import LoopSimulation, SpeedFollowingROM, simulate_loop
from ..errors import ConfigError
from ..structure import ModalStructure
from ..truth import TruthLco, truth_lco

__all__ = ["established_loop_lco", "LcoComparison", "compare_lco"]


def established_loop_lco(rom, structure: ModalStructure, V: float, n_steps: int, mode: int,
                         deflection: float, *, max_extensions: int = 5,
                         **loop) -> LoopSimulation:
    """The sampled-data ROM loop at V released from a deflected mode, continued while it
    still grows (its LCO, if any, established).

    Each continuation starts from the structure's last state; the ROM's past outputs restart
    at zero, a small kick that a converging LCO forgets.

    Parameters
    ----------
    rom : object
        The discrete ROM (:func:`~casflutter.aeroelastic.simulate_loop`).
    structure : ModalStructure
        Σs.
    V : float
        Speed index.
    n_steps : int
        Steps of each simulation.
    mode : int
        0-based mode deflected at the start.
    deflection : float
        Its deflection.
    max_extensions : int
        Continuations at most.
    **loop
        The loop's other settings (``convective_V0``, ``hold``).

    Returns
    -------
    LoopSimulation
        The last simulation; ``kind`` says whether it settled (``"lco"``), decayed or still
        grows.
    """
    xs0 = structure.displaced_state(mode, deflection)
    for _ in range(int(max_extensions) + 1):
        sim = simulate_loop(rom, structure, V, n_steps, xs0=xs0, **loop)
        if sim.stopped_early or sim.modes.kind != "divergence":
            break
        xs0 = sim.xs[-1]
    return sim


@dataclass(frozen=True)
class LcoComparison:
    """The speed-following ROM's LCO and the wing's at one speed (:func:`compare_lco`).

    Attributes
    ----------
    speed_factor : float
        ``V`` over the wing's flutter speed.
    V : float
        Speed index.
    rom : LoopSimulation
        The ROM loop's established response.
    truth : TruthLco
        The wing's.
    """

    __repr__ = result_repr

    speed_factor: float
    V: float
    rom: LoopSimulation
    truth: TruthLco

    @property
    def rom_amplitude(self) -> np.ndarray:
        """Half peak-to-peak amplitude per sensor of the ROM loop."""
        return np.asarray(self.rom.sensors.amplitude, dtype=float)

    @property
    def comparable(self) -> bool:
        """Whether both responses are limit cycles (a diverging or decaying response has no
        amplitude to compare)."""
        return self.rom.sensors.kind == "lco" and self.truth.kind == "lco"

    @property
    def amplitude_error_percent(self) -> np.ndarray:
        """``100 (rom / truth − 1)`` per sensor; NaN unless both are limit cycles."""
        if not self.comparable:
            return np.full(self.rom_amplitude.shape, np.nan)
        return 100.0 * (self.rom_amplitude / np.asarray(self.truth.amplitude, float) - 1.0)

    def describe_error(self) -> str:
        """``"+3.1 %, -2.0 %"`` per sensor, or what the two responses are when they are not
        both limit cycles (``"ROM divergence, truth lco"``)."""
        if not self.comparable:
            return f"ROM {self.rom.sensors.kind}, truth {self.truth.kind}: no amplitudes to compare"
        return ", ".join(f"{e:+.1f} %" for e in self.amplitude_error_percent)

    def record(self) -> dict:
        """Plain numbers (``summary.json``).

        Returns
        -------
        dict
            ``speed_factor``, ``V``, ``rom_kind``, ``truth_kind``, ``rom_amplitude``,
            ``truth_amplitude``, ``amplitude_error_percent`` (per sensor), ``rom_freq_hz``,
            ``truth_freq_hz``.  A model's amplitudes and frequency are its cycle's: ``None``
            where its response is a decay or a divergence.
        """
        rom_cycle, truth_cycle = self.rom.sensors.kind == "lco", self.truth.kind == "lco"
        return {"speed_factor": self.speed_factor, "V": self.V,
                "rom_kind": self.rom.sensors.kind, "truth_kind": self.truth.kind,
                "rom_amplitude": self.rom_amplitude.tolist() if rom_cycle else None,
                "truth_amplitude": list(self.truth.amplitude) if truth_cycle else None,
                "amplitude_error_percent": [None if not np.isfinite(e) else float(e)
                                            for e in self.amplitude_error_percent],
                "rom_freq_hz": float(self.rom.sensors.frequency_hz) if rom_cycle else None,
                "truth_freq_hz": float(self.truth.freq_hz) if truth_cycle else None}


def compare_lco(rom: SpeedFollowingROM, truth, V_flutter: float, speed_factors, *,
                duration: float, mode: int, deflection: float, dt: float,
                truth_lcos=None, max_extensions: int = 5) -> tuple[LcoComparison, ...]:
    """The speed-following ROM loop's established LCO beside the wing's, at multiples of the
    wing's flutter speed, on the ROM's sensors.

    Parameters
    ----------
    rom : SpeedFollowingROM
        The ROM (its nonlinear loop, stepped at ``dt V0 / V`` with its hold).
    truth : AeroelasticTruth
        The wing.
    V_flutter : float
        The wing's flutter speed index.
    speed_factors : sequence of float
        Multiples of ``V_flutter`` (> 0).
    duration : float
        Length of each simulation [s] (both are continued while they grow).
    mode : int
        0-based mode deflected at the start.
    deflection : float
        Its deflection.
    dt : float
        Output sample time of the truth's simulations [s].
    truth_lcos : mapping of float to TruthLco, optional
        The wing's established responses by speed factor, where already computed.
    max_extensions : int
        Continuations at most.

    Returns
    -------
    tuple of LcoComparison

    Raises
    ------
    ConfigError
        A speed factor that is not > 0.
    """
    factors = [float(f) for f in speed_factors]
    if not factors or not all(np.isfinite(f) and f > 0 for f in factors):
        raise ConfigError(f"speed_factors = {list(speed_factors)!r}: multiples of the flutter "
                          "speed, each > 0")
    known = dict(truth_lcos or {})
    st = rom.structure
    out = []
    for f in factors:
        V = f * float(V_flutter)
        n = max(2, int(round(duration / rom.sample_time(V))))
        sim = established_loop_lco(rom.model, st, V, n, mode, deflection,
                                   max_extensions=max_extensions, convective_V0=rom.V0,
                                   hold=rom.hold)
        tr = known.get(f)
        if tr is None:
            tr = truth_lco(truth, V, duration, mode, deflection, dt=dt, sensor_rows=st.Hs,
                           sensor=st.sensor, max_extensions=max_extensions)
        out.append(LcoComparison(f, V, sim, tr))
    return tuple(out)
