"""``casflutter lco``: JSON of the typical section with a cubic spring, the NATA file and the
ROM loop; the figure only when asked; clear errors; the settings' validation; the figures."""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca
import matplotlib.pyplot as plt
import pytest

from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.lco import LCOSettings, Outputs, continue_lco, lco_branch
from casflutter.report import plot_bifurcation, plot_bifurcation_pair
from casflutter.truth import TypicalSection, TypicalSectionParams

ROOT = Path(__file__).resolve().parents[2]


def test_typical_section_json(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["lco", "typical_section", "--set", "kappa2=3", "--vrange", "1.5", "2.6",
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["kind"] == "supercritical"
    assert doc["hopf"]["V"] == pytest.approx(2.170, rel=5e-3)
    assert set(doc) >= {"hopf", "kind", "branch", "folds", "units", "stop_reason", "figure"}
    p = doc["branch"][-1]
    assert set(p) >= {"V", "freq_hz", "amplitude", "stable"}
    assert set(p["amplitude"]) == {"plunge", "pitch", "h/b", "theta"}
    assert doc["units"]["amplitude"]["theta"] == "rad"
    V = [q["V"] for q in doc["branch"]]
    assert min(V) > doc["hopf"]["V"] and max(V) <= 2.6
    assert doc["figure"] is None and not list(tmp_path.iterdir())    # no file by default


def test_nata_text_and_figure(capsys, tmp_path):
    fig = tmp_path / "nata.png"
    assert main(["lco", str(ROOT / "problems" / "nata" / "problem.toml"),
                 "--figure", str(fig)]) == 0
    out = capsys.readouterr().out
    assert "nata: subcritical Hopf point at V = 12.4" in out and "m/s" in out
    assert "fold of cycles at V = 6.3" in out and "hysteresis" in out
    assert fig.is_file() and fig.stat().st_size > 10_000


def test_rom_loop_from_a_saved_rom(capsys):
    assert main(["lco", "seed_wing", "--rom", str(ROOT / "problems" / "seed_wing_rom" / "rom.npz"),
                 "--vrange", "20", "40", "--max-points", "6", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["system"] == "rom_loop" and doc["kind"] == "supercritical"
    assert doc["units"]["V"] == "m/s"
    assert doc["hopf"]["V"] == pytest.approx(1.1886 * 28.9, rel=1e-3)
    assert "Acc2 (lateral)" in doc["branch"][0]["amplitude"]


def test_errors(capsys):
    assert main(["lco", "goland"]) == 1
    assert "degenerate" in capsys.readouterr().err
    assert main(["lco", "typical_section", "--vrange", "0.5", "1.0"]) == 1
    err = capsys.readouterr().err
    assert "no flutter (Hopf) point in the speed range [0.5, 1]" in err and "--vrange" in err
    assert main(["lco", "nata", "--rom", "missing.npz"]) == 1
    assert "does not exist" in capsys.readouterr().err


def test_a_diverging_section_is_not_called_stable(capsys):
    """NATA with its elastic axis at mid-chord (a = 0): the quasi-steady moment about it,
    rho U^2 b^2 (1/2 + a) cl_alpha alpha, beats the linear pitch spring k_1 at
    U_d = sqrt(k_1 / (rho b^2 (1/2 + a) cl_alpha)), whatever the plunge does, long before
    the oscillatory modes would flutter."""
    assert main(["lco", "nata", "--set", "a=0", "--set", "I_alpha=0.06", "--vrange", "1",
                 "60"]) == 1
    err = capsys.readouterr().err
    k1, rho, b, cl = 2.82, 1.225, 0.135, 6.28
    Ud = (k1 / (rho * b**2 * 0.5 * cl)) ** 0.5
    assert "no flutter (Hopf) point" in err and "diverges statically" in err
    assert "stays stable" not in err
    V = float(err.split("diverges statically at V = ")[1].split()[0])
    assert V == pytest.approx(Ud, rel=1e-5)


def test_settings_are_validated():
    with pytest.raises(ConfigError, match="LCOSettings.degree"):
        LCOSettings(degree=0)
    with pytest.raises(ConfigError, match="LCOSettings.sensor_kind"):
        LCOSettings(sensor_kind="strain")
    with pytest.raises(ConfigError, match="unknown LCO setting"):
        LCOSettings.from_mapping({"intervals": 3})


def test_continuation_failure_keeps_the_last_point():
    """A vector field undefined beyond |x| = 0.5 (the cycle r^2 = V - 1 reaches it at
    V = 1.25): the continuation fails there, says so and keeps the points before."""
    x = ca.SX.sym("x", 2)
    V = ca.SX.sym("V")
    r2 = x[0] ** 2 + x[1] ** 2
    wall = 1e-12 * ca.sqrt(0.25 - x[0] ** 2)            # NaN beyond |x| = 0.5
    f = ca.Function("f", [x, V], [ca.vertcat((V - 1) * x[0] - 2 * x[1] - x[0] * r2 + wall,
                                             2 * x[0] + (V - 1) * x[1] - x[1] * r2)])
    out = Outputs(("x",), ("",), ca.Function("h", [x, V], [x[0]]))
    br = continue_lco(f, out, (0.5, 2.0), LCOSettings(max_points=200))
    assert not br.completed
    assert "continuation failed at V = 1.2" in br.stop_reason
    assert "last converged point is kept" in br.stop_reason
    assert 0.45 < br.points[-1].amplitude["x"] < 0.501   # the nodes stay inside |x| <= 0.5
    assert br.to_dict()["completed"] is False


def test_bifurcation_figures():
    sub = lco_branch(TypicalSection(TypicalSectionParams(kappa2=-3.0, kappa4=10.0)), (1.5, 2.6))
    fig = plot_bifurcation(sub, ["theta"], hb_points={"theta": ([2.0], [0.5])})
    ax = fig.axes[0]
    styles = {line.get_linestyle() for line in ax.get_lines()}
    assert {"-", "--"} <= styles                                  # stable and unstable parts
    assert ax.get_xlabel() == "" and "speed index" in fig.axes[-1].get_xlabel()
    assert ax.get_ylabel() == "LCO amplitude, theta [rad]"
    assert any(line.get_marker() == "^" for line in ax.get_lines())    # the fold
    assert "subcritical" in ax.get_title()
    sup = lco_branch(TypicalSection(TypicalSectionParams(kappa2=3.0)), (1.5, 2.6),
                     LCOSettings(max_points=10))
    fig2 = plot_bifurcation_pair(sup, sub, ["theta"])
    assert len(fig2.axes) == 4
    plt.close("all")
