"""``load_config(updates=...)``: dotted-path changes on top of a run configuration, checked by
the same validation as the file itself (the hook the ``pipeline`` sweep evaluator uses)."""

import pytest

from casflutter.errors import ConfigError
from casflutter.pipeline import default_config_path, load_config


def test_dotted_updates_reach_their_sections_and_keep_the_rest():
    base = load_config()
    cfg = load_config(updates={"controller.order": 4, "rom.orders": [2, 1, 1, 1, 2, 2],
                               "problem.set.zeta": 0.03, "problem.set": {"rho": 1.2},
                               "solver.ipopt.ipopt.tol": 1e-7, "data": {"V0": 0.7},
                               "seed": 5})
    assert cfg.controller.order == 4 and cfg.rom.orders == [2, 1, 1, 1, 2, 2]
    assert cfg.problem.set == {"zeta": 0.03, "rho": 1.2}
    assert cfg.solver.ipopt == {"ipopt.tol": 1e-7}  # the key keeps its own dots
    assert cfg.data.V0 == 0.7 and cfg.seed == 5
    # everything not named is the file's value
    assert cfg.controller.starts == base.controller.starts
    assert cfg.data.dt == base.data.dt and cfg.rom.nf == base.rom.nf
    # the default path is the same file
    assert load_config(default_config_path()) == base


@pytest.mark.parametrize("updates, words", [
    ({"controller.ordr": 1}, ["'ordr'", "[controller]", "order", "max_outer"]),
    ({"contrlr.order": 1}, ["'contrlr'", "top level", "controller", "suppression"]),
    ({"seed.x": 1}, ["'seed.x'", "single value"]),
    ({"controller.order": 1.5}, ["controller.order", "integer"]),
    ({"problem.set.zet": 0.1}, ["problem.set", "'zet'", "zeta_lateral"]),
    ({"problem.set.zeta": -0.1}, ["problem.set", "zeta", ">= 0"]),
])
def test_unknown_or_invalid_updates_name_the_key(updates, words):
    with pytest.raises(ConfigError) as info:
        load_config(updates=updates)
    for w in words:
        assert w in str(info.value)


def test_problem_set_in_the_file_is_checked_at_load(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text('[problem]\nname = "seed_wing"\nset = {modal_mas = 1.0}\n')
    with pytest.raises(ConfigError, match="problem.set: unknown parameter 'modal_mas'"):
        load_config(path)
    # the same file with the name corrected loads, and an update overrides the file's value
    path.write_text('[problem]\nname = "seed_wing"\nset = {modal_mass = 1e-3}\n')
    assert load_config(path).problem.set == {"modal_mass": 1e-3}
    assert load_config(path, updates={"problem.set.modal_mass": 2e-3}).problem.set == {
        "modal_mass": 2e-3}
