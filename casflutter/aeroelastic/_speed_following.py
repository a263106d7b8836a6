"""A ROM that follows the wing over speed, from records at one speed (reduced frequency).

The paper closes the ROM identified at ``V0`` as eq. 8: the aerodynamic forces scaled by
``V²``, their dynamics frozen at ``V0``.  Unsteady aerodynamics depend on the reduced
frequency ``k = ω b / U``: the same flow at another speed runs on a time axis scaled by
``U / U0``.  The ROM that follows the wing keeps the identified model and scales its time
(``/work/shared/notes/multispeed.md``, "Reduced frequency"):

- the linear loop ΣAE(V) with Σf's ``Af, Bf, bf`` times ``V / V0``
  (:class:`~casflutter.aeroelastic.AeroelasticSystem` ``convective_V0``), for flutter,
  residues and design;
- the nonlinear loop with the HWL recursion stepped at ``dt · V0 / V``
  (:func:`~casflutter.aeroelastic.simulate_loop` and :func:`casflutter.lco.rom_loop_map`
  with ``convective_V0``), for the LCO.

Two more things separate the paper's loop from the wing, and both are left out here:

- *The records' coupling delay.*  A loosely coupled CFD time march computes the flow of
  step ``k`` on the grid of step ``k − 1``, so the recorded forces lag the motion by one
  sample and the ROM's input delay ``r`` holds that lag (Table I: ``r = 1``).  It is the
  solver's, not the flow's: the wing in the tunnel has none.  Kept, it is a phase lag
  ``ω dt`` on the aerodynamic forces that the lightly damped flutter mode feels strongly;
  :meth:`casflutter.ident.HWLModel.advanced` removes it.
- *The force's hold between samples.*  In the nonlinear loop a zero-order hold delays the
  force by half a step; the predictive first-order hold cancels that to first order
  (:func:`~casflutter.aeroelastic.simulate_loop`, ``hold = "foh"``), so the sampled loop
  flutters where its continuous ΣAE does.

Σf is realised at its exact order (``"auto"``): the truncation to Table I's ``nf = 15``
moves the flutter speed by several per cent on its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ..ident import HWLModel
from ..realize import realize
from ..structure import ModalStructure
from ._flutter import FlutterResult, find_flutter
from ._loop import AeroelasticSystem
from ._residues import ControlReversal, control_reversal
from ._simulate import check_hold, loop_sample_time

__all__ = ["SpeedFollowingROM", "speed_following_rom"]


@dataclass(frozen=True)
class SpeedFollowingROM:
    """A ROM identified at ``V0`` whose aerodynamic time scale follows the speed
    (module docstring), as a linear family and as a nonlinear loop.

    Attributes
    ----------
    model : HWLModel
        The identified ROM without the records' coupling delay (the nonlinear loop's ROM).
    V0 : float
        The identification speed index.
    system : AeroelasticSystem
        ΣAE(V) of the linearised ``model`` at its exact order, Σf's dynamics scaled by
        ``V / V0`` (eq. 8 with the reduced-frequency scaling).
    flutter : FlutterResult
        The flutter search of ``system``.
    coupling_delay : int
        Samples of delay removed from the identified ROM.
    hold : str
        The force's hold of the nonlinear loop (``"foh"``: predictive first-order).
    """

    __repr__ = result_repr

    model: HWLModel
    V0: float
    system: AeroelasticSystem
    flutter: FlutterResult
    coupling_delay: int = 0
    hold: str = "foh"

    @property
    def structure(self) -> ModalStructure:
        """Σs of the loop."""
        return self.system.structure

    def sample_time(self, V: float) -> float:
        """The nonlinear loop's step at speed index V, ``dt · V0 / V`` [s].

        Parameters
        ----------
        V : float
            Speed index (> 0).

        Returns
        -------
        float
        """
        return float(loop_sample_time(float(self.model.dt), float(V), self.V0))

    def control_reversal(self, speeds, servo_omega: float,
                         servo_zeta: float = 0.7) -> ControlReversal | None:
        """The flutter mode's control reversal of ``system`` with the flap behind a servo
        (:func:`~casflutter.aeroelastic.control_reversal`).

        Parameters
        ----------
        speeds : array_like
            Increasing speed indices of the scan.
        servo_omega, servo_zeta : float
            The servo (rad/s, damping ratio).

        Returns
        -------
        ControlReversal or None
        """
        return control_reversal(self.system.with_servo(servo_omega, servo_zeta), speeds)


def speed_following_rom(model: HWLModel, structure: ModalStructure, V0: float, *,
                        coupling_delay: int = 0, order: int | str = "auto",
                        V_range=(0.3, 2.5), n_grid: int = 111, max_refine: int = 3,
                        hold: str = "foh") -> SpeedFollowingROM:
    """The ROM that follows the wing over speed (module docstring), and its flutter.

    Parameters
    ----------
    model : HWLModel
        The ROM identified from records at ``V0``.
    structure : ModalStructure
        Σs (eq. 7) with the run's sensors.
    V0 : float
        The records' speed index.
    coupling_delay : int
        Samples by which the records' forces lag the motion
        (:attr:`casflutter.truth.RecordSettings.coupling_delay`); removed from the ROM.
    order : int or "auto"
        Order of Σf (:func:`casflutter.realize.realize`); ``"auto"`` the exact order.
    V_range, n_grid, max_refine :
        The flutter search (:func:`~casflutter.aeroelastic.find_flutter`).
    hold : {"zoh", "foh"}
        The force's hold in the nonlinear loop.

    Returns
    -------
    SpeedFollowingROM

    Raises
    ------
    ConfigError
        ``V0`` not > 0, an unknown hold, or a coupling delay the ROM's input delay does not
        hold (:meth:`~casflutter.ident.HWLModel.advanced`).

    See Also
    --------
    control_reversal : the flutter mode's control reversal on ``system``.
    casflutter.lco.compare_lco : the nonlinear loop's LCO beside the wing's.

    Examples
    --------
    The typical section's records at V0 = 1.8: eq. 8's frozen loop flutters 4 % above the
    truth, the speed-following one with it.

    >>> import casflutter as cf
    >>> from casflutter.aeroelastic import speed_following_rom
    >>> truth = cf.load_problem("typical_section")
    >>> data = cf.truth_records(truth, V0=1.8, dt=0.1, duration=60.0, band=(0.002, 1.0))
    >>> rom = cf.identify_common_denominator(data).model
    >>> frozen = cf.AeroelasticSystem.from_parts(cf.realize(rom).sigma_f,
    ...                                          truth.modal_structure())
    >>> sf = speed_following_rom(rom, truth.modal_structure(), 1.8, V_range=(0.5, 3.0))
    >>> [round(fl.Vf, 3) for fl in (cf.find_flutter(frozen, (0.5, 3.0)), sf.flutter,
    ...                             cf.find_flutter(truth, (0.5, 3.0)))]
    [2.259, 2.17, 2.17]
    """
    if isinstance(V0, bool) or not isinstance(V0, (int, float, np.floating)) or not (
            np.isfinite(V0) and V0 > 0):
        raise ConfigError(f"V0 = {V0!r}: the records' speed index (> 0)")
    check_hold(hold)
    try:
        rom = model.advanced(coupling_delay)
    except ValueError as exc:
        raise ConfigError(f"coupling_delay: {exc}") from None
    sigma_f = realize(rom, order).sigma_f
    system = AeroelasticSystem.from_parts(sigma_f, structure, warn_unstable=False,
                                          convective_V0=float(V0))
    flutter = find_flutter(system, tuple(V_range), n_grid=n_grid, max_refine=max_refine)
    return SpeedFollowingROM(rom, float(V0), system, flutter, int(coupling_delay), hold)
