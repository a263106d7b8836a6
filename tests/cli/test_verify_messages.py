"""``casflutter verify`` says what its numbers are (dV = V² - Vf², the airspeed when the
plant file has the scale), refuses two files given the wrong way round before any work, and
``verify_controller`` takes the :class:`~casflutter.verify.PlantData` that ``load_plant``
returns."""

import json

import control
import pytest

from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.verify import (controller_to_json, load_plant, plant_to_json,
                               verify_controller)

#: a first-order unstable plant whose ΔV channel is its first input/output, K = -3
P = control.ss([[1.0]], [[1.0, 1.0]], [[1.0], [1.0]], [[0.0, 0.0], [0.0, 0.0]])
K = control.ss([], [], [], [[-3.0]])


@pytest.fixture()
def files(tmp_path):
    plant = plant_to_json(P, 1, 1, Vf=1.0, n_delta=1)
    plant.update(format="casflutter-plant/1",
                 Vf_speeds={"speed_index": 1.0, "airspeed_m_s": 28.9})   # as run writes it
    ctrl = dict(controller_to_json(K), format="casflutter-controller/1")
    p, k = tmp_path / "plant.json", tmp_path / "controller.json"
    p.write_text(json.dumps(plant))
    k.write_text(json.dumps(ctrl))
    return str(p), str(k)


def test_the_report_says_what_dv_is_and_gives_the_airspeed(files, capsys):
    assert main(["verify", *files]) == 0
    out = capsys.readouterr().out
    assert "dV = V² - Vf² (eq. 10)" in out
    rep = verify_controller(P, K, 1, 1, Vf=1.0, n_delta=1)
    lo, hi = rep.exact_V
    assert f"U in ({28.9 * lo:.6g}, {28.9 * hi:.6g}) m/s" in out
    assert "Vf = 1 (U = 28.9 m/s)" in out


def test_swapped_files_are_refused_before_any_work(files, capsys):
    plant, ctrl = files
    assert main(["verify", ctrl, plant]) == 1
    err = capsys.readouterr().err
    assert "look swapped" in err and f"casflutter verify {plant} {ctrl}" in err
    assert main(["verify", ctrl, ctrl]) == 1
    assert "is a controller file" in capsys.readouterr().err


def test_verify_controller_takes_the_loaded_plant_file(files):
    data = load_plant(files[0])
    a = verify_controller(data, K)
    b = verify_controller(P, K, 1, 1, Vf=1.0, n_delta=1)
    assert a.gamma == b.gamma and a.exact_V == b.exact_V and a.Vf == 1.0
    assert verify_controller(data, K, Vf=None, n_delta=None).Vf == 1.0   # the file's channel
    with pytest.raises(ConfigError, match="number of measurements and controls"):
        verify_controller(P, K)


@pytest.mark.parametrize("extra, named", [
    (["--range", "0.5", "1.5"], "--range"), (["--disk"], "--disk"),
    (["--servo", "250"], "--servo"), (["--margins", "3", "30"], "--margins"),
])
def test_family_options_on_a_single_plant_are_refused_not_ignored(files, capsys, extra, named):
    """The family route's options mean nothing to a single LFT plant: refused by name, where
    they were silently ignored."""
    assert main(["verify", *files, *extra]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"casflutter: error: {named} belong to a plant family") and \
        "drop them" in err
