"""``casflutter verify FAMILY CONTROLLER``: the family route (a family in memory through the
command's body, a ROM loop kept in an ``.npz`` through the command line, a family file when
the loader is installed), its verdict, JSON keys, figure and refusals."""

from __future__ import annotations

import contextlib
import io
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from casflutter.aeroelastic import write_family
from casflutter._resources import problems_dir
from casflutter.cli import main
from casflutter.cli._verify_family import verify_command
from casflutter.errors import ConfigError
from casflutter.verify import controller_to_json

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verify"))
from family_helpers import WITNESSES, random_family, small_controller  # noqa: E402

KEYS = {"stable_interval", "absolute_flutter_speed", "robust_flutter_speed", "margins",
        "crossings", "verdict", "speed_unit", "frequency_unit"}
ROM_LOOP = problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz"


@pytest.fixture(scope="module")
def family_and_file(tmp_path_factory):
    fam = random_family(4)
    K = small_controller(np.random.default_rng(104), 2, 2, 2, gain=0.3, with_d=False)
    doc = controller_to_json(K)
    doc["inputs"] = [{"name": "y0"}, {"name": "y1"}]
    doc["outputs"] = [{"name": "u0"}, {"name": "u1"}]
    path = tmp_path_factory.mktemp("famverify") / "K.json"
    path.write_text(json.dumps(doc))
    return fam, path


def _run(fn, *args, **kw):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = fn(*args, **kw)
    return rc, out.getvalue()


def test_the_verdict_follows_the_certified_interval_and_the_margins(family_and_file,
                                                                    tmp_path):
    fam, path = family_and_file
    rc, text = _run(verify_command, fam, path, require_v=(0.1, 0.8))
    assert rc == 0 and "PASSED" in text and "stable_interval: [0.1, 0.88" in text
    rc, text = _run(verify_command, fam, path, require_v=(0.1, 0.85))
    assert rc == 1 and "not robust" in text and "output 'y0': phase margin" in text
    rc, text = _run(verify_command, fam, path, require_v=(0.1, 0.9), json_out=True,
                    figure=tmp_path / "margins.png")
    doc = json.loads(text)
    assert rc == 1 and KEYS <= set(doc)
    assert doc["verdict"]["covered"] is False and "not covered" in doc["verdict"]["reason"]
    assert (tmp_path / "margins.png").stat().st_size > 10_000
    # looser thresholds: robust over the same range
    rc, _ = _run(verify_command, fam, path, require_v=(0.1, 0.85), margins=(1.0, 10.0))
    assert rc == 0


def test_a_required_range_outside_the_verified_one_is_refused(family_and_file):
    fam, path = family_and_file
    with pytest.raises(ConfigError, match="widen --range"):
        verify_command(fam, path, require_v=(0.1, 2.0))


def test_the_seed_wing_rom_loop_on_the_command_line():
    """The default run's ROM loop behind the wing's servo, with its order-4 'low' controller
    (designed to hold V in (0, 1.9033)): certified to there, so V up to 2.0 is not covered."""
    rc, text = _run(main, ["verify", str(ROM_LOOP),
                           str(WITNESSES / "rom_order4_low_controller.json"), "--servo", "251.3",
                           "--range", "0", "2.4", "--require-v", "0.5", "2.0", "--json"])
    doc = json.loads(text)
    assert rc == 1 and KEYS <= set(doc) and doc["speed_unit"] == "speed index"
    assert doc["stable_interval"]["upper"] == pytest.approx(1.9033, abs=1e-4)
    assert doc["verdict"]["covered"] is False


def test_options_of_the_other_route_are_refused(capsys):
    rc = main(["verify", str(ROM_LOOP),
               str(WITNESSES / "rom_order4_low_controller.json"), "--nmeas", "2"])
    assert rc == 1 and "--nmeas" in capsys.readouterr().err


def test_a_family_file(tmp_path):
    fam = random_family(4)
    write_family(fam, tmp_path / "fam.toml", fam.speeds)
    K = small_controller(np.random.default_rng(104), 2, 2, 2, gain=0.3, with_d=False)
    doc = controller_to_json(K)
    doc["inputs"], doc["outputs"] = ["y0", "y1"], ["u0", "u1"]
    (tmp_path / "K.json").write_text(json.dumps(doc))
    rc, text = _run(main, ["verify", str(tmp_path / "fam.toml"), str(tmp_path / "K.json"),
                           "--require-v", "0.1", "0.8", "--json"])
    assert rc == 0 and KEYS <= set(json.loads(text))
