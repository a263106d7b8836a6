"""The ``pipeline`` evaluator: ``casflutter run`` (the seed-wing study) swept over run-config
keys (controller order, the accelerometer rows) and truth parameters by dotted path."""

import json
from dataclasses import replace
from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.study import (Parameter, PointStore, Study, evaluator_names, load_study,
                              run_sweep, sweep_table)

# The reduced seed-wing run of tests/pipeline/test_run.py, cut further so that one point
# takes 10-20 s (one minimax solve; the controller is poor but the run is complete).
REDUCED = """
seed = 3
[problem]
name = "seed_wing"
{problem_set}
[data]
duration = 4.0
[rom]
regularization = 1e-6
[flutter]
V_range = [0.05, 2.5]
n_grid = 61
[lco]
duration = 1.0
initial_deflection = 0.05
[controller]
order = {order}
starts = 1
zero_start = true
strictly_proper = false
max_outer = 1
max_stab_rounds = 2
stability_margin = 1e-4
{sensors}
[suppression]
speed_factors = [1.05]
settle = 1.5
ramp = 0.5
hold = 1.5
release = 1.0
# a quiet tunnel: the suppression record is checked against the open loop without turbulence
gust_intensity = 0.0
noise = 0.0
"""

ORDERS = (1, 2)
ZETAS = (0.005, 0.01)   # structural damping of the lateral mode, the flutter mode (mode 2)
#: paper §IV accelerometer rows (Acc1, Acc2) and two other readings of the same wing: the
#: sensors mixed (S H0) and Acc2 alone
H0 = np.array([[0.1299, -0.0006, -0.2866, -0.1130, 0.0766],
               [-0.0021, 0.1364, 0.0141, 0.0021, -0.0020]])
S = np.array([[2.0, 0.5], [-0.3, 1.5]])
ROWS = ((S @ H0).tolist(), H0[1:].tolist())


def _study(cfg_path: Path) -> Study:
    # a 2-point Latin hypercube over explicit values: each order, damping and row set once
    return Study(name="pipe", evaluator="pipeline", design="lhs", samples=2, seed=0,
                 parameters=(Parameter("controller.order", values=ORDERS),
                             Parameter("problem.set.zeta_lateral", values=ZETAS),
                             Parameter("sensors.rows", values=ROWS)),
                 settings={"config": cfg_path.name}, base_dir=str(cfg_path.parent))


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pipe")
    cfg = folder / "base.toml"
    cfg.write_text(REDUCED.format(order=3, problem_set="", sensors=""))
    study = _study(cfg)
    res = run_sweep(study, store=folder / "pipe.jsonl", workers=0, progress=False)
    return folder, study, res, sweep_table(study, res.store)


def test_pipeline_is_registered():
    assert "pipeline" in evaluator_names()


def test_swept_parameters_take_effect(swept):
    from casflutter.aeroelastic import find_flutter
    from casflutter.truth import load_problem

    _, study, res, rows = swept
    assert (res.n_points, res.n_computed, res.n_failed) == (2, 2, 0), [r["error"] for r in rows]
    assert sorted(r["controller.order"] for r in rows) == list(ORDERS)
    assert sorted(r["problem.set.zeta_lateral"] for r in rows) == list(ZETAS)
    from casflutter.study._pipeline_eval import PIPELINE_OUTPUTS
    for r in rows:
        assert set(PIPELINE_OUTPUTS) <= set(r)   # every documented column is produced
        # the requested order, not the base file's 3
        assert r["controller_order"] == r["controller.order"]
        # the damping reached the truth: its flutter speed is that of the truth built
        # directly with the same damping (same search as the run)
        truth = load_problem("seed_wing", [f"zeta_lateral={r['problem.set.zeta_lateral']}"])
        N = truth.n_modes
        direct = find_flutter(truth.state_matrix, (0.05, 2.5), n_grid=61, max_refine=3,
                              mode_states=[np.array([i, N + i]) for i in range(N)],
                              omega=truth.modal_structure().omega)
        np.testing.assert_allclose(r["Vf_truth"], direct.Vf, rtol=1e-12)
        assert r["stable_V_lo"] <= r["Vf_rom"] <= r["stable_V_hi"]
        assert r["small_gain_V_lo"] < r["Vf_rom"] < r["small_gain_V_hi"]
        assert r["time_total"] >= r["time_controller"] > 0
    lo, hi = sorted(rows, key=lambda r: r["problem.set.zeta_lateral"])
    # more structural damping of the flutter mode raises the flutter speed (ROM and truth)
    assert hi["Vf_rom"] > lo["Vf_rom"] + 0.01
    assert hi["Vf_truth"] > lo["Vf_truth"] + 0.01


def test_swept_point_equals_a_direct_run(swept):
    """The same point run directly from a config file that spells the values out."""
    from casflutter.pipeline import load_config, run

    folder, _, _, rows = swept
    r = rows[0]
    path = folder / "direct.toml"
    path.write_text(REDUCED.format(order=r["controller.order"],
                                   problem_set=f"set = {{zeta_lateral = "
                                               f"{r['problem.set.zeta_lateral']!r}}}",
                                   sensors=f"[sensors]\nrows = {r['sensors.rows']!r}"))
    cfg = load_config(path)
    result = run(cfg, write=False, quiet=True)
    s = result.summary()
    _check_sensor_rows_reach_every_stage(result, cfg, np.asarray(r["sensors.rows"]))
    expected = {
        "Vf_rom": s["flutter"]["V"], "freq_hz_rom": s["flutter"]["freq_hz"],
        "mode_rom": s["flutter"]["mode"], "Vf_truth": s["flutter_truth"]["V"],
        "freq_hz_truth": s["flutter_truth"]["freq_hz"], "lco_V": s["lco"]["V"],
        "lco_freq_hz": s["lco"]["freq_hz"], "lco_kind": s["lco"]["kind"],
        # amplitudes are a cycle's only (None for a decay or a divergence)
        "lco_amplitude": max(s["lco"]["amplitude"] or [None]),
        "lco_truth_amplitude": max(s["lco"]["truth_amplitude"] or [None]),
        "controller_order": s["controller"]["order"], "gamma": s["controller"]["gamma"],
        "small_gain_V_lo": s["controller"]["small_gain_V"][0],
        "small_gain_V_hi": s["controller"]["small_gain_V"][1],
        "stable_V_lo": s["controller"]["lft_stable_V"][0],
        "stable_V_hi": s["controller"]["lft_stable_V"][1],
        "certified_V_lo": s["controller"]["stable_interval"][0],
        "certified_V_hi": s["controller"]["stable_interval"][1],
        "attenuation_percent": s["suppression"]["attenuation_percent"],
        "fit_error_max": max(s["fit_error_percent"]), "nf": s["nf"], "nae": s["nae"],
    }
    for name, value in expected.items():
        if isinstance(value, float):
            # deterministic in one process: equal up to floating-point reassociation
            assert r[name] == pytest.approx(value, rel=1e-8, abs=1e-12), name
        else:
            assert r[name] == value, name
    assert set(s["timings_s"]) == {k[len("time_"):] for k in r if k.startswith("time_")}


def _check_sensor_rows_reach_every_stage(result, cfg, R):
    """The configured rows R read every stage: Σs, the LFT (eq. 14) and the truth's LCO and
    suppression records equal R times the same quantities computed independently with one
    accelerometer per mode (identity rows)."""
    from casflutter.aeroelastic import AeroelasticSystem, build_lft
    from casflutter.truth import closed_loop_truth, truth_lco

    truth, system, lft = result.truth, result.system, result.lft
    np.testing.assert_array_equal(system.structure.Hs, R)
    assert result.summary()["n_sensors"] == lft.nmeas == R.shape[0]
    eye = build_lft(AeroelasticSystem.from_parts(
        result.realization.sigma_f, truth.modal_structure().with_sensors(np.eye(5),
                                                                         "acceleration"),
        warn_unstable=False), lft.Vf)
    for name in ("C2", "D21", "D22"):
        np.testing.assert_allclose(getattr(lft, name), R @ getattr(eye, name), rtol=1e-12,
                                   atol=1e-12, err_msg=name)
    crit = result.summary()["flutter"]["mode"] - 1
    dt = result.identification.model.dt
    lt = result.lco.truth
    acc = truth_lco(truth, lt.V, cfg.lco.duration, crit, cfg.lco.initial_deflection, dt=dt,
                    sensor_rows=np.eye(5)).zm
    np.testing.assert_allclose(lt.zm, acc @ R.T, rtol=1e-10, atol=1e-12)
    # suppression: open loop (gain 0) during the settling phase
    sup = result.suppression.runs[0]
    t = sup.simulation.timepts
    n = int(np.sum(t < cfg.suppression.settle)) - 1
    x0 = truth.displaced_state(crit, cfg.lco.initial_deflection)
    no_control = control.ss([], [], [], np.zeros((1, 5)))
    open_acc = closed_loop_truth(truth, no_control, sup.V, t[:n], x0, lambda t: 0.0,
                                 sensor_rows=np.eye(5)).zm
    np.testing.assert_allclose(sup.simulation.zm[:n], open_acc @ R.T, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize("name, words", [
    ("controller.ordr", ["'ordr'", "[controller]", "allowed", "max_outer"]),
    ("contrlr.order", ["'contrlr'", "allowed", "controller", "suppression"]),
    ("problem.set.zeta_lat", ["problem.set", "'zeta_lat'", "zeta_lateral"]),
])
def test_unknown_name_fails_before_any_work(tmp_path, name, words):
    """The pre-flight check stops the study before any point is submitted."""
    st = Study(name="bad", evaluator="pipeline", parameters=(Parameter(name, values=(1.0,)),),
               settings={})
    with pytest.raises(ConfigError) as exc:
        run_sweep(st, store=tmp_path / "bad.jsonl", workers=0, progress=False)
    msg = str(exc.value)
    for w in [*words, "point 1 of 1", f"{name} = 1.0", "no point was run"]:
        assert w in msg
    assert list(PointStore(tmp_path / "bad.jsonl")) == []


def test_one_bad_point_stops_the_whole_study(tmp_path):
    """The first point is valid, the second is not: neither runs, the message names the
    second point and its key (local processes: nothing is submitted, no worker starts)."""
    st = Study(name="bad2", evaluator="pipeline",
               parameters=(Parameter("rom.orders", values=([3, 1, 1, 1, 2, 2], [3, 1, 1])),),
               settings={"controller.order": 1})
    with pytest.raises(ConfigError, match=r"point 2 of 2 \(rom\.orders = \[3, 1, 1\]\).*"
                                          r"rom\.orders = \[3, 1, 1\]: give six integers"):
        run_sweep(st, store=tmp_path / "bad2.jsonl", workers=2, progress=False)
    assert list(PointStore(tmp_path / "bad2.jsonl")) == []
    bad_rows = Study(name="bad3", evaluator="pipeline",
                     parameters=(Parameter("sensors.rows", values=([[1.0, 0, 0, 0]],)),))
    with pytest.raises(ConfigError, match=r"point 1 of 1.*sensors\.rows\[0\] has 4 entries"):
        run_sweep(bad_rows, store=tmp_path / "bad3.jsonl", workers=0, progress=False)


def test_pipeline_config_direct_errors():
    from casflutter.study._pipeline_eval import pipeline_config

    with pytest.raises(ConfigError, match="'seed.x'.*single value"):
        pipeline_config({"seed.x": 1})
    with pytest.raises(ConfigError, match="rom.orders"):
        pipeline_config({"rom.orders": [3, 1, 1]})
    # the evaluator's own settings are not config keys; fixed changes merge with swept ones
    cfg = pipeline_config({"controller.order": 4},
                          {"quiet": False, "out_dir": "x", "controller": {"starts": 1}})
    assert (cfg.controller.order, cfg.controller.starts) == (4, 1)


def test_example_study_file_is_valid():
    """Every point of the example study gives a valid config carrying the swept values."""
    from casflutter.study._pipeline_eval import pipeline_config

    st = load_study(Path(__file__).parents[2] / "problems" / "studies" /
                    "seed_wing_pipeline.toml")
    assert st.evaluator == "pipeline" and len(st.points()) >= 4
    for p in st.points():
        cfg = pipeline_config(p, st.resolved_settings())
        assert cfg.controller.order == p["controller.order"]
        assert cfg.problem.set["zeta_lateral"] == p["problem.set.zeta_lateral"]


@pytest.mark.slow
def test_example_study_writes_point_folders(tmp_path):
    """The example study on 2 local processes with per-point files (slow: full points)."""
    st = load_study(Path(__file__).parents[2] / "problems" / "studies" /
                    "seed_wing_pipeline.toml")
    st = replace(st, settings={**st.settings, "out_dir": str(tmp_path / "points")})
    res = run_sweep(st, store=tmp_path / "s.jsonl", workers=2, progress=False)
    assert (res.n_failed, res.n_left) == (0, 0)
    rows = sweep_table(st, res.store)
    folders = sorted((tmp_path / "points").iterdir())
    assert len(folders) == len(rows)
    for f in folders:   # each point's own summary.json holds the numbers of its row
        s = json.loads((f / "summary.json").read_text())
        (r,) = [r for r in rows if r["Vf_rom"] == s["flutter"]["V"]
                and r["controller.order"] == s["controller"]["order"]]
        assert r["gamma"] == s["controller"]["gamma"]
        assert (f / "report.html").is_file()
    for order in {r["controller.order"] for r in rows}:
        # more damping of the flutter mode, higher flutter speed (ROM and truth)
        same = sorted((r for r in rows if r["controller.order"] == order),
                      key=lambda r: r["problem.set.zeta_lateral"])
        assert all(b["Vf_rom"] > a["Vf_rom"] and b["Vf_truth"] > a["Vf_truth"]
                   for a, b in zip(same, same[1:]))
