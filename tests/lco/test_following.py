"""The LCO of the ROM that follows the wing over speed beside the wing's own.

Truth used: the seed wing's own nonlinear simulation (its established LCO, continued while it
grows), on the same accelerometers.  Target of issue 32: the ROM's LCO amplitude within 15 %
of the wing's at 1.05 times the wing's flutter speed.  (At 1.2 times it the ROM's LCO is 40 %
smaller: its polynomial nonlinearity, fitted on single-mode chirps 40 times smaller than the
LCO, does not carry that far; the report says so beside the numbers.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casflutter.aeroelastic import find_flutter, speed_following_rom
from casflutter.errors import ConfigError
from casflutter.ident import HWLModel
from casflutter.lco import compare_lco
from casflutter.truth import SeedWing

ROM = Path(__file__).resolve().parents[2] / "problems" / "seed_wing_rom" / "rom.npz"


@pytest.mark.slow
def test_the_speed_following_lco_is_the_wings_just_above_flutter():
    truth = SeedWing()
    sensors = truth.modal_structure().with_sensors(kind="acceleration")
    sf = speed_following_rom(HWLModel.load(ROM), sensors, 0.69, coupling_delay=1)
    Vw = find_flutter(truth, (0.3, 2.5), n_grid=111, max_refine=3).Vf
    (c,) = compare_lco(sf, truth, Vw, [1.05], duration=10.0, mode=1, deflection=0.01,
                       dt=0.002)
    assert c.V == pytest.approx(1.05 * Vw)
    assert c.truth.kind == "lco" and c.rom.sensors.kind == "lco"
    assert np.all(np.abs(c.amplitude_error_percent) < 15.0)
    assert c.rom.sensors.frequency_hz == pytest.approx(c.truth.freq_hz, rel=0.03)
    assert c.record()["amplitude_error_percent"] == list(c.amplitude_error_percent)


def test_speed_factors_must_be_positive():
    with pytest.raises(ConfigError, match="speed_factors"):
        compare_lco(None, None, 1.0, [1.05, 0.0], duration=1.0, mode=0, deflection=0.01,
                    dt=0.002)


def test_a_diverging_rom_has_no_amplitude_error():
    """A ROM loop that diverges (amplitudes of 1e11) beside a truth that settles: no
    percentage, which would read +4e13 %, but what each response is."""
    from types import SimpleNamespace as NS

    from casflutter.lco import LcoComparison

    c = LcoComparison(speed_factor=1.2, V=1.3,
                      rom=NS(sensors=NS(kind="divergence", amplitude=[2e11, 9e11],
                                        frequency_hz=0.053)),
                      truth=NS(kind="lco", amplitude=[4.4, 3.0], freq_hz=2.68))
    assert not c.comparable and np.all(np.isnan(c.amplitude_error_percent))
    assert c.record()["amplitude_error_percent"] == [None, None]
    assert c.describe_error().startswith("ROM divergence, truth lco")
