"""Run configuration: bad configs fail before any work, naming the key and what is allowed."""

import pytest

from casflutter.errors import ConfigError
from casflutter.pipeline import RunConfig, load_config


def _write(tmp_path, text):
    p = tmp_path / "run.toml"
    p.write_text(text)
    return p


def test_defaults_are_the_paper_choices():
    cfg = RunConfig()
    assert cfg.rom.orders == [3, 1, 1, 1, 2, 2]
    assert cfg.data.V0 == 0.69 and cfg.controller.order == 3


@pytest.mark.parametrize("text,match", [
    ("[rom]\nordres = [3,1,1,1,2,2]\n", r"unknown key 'ordres' in \[rom\] \(did you mean 'orders'\?\); allowed: orders"),
    ("colour = 1\n", r"unknown key 'colour' in top level; allowed: problem"),
    ("order = 4\n", r"unknown key 'order' in top level \(it belongs in \[controller\]\)"),
    ("[controller]\nmax_outr = 4\n",
     r"unknown key 'max_outr' in \[controller\] \(did you mean 'max_outer'\?\)"),
    ("[data]\ndt = 'fast'\n", r"data.dt: expected a number, got str"),
    ("[data]\ndt = -0.1\n", r"data.dt = -0.1: must be > 0"),
    ("[controller]\norder = 2.5\n", r"controller.order: expected an integer"),
    ("[rom]\norders = [3,1,1]\n", r"rom.orders .*six integers"),
    ("[rom]\norders = [0,1,1,1,2,2]\n", r"rom.orders .*mu must be >= 1"),
    ("[rom]\nnf = 'many'\n", r"rom.nf = 'many'"),
    ("[rom]\ncriterion = 'magic'\n", r"rom.criterion.*'prediction', 'simulation'"),
    ("[data]\nband = [1.0, 500.0]\n", r"above the Nyquist"),
    ("[flutter]\nV_range = [2.0, 1.0]\n", r"flutter.V_range"),
    ("[data]\nband_hz = [1.0, 50.0]\n", r"data.band_hz was renamed data.band"),
    ("[flutter]\nvrange = [0.5, 1.0]\n", r"flutter.vrange was renamed flutter.V_range"),
    ("[suppression]\nspeed_factor = 1.1\n",
     r"suppression.speed_factor was renamed suppression.speed_factors"),
    ("[suppression]\nspeed_factors = 1.1\n", r"suppression.speed_factors: expected a list"),
    ("[suppression]\nspeed_factors = [1.05, 0.0]\n", r"speed_factors .*must be > 0"),
    ("[suppression]\ngust_intensity = -0.01\n", r"gust_intensity = -0.01: must be"),
    ("[suppression]\nworkers = -1\n", r"suppression.workers = -1: must be an integer >= 0"),
    ("[lco]\nworkers = -2\n", r"lco.workers = -2: must be an integer >= 0"),
    ("[lco]\nworkers = 1.5\n", r"lco.workers.*integer"),
    ("stages = ['lco', 'dance']\n", r"stages: unknown stage 'dance'"),
    ("stages = ['suppression']\n", r"'suppression' needs the 'controller' stage"),
    ("[controller]\nmethod = 'hifoo'\n", r"controller.method = 'hifoo': allowed 'auto'"),
    ("[controller]\norder = 0\n",
     r"controller.order = 0 with strictly_proper = true \(the default\) .* static gain set "
     r"strictly_proper = false"),
    ("[controller]\nspeeds = [0.5, 1.2]\n", r"controller.speeds .*containing 1.0"),
    ("[controller]\nmax_stab_rounds = 0\n",
     r"controller.max_stab_rounds = 0: give an integer >= 1 \(SynthesisOptions\)$"),
    ("[controller]\ninterval = [2.0, 1.0]\n", r"controller.interval"),
    ("[problem]\nname = 'concorde'\n", r"problem.name = 'concorde': allowed .*typical_section"),
    ("[problem]\nfile = 'wing.toml'\n",
     r"unknown key 'file' in \[problem\] \(a problem file is named by name: name = \"FILE.toml\""),
    ("[data\n", r"not valid TOML"),
    ("rom = 3\n", r"\[rom\] must be a table"),
])
def test_bad_configs_are_named(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match):
        load_config(_write(tmp_path, text))


def test_missing_file():
    with pytest.raises(ConfigError, match="does not exist"):
        load_config("/nonexistent/run.toml")


def test_cli_fails_before_work(tmp_path, capsys):
    from casflutter.cli import main
    rc = main(["run", str(_write(tmp_path, "[rom]\nordres = 1\n")), "--out", str(tmp_path / "o")])
    assert rc == 1
    assert "unknown key 'ordres'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
