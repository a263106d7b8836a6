"""One controller for two models of the seed wing over the paper's V ∈ (0, 2.4).

``tests/witnesses/rom_and_truth_interval_controller_order5.json`` was found by the interval
continuation over two loop families at once (see its ``about``): the ROM loop of a linear ROM
identified from the truth's records at V0 = 0.69 alone (time scaled by V/V0), and the wing's
own linearisation, both with the flap behind the 40 Hz servo.  Truth used: the verification
layer's exact stable interval of each loop (polynomial guardian map, python-control closes
the loop), which shares no code with the continuation.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from casflutter.aeroelastic import AeroelasticSystem, TruthLoop
from casflutter.truth import SeedWing
from casflutter.verify import load_controller, speed_family_interval

#: the test witnesses (tests/witnesses/README.md): inputs of the tests, each certified here
WITNESS_DIR = Path(__file__).resolve().parents[1] / "witnesses"

SERVO = 251.3       # rad/s, the seed wing's 40 Hz servo
V0 = 0.69           # the paper's identification speed (Table I)


@pytest.fixture(scope="module")
def families(seed_wing_sigma_f):
    truth = SeedWing()
    rom = AeroelasticSystem.from_parts(seed_wing_sigma_f, truth.modal_structure(),
                                       convective_V0=V0).with_servo(SERVO)
    return {"rom": rom, "wing": TruthLoop(truth, SERVO)}


@pytest.mark.parametrize("model", ["rom", "wing"])
def test_the_order_5_controller_holds_both_models_over_the_paper_interval(families, model):
    K = load_controller(WITNESS_DIR / "rom_and_truth_interval_controller_order5.json")
    assert K.nstates == 5
    fam = families[model]
    cert = speed_family_interval(lambda V: fam.loop(V).flap_to_sensors(), K, V0)
    assert cert.lower == 0.0 and cert.upper >= 2.4          # measured 2.4003 on both
