"""``casflutter flutter`` and ``casflutter problems`` on a plant family file: the JSON keys
and units, every crossing lowest first, the figure, --vrange, refused options.

Truth used: :func:`casflutter.aeroelastic.family_flutter` on the loaded family (the command
must report what the library finds, in the family's units).
"""

from __future__ import annotations

import json
import re

import pytest
from numpy.testing import assert_allclose

from casflutter._resources import problems_dir
from casflutter.aeroelastic import family_flutter, load_family
from casflutter.cli import main

FAMILY = str(problems_dir() / "goland_4flaps" / "problem_mat.toml")


def _json(capsys, *argv):
    assert main(list(argv)) == 0
    return json.loads(capsys.readouterr().out)


def test_json_lists_every_crossing_in_the_family_units_and_draws_the_figure(tmp_path, capsys):
    fig = tmp_path / "vg.png"
    doc = _json(capsys, "flutter", FAMILY, "--json", "--figure", str(fig))
    want = family_flutter(load_family(FAMILY))
    assert doc["kind"] == "plant_family" and doc["problem"] == "goland_4flaps"
    assert all(set(c) >= {"speed", "omega_rad_s", "freq_hz", "branch"} for c in doc["flutter"])
    assert len(doc["flutter"]) == len(want.crossings) >= 1
    assert_allclose([c["speed"] for c in doc["flutter"]], [c.V for c in want.crossings],
                    rtol=1e-12)
    assert_allclose([c["omega_rad_s"] for c in doc["flutter"]],
                    [c.omega for c in want.crossings], rtol=1e-12)
    assert [c["speed"] for c in doc["flutter"]] == sorted(c["speed"] for c in doc["flutter"])
    assert doc["flutter_speed"] == doc["flutter"][0]["speed"]
    assert_allclose(doc["flutter_freq_hz"] * 2 * 3.141592653589793,
                    doc["flutter_omega_rad_s"], rtol=1e-12)
    assert doc["units"] == {"speed": "m/s", "omega_rad_s": "rad/s", "freq_hz": "Hz"}
    assert doc["speed_range"] == [60.0, 200.0] and doc["warnings"] == []
    assert fig.is_file() and fig.stat().st_size > 10_000 and doc["figure"] == str(fig)


def test_vrange_and_text_output(capsys):
    doc = _json(capsys, "flutter", "seed_wing_family", "--vrange", "0.7", "1.0", "--json")
    assert doc["flutter"] == [] and doc["status"] == "no_crossing"
    assert doc["speed_range"] == [0.7, 1.0] and doc["units"]["speed"] == "speed index"
    assert main(["flutter", "seed_wing_family"]) == 0
    out = capsys.readouterr().out
    assert "flutter, destabilizing" in out and "speed index" in out


@pytest.mark.parametrize("argv, match", [
    (["--v0", "100"], "--v0 does not apply to the plant family"),
    (["--convective"], "--convective does not apply"),
    (["--set", "mu=3"], "no parameters to --set"),
    (["--vrange", "10", "100"], "outside the range"),
])
def test_options_that_do_not_apply_are_refused(argv, match, capsys):
    assert main(["flutter", "goland_4flaps", *argv]) == 1
    err = capsys.readouterr().err
    assert re.search(match, err) and "Traceback" not in err


def test_problems_describes_the_family(capsys):
    (info,) = _json(capsys, "problems", "goland_4flaps", "--json")
    assert info["kind"] == "plant_family" and info["n_states"] == 50
    assert [r["role"] for r in info["inputs"]] == ["control"] * 4
    assert [r["unit"] for r in info["outputs"]][:2] == ["rad/s", "rad/s"]
    assert info["speeds"] == {"min": 60.0, "max": 200.0, "count": 41,
                              "interpolation": "linear"}
    assert "flutter" in info["reference"]
    assert main(["problems", str(problems_dir() / "seed_wing_family")]) == 0
    out = capsys.readouterr().out
    assert "w[0] [] (disturbance)" in out and "plant family: 32 states" in out
