"""The paper's design on a ROM whose time scales with V (``problems/seed_wing/convective.toml``).

Truth used: the exact stable interval of the wing's own linearisation closed by the same
controller (``RunResult.truth_stable_V``, :class:`casflutter.aeroelastic.TruthLoop`), and
eigenvalues of the scaled ROM loop computed here.  The tolerance, 1 % of the interval, is the
flutter-speed error of the convective ROM (0.4 %) with room; measured 0.09 %.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.pipeline import config_path, load_config, run


@pytest.fixture(scope="module")
def result():
    cfg = load_config(config_path("seed_wing", "convective"),
                      updates={"verify.required": [0.05, 1.15]})
    return run(cfg, quiet=True, write=False)


def test_the_rom_interval_is_the_wings(result):
    rom, wing = result.rom_stable_V, result.truth_stable_V
    assert result.convective_V0 == result.config.data.V0
    assert rom[0] == wing[0] == 0.0
    assert abs(rom[1] / wing[1] - 1) < 0.01          # 1.2850 vs 1.2838
    # the LFT frozen at Vf says something else about the same controller
    frozen = result.verification.exact_V
    assert abs(frozen[1] / wing[1] - 1) > 0.05           # 1.405


def test_the_interval_is_the_scaled_loops_with_the_servo(result):
    """``controlled_rom`` (the family Fig. 10 draws) is the loop the certificate is about."""
    K, upper = result.controller, result.rom_stable_V[1]
    family = result.controlled_rom
    assert family.servo_omega == result.config.controller.servo_omega
    # the flap's position and rate are two more states than ΣAE(V)
    assert family.state_matrix(1.0).shape[0] == result.system.state_matrix(1.0).shape[0] + 2
    for V in np.linspace(0.05, 0.995 * upper, 12):
        assert np.max(np.linalg.eigvals(family.closed_loop_state_matrix(V, K)).real) < 0, V
    assert np.max(np.linalg.eigvals(family.closed_loop_state_matrix(1.01 * upper, K)).real) > 0


def test_the_summary_and_the_target_use_the_scaled_loop(result):
    c = result.summary()["controller"]
    assert c["method"] == "paper"
    assert c["stable_interval"] == list(result.rom_stable_V)
    assert c["lft_stable_V"] == list(result.verification.exact_V)
    assert c["servo_omega"] == result.config.controller.servo_omega
    assert result.interval_ok is True          # (0.05, 1.15) Vf inside (0, 1.285)


def test_stages_that_simulate_the_frozen_loop_are_refused():
    path = config_path("seed_wing", "convective")
    for stage in ("lco", "suppression"):
        with pytest.raises(ConfigError, match=f"rom.convective.*'{stage}'"):
            load_config(path, updates={"stages": ["controller", stage]})
    with pytest.raises(ConfigError, match="verify.sweep"):
        load_config(path, updates={"verify.sweep": [0.5, 2.0]})


@pytest.mark.parametrize("updates, match", [
    ({"controller.method": "hifoo"}, "controller.method = 'hifoo': allowed 'auto'"),
    ({"controller.method": "multispeed", "controller.order": 0}, "order >= 1"),
    ({"controller.method": "multispeed", "rom.convective": False},
     "set rom.convective = true"),
    ({"controller.interval": [2.4, 0.05]}, "0 <= lo < hi"),
    ({"controller.reduction_orders": [8, "six"]}, "reduction_orders"),
])
def test_the_multispeed_design_is_refused_where_it_cannot_work(updates, match):
    with pytest.raises(ConfigError, match=match):
        load_config(config_path("seed_wing", "convective"), updates=updates)


def test_the_multispeed_design_holds_the_scaled_loop_and_the_wing():
    """``controller.method = "multispeed"`` on the scaled ROM loop (servo in front of the
    flap) over (0.05, 1.45), 34 % above the flutter speed, at order 3: the design holds the
    interval and the verification layer certifies it on the ROM loop and on the wing."""
    cfg = load_config(config_path("seed_wing", "convective"), updates={
        "controller.method": "multispeed", "controller.interval": [0.05, 1.45],
        "controller.order": 3, "controller.hinf_speeds": 0, "controller.random_starts": 1})
    res = run(cfg, quiet=True, write=False)
    assert res.synthesis is None and res.controller.nstates == 3
    assert res.design.held
    rom, wing = res.rom_stable_V, res.truth_stable_V
    assert rom[0] == 0.0 and rom[1] >= 1.45
    assert wing[0] == 0.0 and wing[1] >= 1.45        # certified on the wing too
    c = res.summary()["controller"]
    assert c["order"] == 3 and c["held"] is True and c["interval"] == [0.05, 1.45]
    assert np.isfinite(c["gamma"])                          # measured by the verification


def test_a_run_whose_check_fails_writes_its_outputs_and_exits_3(tmp_path, capsys):
    """The paper's order-3 design holds the wing to 1.19 Vf: a target of 2.2 Vf fails."""
    from casflutter.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text(config_path("seed_wing", "convective").read_text()
                   + "\n[verify]\nrequired = [0.05, 2.2]\n")
    out = tmp_path / "out"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 3
    s = json.loads((out / "summary.json").read_text())
    assert s["verification"]["interval_ok"] is False and s["verification"]["success"] is False
    assert "a check failed" in capsys.readouterr().err
