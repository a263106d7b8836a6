"""``casflutter bench design``: one JSON record per order and seed, certified by the
verification layer, and a summary per order.

Truth used: :func:`casflutter.verify.verify_family` run here on the controller rebuilt from
the design with the same seed (the record's certified interval must be that one), on the
shipped ``goland_4flaps`` family.
"""

from __future__ import annotations

import json

import pytest

from casflutter.aeroelastic import load_family
from casflutter.cli import main
from casflutter.design import design_over_speeds
from casflutter.pipeline import RunConfig, multispeed_settings
from casflutter.verify import verify_family

KEYS = {"problem", "nx", "n_inputs", "n_outputs", "order", "seed", "interval", "held", "reach",
        "worst_abscissa", "gamma", "wall_time_s", "cpu_time_s", "certified_interval", "status",
        "objective", "robust_flutter_speed"}


def test_records_per_order_and_seed_with_the_certificate(tmp_path):
    out = tmp_path / "bench.json"
    assert main(["-q", "bench", "design", "--problem", "goland_4flaps", "--interval", "60",
                 "150", "--orders", "2", "--seeds", "0", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    (rec,) = doc["records"]
    assert set(rec) >= KEYS
    assert (rec["nx"], rec["n_inputs"], rec["n_outputs"]) == (50, 4, 8)
    assert rec["order"] == 2 and rec["seed"] == 0 and rec["held"] is True
    assert rec["reach"] == 150.0
    assert doc["summary"]["2"]["held"] == 1 and doc["summary"]["2"]["of"] == 1
    family = load_family("goland_4flaps")
    # the family names no disturbances: the H-infinity phase bounds the loop's sensitivities
    assert rec["objective"] == "sensitivity"
    # the design `casflutter run` makes on a configuration naming the family
    settings = multispeed_settings(RunConfig(), "sensitivity")
    assert doc["settings"].startswith("the [controller] defaults of a run configuration")
    K = design_over_speeds(family, (60.0, 150.0), 2, seed=0, settings=settings).controller
    check = verify_family(family, K, speed_range=family.speed_range)
    assert rec["certified_interval"] == pytest.approx(list(check.stable_interval), rel=1e-9)
    assert rec["robust_flutter_speed"] == pytest.approx(check.robust_flutter_speed, rel=1e-9)
    assert rec["certified_interval"][0] <= 60.0 and rec["certified_interval"][1] >= 150.0


@pytest.mark.parametrize("args, words", [
    (["--interval", "150", "60"], "LO < HI"),
    (["--interval", "60", "150", "--orders", "two"], "--orders"),
    (["--interval", "60", "150", "--problem", "no_such_problem"], "neither a plant family"),
    # the family's lag pole at -2.986 rad/s (60 m/s) is in every closed loop
    (["--interval", "60", "150", "--decay", "5"], "ask for a decay rate below 2.986"),
])
def test_bad_arguments_are_refused_before_any_work(tmp_path, capsys, args, words):
    out = tmp_path / "b.json"
    base = ["bench", "design", "--problem", "goland_4flaps", "--out", str(out)]
    assert main(base + args) == 1
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_a_problem_name_with_a_run_configuration_gives_its_design_family():
    """``--problem NAME`` of a problem that ships a ``run.toml`` (as the help's ``seed_wing``)
    is that run's design family, the same as the run configuration's file given by path:
    here the Goland wing's RFA loop."""
    from casflutter._resources import problems_dir
    from casflutter.cli.bench.design import _family
    by_name, what, _ = _family("goland_gaf")
    by_path, _, _ = _family(str(problems_dir() / "goland_gaf" / "run.toml"))
    assert "run configuration goland_gaf" in what
    A_name, A_path = (f.plant(1.2).A for f in (by_name, by_path))
    assert A_name.shape == A_path.shape and A_name.shape[0] >= 10
    assert (A_name == A_path).all()


@pytest.mark.parametrize("problem, from_run", [("goland_gaf", True), ("goland_4flaps", False)])
def test_a_run_configuration_designs_with_its_controller_settings(tmp_path, monkeypatch,
                                                                  problem, from_run):
    """The bench measures the design ``casflutter run`` makes: a run configuration's
    ``[controller]`` settings (goland_gaf's: no full-order start, ``Dk = 0``, 40 H-inf
    iterations), a family file the ``[controller]`` defaults of a run that names it."""
    import casflutter.design as design
    from casflutter.errors import SynthesisError
    from casflutter.pipeline import config_path, load_config

    seen = []

    def capture(family, interval, order, *, settings, seed):
        seen.append(settings)
        raise SynthesisError("captured")

    monkeypatch.setattr(design, "design_over_speeds", capture)
    out = tmp_path / "b.json"
    assert main(["-q", "bench", "design", "--problem", problem, "--interval", "100", "130",
                 "--orders", "2", "--seeds", "0", "--out", str(out)]) == 0
    (settings,) = seen
    (rec,) = json.loads(out.read_text())["records"]
    assert rec["status"] == "failed: captured" and rec["held"] is False
    if from_run:
        c = load_config(config_path(problem, "run")).controller
        assert (settings.full_order, settings.strictly_proper, settings.random_starts,
                settings.n_speeds) == (c.full_order, c.strictly_proper, c.random_starts,
                                       c.n_speeds)
        assert settings.synthesis.max_outer == c.max_outer == 40
        assert settings.full_order is False
    else:   # a run configuration that names the family file: [controller]'s defaults
        c = RunConfig().controller
        assert (settings.full_order, settings.strictly_proper, settings.random_starts,
                settings.synthesis.max_outer, settings.rate_weight) \
            == (c.full_order, c.strictly_proper, c.random_starts, c.max_outer,
                c.flap_rate_weight)
