"""The truth's own free response above its flutter speed: its limit-cycle oscillation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..data import ResponseAnalysis, analyze_response
from ..errors import ConfigError

__all__ = ["TruthLco", "truth_lco"]


@dataclass(frozen=True)
class TruthLco:
    """Outcome of :func:`truth_lco`.

    Attributes
    ----------
    V : float
        Speed index.
    kind : str
        ``"decay"``, ``"lco"`` or ``"divergence"`` (of the sensors).
    freq_hz : float
        Fundamental frequency [cycles per time unit].
    amplitude : tuple of float
        Half peak-to-peak amplitude per sensor.
    timepts : ndarray
        Times of the returned history (``t_start`` is added to get the simulation time).
    zm : ndarray, shape (K, n_sensors)
        Sensor readings.
    analysis : ResponseAnalysis
        Of the sensors.
    t_start : float
        Where the returned history begins in the simulation.
    final_state : ndarray or None
        The truth's full state at the end (on the LCO when ``kind == "lco"``): where a
        suppression run starts from the established LCO.
    """

    __repr__ = result_repr

    V: float
    kind: str
    freq_hz: float
    amplitude: tuple
    timepts: np.ndarray
    zm: np.ndarray
    analysis: ResponseAnalysis
    t_start: float
    final_state: np.ndarray | None = None


def truth_lco(truth, V: float, duration: float, mode: int, deflection: float, *,
              dt: float, sensor_rows=None, sensor: str = "acceleration",
              max_extensions: int = 5) -> TruthLco:
    """The truth's own response at V from a deflected mode (its LCO, if any).

    Just above the Hopf point an LCO grows slowly: while the modal displacements of the last
    ``duration`` are still classified as growing (a test that does not depend on the
    sensors), the simulation is continued from its final state (at most ``max_extensions``
    times); the returned history is the last ``duration`` and ``t_start`` says where it
    begins.

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator.
    V : float
        Speed index.
    duration : float
        Length of each simulation.
    mode : int
        0-based mode deflected at the start.
    deflection : float
        Its deflection.
    dt : float
        Output sampling time.
    sensor_rows : array_like, optional
        ``Hs`` (default: the truth's own).
    sensor : {"acceleration", "velocity", "displacement"}
        What the sensors read: ``Hs u''``, ``Hs u'`` or ``Hs u``.
    max_extensions : int
        Largest number of continuations.

    Returns
    -------
    TruthLco

    See Also
    --------
    lco_branch : the whole LCO branch by continuation.
    analyze_response : the classification of the response.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section", ["kappa2=3"])
    >>> cf.truth_lco(truth, 2.4, 400.0, mode=1, deflection=0.05, dt=0.1).kind
    'lco'
    """
    motion = {"acceleration": "uddot", "velocity": "udot", "displacement": "u"}
    if sensor not in motion:
        raise ConfigError(f"sensor={sensor!r}: use one of {', '.join(motion)}")
    t = np.arange(0.0, duration, dt)
    x0 = truth.displaced_state(mode, deflection)
    rows = truth.modal_structure().with_sensors(sensor_rows).Hs
    t_start = 0.0
    for k in range(max_extensions + 1):
        sim = truth.simulate(t, x0, V)
        growing = analyze_response(t, sim.u).kind == "divergence"
        if not growing or not np.all(np.isfinite(sim.states[-1])) or k == max_extensions:
            break
        x0, t_start = sim.states[-1], t_start + t[-1]
    zm = getattr(sim, motion[sensor]) @ rows.T
    an = analyze_response(t, zm)
    return TruthLco(V=float(V), kind=an.kind, freq_hz=float(an.frequency_hz),
                    amplitude=tuple(float(a) for a in an.amplitude), timepts=t, zm=zm,
                    analysis=an, t_start=t_start, final_state=np.array(sim.states[-1]))
