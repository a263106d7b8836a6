"""Flutter-speed sensitivities of a wing or GAF file: refused with a ConfigError that says
the file has no simulator parameters and what to do instead, before its records or table
are read."""

from pathlib import Path

import pytest

import casflutter.truth._wing_file as wing_file
from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.study import flutter_sensitivity, flutter_sensitivity_nlp, flutter_speed_fd

ROOT = Path(__file__).resolve().parents[2] / "problems"


@pytest.fixture()
def no_loading(monkeypatch):
    """Reading a wing file's records or table is an error here: the refusal comes first."""
    def boom(*a, **k):
        raise AssertionError("the wing file was loaded before the refusal")
    monkeypatch.setattr(wing_file.WingProblem, "from_mapping", classmethod(boom))
    monkeypatch.setattr(wing_file.GAFProblem, "from_mapping", classmethod(boom))


@pytest.mark.parametrize("problem, kind, command", [
    ("example_wing", 'kind = "wing"', "casflutter run"),
    (str(ROOT / "example_wing" / "problem.toml"), 'kind = "wing"', "casflutter run"),
    ("goland_gaf", 'kind = "gaf"', "casflutter flutter"),
])
def test_a_wing_file_has_no_parameters_to_differentiate(problem, kind, command, no_loading):
    with pytest.raises(ConfigError) as info:
        flutter_sensitivity(problem)
    msg = str(info.value)
    assert kind in msg and "no simulator parameters to differentiate" in msg
    assert "typical_section" in msg and command in msg


@pytest.mark.parametrize("call", [
    lambda: flutter_sensitivity_nlp("example_wing"),
    lambda: flutter_speed_fd("goland_gaf", "alpha"),
])
def test_every_sensitivity_route_refuses_it(call, no_loading):
    with pytest.raises(ConfigError, match="no simulator parameters"):
        call()


def test_the_sensitivity_command_says_it_in_one_line(capsys, no_loading):
    assert main(["sensitivity", "--problem", "example_wing"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("casflutter: error:")
    assert "no simulator parameters" in err[0] and "internal error" not in err[0]


def test_a_truth_problem_still_works():
    res = flutter_sensitivity("typical_section", ["mu"])
    assert res.Vf > 0 and res["mu"].dVf_dp != 0
