"""``casflutter problems``: lists every problem with its parameters and reference values."""

from __future__ import annotations

import json

from casflutter.cli import main
from casflutter.truth import GolandParams, TypicalSectionParams, problem_names


def test_lists_all_problems_and_parameters(capsys):
    assert main(["problems"]) == 0
    out = capsys.readouterr().out
    for name in problem_names():
        assert name in out
    for cls in (TypicalSectionParams, GolandParams):
        for pname in cls.parameter_names():
            assert f"    {pname} " in out
    assert "137.2" in out and "2.17" in out


def test_json_and_set(capsys):
    assert main(["problems", "goland", "--json", "--set", "rho=1.02"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert [i["name"] for i in info] == ["goland"]
    rows = {r["name"]: r for r in info[0]["parameters"]}
    assert rows["rho"]["value"] == 1.02 and rows["rho"]["default"] == 1.225
    assert info[0]["reference"]["flutter"]["airspeed"] == 137.2


def test_unknown_names_list_valid_ones(capsys):
    assert main(["problems", "goland", "--set", "foo=1"]) == 1
    err = capsys.readouterr().err
    assert "unknown parameter 'foo'" in err and "semispan" in err and "rho" in err
    assert main(["problems", "nope"]) == 1
    err = capsys.readouterr().err
    assert "unknown problem 'nope'" in err and "typical_section" in err and "goland" in err
