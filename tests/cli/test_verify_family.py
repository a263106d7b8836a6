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


def test_the_figure_goes_into_a_folder_that_does_not_exist_yet(family_and_file, tmp_path):
    """R3: ``--figure DIR/fig.png`` with DIR missing is written (as ``flutter --figure``),
    not an internal error after the certificate."""
    fam, path = family_and_file
    figure = tmp_path / "new" / "sub" / "margins.png"
    rc, text = _run(verify_command, fam, path, figure=figure)
    assert rc == 0 and "PASSED" in text
    assert figure.stat().st_size > 10_000
    assert sorted(p.name for p in figure.parent.iterdir()) == ["margins.png"]


@pytest.mark.parametrize("speed_range, words", [
    ((0.8, 0.2), "--range 0.8 0.2: LO must be below HI; give --range 0.2 0.8"),
    ((0.5, 0.5), "--range 0.5 0.5: LO must be below HI; give two different speeds"),
    ((0.2, float("inf")), "--range 0.2 inf: give two finite speeds LO < HI (q)"),
    ((0.01, 0.8), "--range LO = 0.01 q is outside the range [0.1, 1.5]"),
])
def test_a_bad_range_names_the_option_not_the_python_keyword(family_and_file, speed_range,
                                                             words):
    fam, path = family_and_file
    with pytest.raises(ConfigError) as err:
        verify_command(fam, path, speed_range=speed_range)
    assert words in str(err.value) and "speed_range" not in str(err.value)


def test_a_loop_family_without_range_is_told_to_pass_it(capsys):
    rc = main(["verify", str(ROM_LOOP), str(WITNESSES / "rom_order4_low_controller.json"),
               "--servo", "251.3"])
    err = capsys.readouterr().err.strip()
    assert rc == 1 and "\n" not in err and err.startswith("casflutter: error: ")
    assert "pass --range LO HI" in err and "speed_range" not in err


def test_require_v_help_says_what_each_route_requires(capsys):
    with pytest.raises(SystemExit):
        main(["verify", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    start = text.index("--require-v LO HI ")
    help_ = text[start:text.index("--json", start)]
    # the LFT route: the exact interval, stability only; the family route: the margins too
    assert "exact interval, eq. 10-15" in help_ and "no margins" in help_
    assert "certified stable interval must cover [LO, HI]" in help_
    assert "--margins thresholds" in help_ and "--disk" in help_
    assert "from the start of the verified range" in help_


def test_margins_failing_below_the_required_range_are_said_so(family_and_file):
    """The margins are held from the verified range's start, not from LO: a failure below LO
    fails the verdict, and the reason says where (not "inside the required" range)."""
    from casflutter.cli._verify_family import verdict
    from casflutter.verify import verify_family

    fam, path = family_and_file
    result = verify_family(fam, str(path))
    rfs = result.robust_flutter_speed
    assert 0.8 < rfs < 0.84
    v = verdict(result, (0.84, 0.85))
    assert v["covered"] is True and v["passed"] is False
    assert "inside" not in v["reason"]
    assert (f"below the required [0.84, 0.85]: the margins must hold from the verified "
            f"range's start, 0.1 q, up to 0.85") in v["reason"]
    assert "inside the required [0.1, 0.85]" in verdict(result, (0.1, 0.85))["reason"]
