"""A run on a rig file (probe 5, P9, P4, P5).

* The keys in the rig's own units that a run configuration leaves out (``data.V0``,
  ``dt``, ``duration``, ``band``, ``flutter.V_range``) come from the rig file's ``[rom]``
  table, as ``casflutter flutter`` takes them, not from the seed wing's defaults; without
  the table they are refused, named, before any work, and so is ``data.coupling_delay``
  left out (the seed wing's CFD coupling); keys the configuration sets win; the seed
  wing's default run is unchanged.
* A stage named in ``stages`` that cannot run is refused before any work (exit 1); one of
  the default list is only skipped, with a note.
* Fig. 9 scales each model's panels to its own signal when one diverges, and its spectrum
  axis covers the LCO frequency.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest
from scipy.optimize import brentq

matplotlib.use("Agg")

import casflutter as cf  # noqa: E402
from casflutter._resources import problems_dir, read_toml  # noqa: E402
from casflutter._settings import build_settings  # noqa: E402
from casflutter.cli import main  # noqa: E402
from casflutter.errors import ConfigError  # noqa: E402
from casflutter.pipeline import (RunConfig, check_requested_stages,  # noqa: E402
                                 default_config_path, flutter_config)

NATA = problems_dir() / "nata" / "problem.toml"


def _rom_table() -> dict:
    with open(NATA, "rb") as fh:
        return tomllib.load(fh)["rom"]


def _write_run(tmp_path: Path, body: str = "", problem: Path = NATA, top: str = "") -> Path:
    path = tmp_path / "run.toml"
    path.write_text(f'seed = 0\n{top}[problem]\nname = "{problem}"\n'
                    '[rom]\nmethod = "common_denominator"\nnf = "auto"\n'
                    + ("" if "[data]" in body else "[data]\ncoupling_delay = 0\n") + body)
    return path


def _qs_flutter_speed(p: dict) -> float:
    """Independent check: the first flutter speed of the rig's linear quasi-steady model
    written out from the pitch-plunge equations (lift ``rho U b cl_alpha w`` with the
    3/4-chord downwash ``w = h' + U alpha + b (1/2 - a) alpha'``, its moment about the
    elastic axis ``b (1/2 + a) L``), by bisection on the oscillatory eigenvalues."""
    b, a, rho, cl = p["b"], p["a"], p["rho"], p["cl_alpha"]
    S = p["m_wing"] * p["x_alpha"] * b
    M = np.array([[p["m_heave"], S], [S, p["I_alpha"]]])
    K = np.diag([p["k_h"], p["k_alpha"][0]])
    C = np.diag([p["c_h"], p["c_alpha"]])
    lvec = np.array([-1.0, b * (0.5 + a)])

    def growth(U):
        Ka = -np.outer(lvec, rho * U * b * cl * np.array([0.0, U]))
        Ca = -np.outer(lvec, rho * U * b * cl * np.array([1.0, b * (0.5 - a)]))
        Mi = np.linalg.inv(M)
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ (K + Ka), -Mi @ (C + Ca)]])
        ev = np.linalg.eigvals(A)
        return ev[np.abs(ev.imag) > 1e-8].real.max()

    Us = np.linspace(2.0, 20.0, 400)
    g = [growth(U) for U in Us]
    i = next(k for k in range(1, len(Us)) if g[k - 1] < 0 <= g[k])
    return brentq(growth, Us[i - 1], Us[i], xtol=1e-12)


# ------------------------------------------------------------------ P9: rig units
def test_default_config_is_its_file_unchanged():
    """The seed wing's default run takes nothing from any problem file: the same settings
    as its TOML file built as it is."""
    raw = build_settings(RunConfig, read_toml(default_config_path(), "configuration"))
    cfg = cf.load_config()
    assert cfg == raw
    assert (cfg.data.V0, cfg.data.dt, cfg.data.coupling_delay) == (0.69, 0.002, 1)
    assert cfg.flutter.V_range == (0.3, 2.5)


def test_rig_run_takes_its_units_from_the_rom_table_and_finds_flutter(tmp_path):
    rom = _rom_table()
    cfg = cf.load_config(_write_run(tmp_path, top="stages = []\n"))
    assert cfg.data.V0 == rom["V0"] and cfg.data.dt == rom["dt"]
    assert cfg.data.duration == rom["duration"] and list(cfg.data.band) == rom["band"]
    assert list(cfg.flutter.V_range) == rom["V_range"]
    # the same records settings as casflutter flutter on the rig (one mapping), whose
    # coupling delay is 0 as the run configuration sets it here
    fc = flutter_config(str(NATA))
    assert (cfg.data, cfg.flutter.V_range) == (fc.data, fc.flutter.V_range)
    # the run now finds the rig's flutter (12.4 m/s), which the seed wing's 0.3-2.5 missed
    res = cf.run(cfg, quiet=True)
    with open(NATA, "rb") as fh:
        Uf = _qs_flutter_speed(tomllib.load(fh))
    assert res.flutters.truth.Vf == pytest.approx(Uf, rel=1e-6)
    assert res.flutters.truth.Vf == pytest.approx(12.4065, abs=1e-3)


def test_rig_run_keys_given_win(tmp_path):
    body = "[data]\nV0 = 12.0\ncoupling_delay = 1\n[flutter]\nV_range = [5.0, 18.0]\n"
    cfg = cf.load_config(_write_run(tmp_path, body), updates={"data.dt": 0.004})
    assert (cfg.data.V0, cfg.data.coupling_delay, cfg.data.dt) == (12.0, 1, 0.004)
    assert cfg.flutter.V_range == (5.0, 18.0)
    assert cfg.data.duration == _rom_table()["duration"]     # left out: the rig's


def test_rig_coupling_delay_left_out_is_refused(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text(f'stages = []\n[problem]\nname = "{NATA}"\n[rom]\nnf = "auto"\n')
    with pytest.raises(ConfigError) as exc:
        cf.load_config(path)
    msg = str(exc.value)
    assert "values of data.coupling_delay are the seed wing's" in msg
    assert "data.V0" not in msg and "flutter.V_range" not in msg   # the [rom] table's
    assert cf.load_config(path, updates={"data.coupling_delay": 1}).data.coupling_delay == 1


def test_rig_without_rom_table_is_refused_naming_the_keys(tmp_path):
    text = NATA.read_text()
    rig = tmp_path / "bare_rig.toml"
    rig.write_text(text[:text.index("[rom]")])
    assert "rom" not in read_toml(rig, "rig")
    with pytest.raises(ConfigError) as exc:
        cf.load_config(_write_run(tmp_path, "[data]\nV0 = 12.0\n", problem=rig))
    msg = str(exc.value)
    for key in ("data.dt", "data.duration", "data.band", "flutter.V_range",
                "data.coupling_delay"):
        assert key in msg
    assert "data.V0" not in msg.split("values of")[1].split(" are ")[0]   # it was given
    assert "seed wing" in msg and "[rom] table" in msg
    # all of them given: accepted
    body = ("[data]\nV0 = 12.0\ndt = 0.005\nduration = 30.0\nband = [0.05, 8.0]\n"
            "coupling_delay = 0\n[flutter]\nV_range = [2.0, 20.0]\n")
    assert cf.load_config(_write_run(tmp_path, body, problem=rig)).data.V0 == 12.0


# ------------------------------------------------------------------ P4: asked-for stages
def test_requested_stage_that_cannot_run_is_refused_before_any_work(tmp_path, capsys):
    path = _write_run(tmp_path)
    with pytest.raises(ConfigError, match="stage 'lco'.*linear"):
        check_requested_stages(cf.load_config(path, updates={"stages": ["lco"]}))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--set", 'stages=["lco"]']) == 1
    err = capsys.readouterr().err
    assert "stage 'lco'" in err and "[1/" not in err          # refused before the stages
    assert not out.exists()
    # the default stage list (stages left out): loads, 'lco' only skipped at run time
    cfg = cf.load_config(path)
    assert "lco" in cfg.stages
    # a RunConfig built in Python keeps the note (whether the list was asked cannot be told)
    res = cf.run(replace(cfg, stages=("lco",)), quiet=True)
    assert "lco" in res.skipped and res.lco is None


def test_requested_stage_needing_a_simulator_is_refused_on_a_wing_file():
    from casflutter.pipeline import config_path

    with pytest.raises(ConfigError, match="stage 'frozen': needs a truth simulator"):
        check_requested_stages(cf.load_config(config_path("example_wing", "run"),
                                              updates={"stages": ["frozen"]}))


# ------------------------------------------------------------------ P5: Fig. 9 axes
def _analysed(t, X, V):
    from casflutter.data._response import analyze_response

    return SimpleNamespace(timepts=t, zm=X, u=X, V=V,
                           sensors=analyze_response(t, X, blowup=np.inf),
                           modes=analyze_response(t, X, blowup=np.inf))


def test_fig9_scales_a_bounded_truth_beside_a_diverging_rom():
    from casflutter.report import plot_lco

    t = np.arange(0.0, 25.0, 0.005)
    grow = np.exp(0.9 * t) * np.sin(2 * np.pi * 0.3 * t)
    rom = _analysed(t, np.column_stack([grow, 3 * grow]), 15.7)
    tt = np.arange(0.0, 60.0, 0.005)
    f_lco, amp = 2.68, (4.37, 29.2)
    Z = np.column_stack([a * np.sin(2 * np.pi * f_lco * tt) for a in amp])
    tr = _analysed(tt, Z, 16.3)
    truth = SimpleNamespace(timepts=tt, zm=Z, V=16.3, analysis=tr.sensors)
    assert rom.sensors.kind == "divergence" and tr.sensors.kind == "lco"
    fig = plot_lco(rom, truth=truth, labels=["h'' [m/s^2]", "alpha'' [rad/s^2]"],
                   speed_unit="m/s")
    axes = np.array(fig.axes).reshape(3, 2)
    for row, a in enumerate(amp):
        lo, hi = axes[row, 1].get_ylim()      # the truth's own scale, not the ROM's 1e9
        assert a < hi < 2 * a and -2 * a < lo < -a
        assert axes[row, 0].get_ylim()[1] > 1e8
    # the spectrum of the truth reaches its LCO frequency; its peak is drawn there
    assert axes[2, 1].get_xlim()[1] > f_lco
    # the ROM's 25 s record is drawn whole and not called "last 6 periods"
    assert "last" not in axes[1, 0].get_xlabel()
    assert axes[1, 0].get_lines()[0].get_xdata()[0] == 0.0
    assert "last 6 periods" in axes[1, 1].get_xlabel()


def test_fig9_two_bounded_cycles_share_a_scale():
    from casflutter.report import plot_lco

    t = np.arange(0.0, 40.0, 0.005)
    a = _analysed(t, np.column_stack([2.0 * np.sin(2 * np.pi * 1.0 * t)]), 1.0)
    b = _analysed(t, np.column_stack([4.0 * np.sin(2 * np.pi * 3.0 * t)]), 1.1)
    truth = SimpleNamespace(timepts=t, zm=b.zm, V=1.1, analysis=b.sensors)
    fig = plot_lco(a, truth=truth)
    axes = np.array(fig.axes).reshape(2, 2)
    assert axes[0, 0].get_ylim() == axes[0, 1].get_ylim()
    assert axes[0, 0].get_ylim()[1] > 4.0
    # one spectrum axis for both, covering the larger LCO frequency (3)
    assert axes[1, 0].get_xlim() == axes[1, 1].get_xlim() and axes[1, 1].get_xlim()[1] > 3.0


def test_default_config_switched_to_a_rig_takes_the_rigs_units():
    """``casflutter run --set problem.name=nata``: the default file's data and flutter keys
    are the seed wing's, in its units; the rig's [rom] table replaces them, and the
    coupling delay, which no rig file gives, must be set."""
    rom = _rom_table()
    with pytest.raises(ConfigError, match="data.coupling_delay.*seed_wing"):
        cf.load_config(updates={"problem.name": "nata"})
    cfg = cf.load_config(updates={"problem.name": "nata", "data.coupling_delay": 0,
                                  "data.dt": 0.004, "rom.nf": "auto", "stages": []})
    assert cfg.data.V0 == rom["V0"] and list(cfg.flutter.V_range) == rom["V_range"]
    assert cfg.data.duration == rom["duration"] and list(cfg.data.band) == rom["band"]
    assert (cfg.data.dt, cfg.data.coupling_delay) == (0.004, 0)       # the updates win
