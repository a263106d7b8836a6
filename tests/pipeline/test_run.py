"""``casflutter run`` on a reduced configuration of the seed wing (the full run is slow)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from casflutter.cli import main

REDUCED = """
seed = 3
[problem]
name = "seed_wing"
[data]
duration = 4.0
[rom]
regularization = 1e-6
[flutter]
n_grid = 61
[lco]
duration = 6.0
[controller]
order = 2
starts = 1
max_outer = 4
stability_margin = 1e-4
max_stab_rounds = 8
[suppression]
settle = 2.0
ramp = 1.0
hold = 2.0
release = 2.0
"""


@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    folder = tmp_path_factory.mktemp("run")
    cfg_path = folder / "run.toml"
    cfg_path.write_text(REDUCED)
    out = folder / "out"
    rc = main(["run", str(cfg_path), "--out", str(out), "--quiet"])
    assert rc == 0
    return cfg_path, out, json.loads((out / "summary.json").read_text())


def test_summary_keys_and_table_i_structure(reduced):
    _, out, s = reduced
    for key in ("problem", "orders", "n_params", "fit_error_percent", "nf", "ns", "nae",
                "flutter", "flutter_truth", "lco", "controller", "suppression", "timings_s"):
        assert key in s
    assert s["orders"] == [3, 1, 1, 1, 2, 2] and s["n_params"] == 230
    assert (s["nf"], s["ns"], s["nae"]) == (15, 10, 25)
    assert s["flutter"]["mode"] == 2              # the lateral branch (paper Fig. 10)
    # the suppression run starts from the truth's established LCO of the [lco] stage (same
    # speed): the RMS it is switched on against is that LCO's (a near-sinusoid: its half
    # peak-to-peak amplitude over sqrt(2); the harmonics and the tunnel's turbulence move it
    # by a few per cent, 10 %; the turbulence's peaks would move the peak by 25 %)
    sup, lco = s["suppression"], s["lco"]
    assert lco["truth_kind"] == "lco" and sup["started_from_lco"]
    assert sup["V"] == pytest.approx(lco["truth_V"], rel=1e-12)
    # and one run per speed factor, each from the truth's established LCO there
    runs = sup["runs"]
    assert [r["speed_factor"] for r in runs] == [1.05, 1.2]
    assert all(r["started_from_lco"] for r in runs)
    assert runs[0]["V"] == sup["V"] and runs[1]["V"] == pytest.approx(1.2 / 1.05 * sup["V"])
    dom = sup["dominant_sensor"]
    assert runs[0]["open_loop_rms"][dom] == pytest.approx(
        lco["truth_amplitude"][dom] / np.sqrt(2), rel=0.10)
    # the speed-following ROM's LCO beside the truth's at the same multiples of the truth's
    # flutter speed; the truth's runs are the LCO stage's and the suppression's starts
    following = lco["speed_following"]
    assert [c["speed_factor"] for c in following] == [1.05, 1.2]
    for c, r in zip(following, runs):
        assert c["V"] == pytest.approx(c["speed_factor"] * s["flutter_truth"]["V"], rel=1e-12)
        assert c["V"] == pytest.approx(r["V"], rel=1e-12)
        assert c["truth_kind"] == "lco" and c["rom_kind"] in ("lco", "divergence", "decay")
        assert r["open_loop_rms"][dom] == pytest.approx(
            c["truth_amplitude"][dom] / np.sqrt(2), rel=0.10)
        np.testing.assert_allclose(c["amplitude_error_percent"], 100 * (
            np.divide(c["rom_amplitude"], c["truth_amplitude"]) - 1), rtol=1e-12)
    assert following[0]["truth_amplitude"] == lco["truth_amplitude"]
    assert set(s["controller"]) >= {"order", "gamma", "small_gain_V", "lft_stable_V",
                                    "stable_interval", "truth_stable_interval",
                                    "absolute_flutter_speed", "robust_flutter_speed"}
    assert s["timings_s"]["total"] >= sum(v for k, v in s["timings_s"].items() if k != "total") - 1e-6
    for name in ("summary.json", "rom.npz", "controller.json", "controller.mat", "report.html",
                 "fig7_rom_fit.png", "fig8_flap_pulses.png", "fig9_lco.png",
                 "fig10_pole_loci.png", "fig11_gain_ramp.png", "lco_speed_following_1p05.png",
                 "lco_speed_following_1p2.png", "margins_truth.png", "model_error_truth.png"):
        assert (out / name).is_file(), name
    html = (out / "report.html").read_text()
    assert "data:image/png;base64," in html and "Table I" in html


def test_controller_files_load_back(reduced):
    _, out, s = reduced
    from scipy.io import loadmat

    from casflutter.verify import load_controller
    K = load_controller(out / "controller.json")
    M = loadmat(out / "controller.mat")
    np.testing.assert_allclose(np.asarray(K.D), M["D"])
    assert K.nstates == s["controller"]["order"] == 2


def _assert_close(a, b, path=""):
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            if not k.endswith("_time_s"):      # seconds measured, not computed
                _assert_close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_close(x, y, f"{path}[{i}]")
    elif isinstance(a, float):
        # same seed, same numbers: up to floating-point reassociation in the linear algebra
        assert b == pytest.approx(a, rel=1e-8, abs=1e-12), path
    else:
        assert a == b, path


def test_same_seed_same_numbers(reduced, tmp_path):
    # a second run in a fresh process (another memory layout, another moment of machine
    # load): the synthesis budget is counted in iterations, never in wall time; and with
    # every computation in that process, where the first run gave the LCO stage's and the
    # suppression's independent pieces to worker processes
    cfg_path, _, s = reduced
    here = tmp_path / "run.toml"
    here.write_text(REDUCED.replace("[lco]\n", "[lco]\nworkers = 1\n")
                    .replace("[suppression]\n", "[suppression]\nworkers = 1\n"))
    out = tmp_path / "again"
    code = ("import sys; from casflutter.cli import main; "
            f"sys.exit(main(['run', {str(here)!r}, '--out', {str(out)!r}, '--quiet']))")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=600)
    again = json.loads((out / "summary.json").read_text())
    config = json.loads((out / "config.json").read_text())
    assert config["lco"]["workers"] == config["suppression"]["workers"] == 1
    for key in ("orders", "n_params", "fit_error_percent", "nf", "nae", "flutter",
                "flutter_truth", "lco", "controller", "suppression"):
        _assert_close(s[key], again[key], key)


def test_exports_carry_names_units_speeds_and_reproduce_the_verification(reduced, capsys):
    """controller.json/.mat and plant.json say what their signals are; ``casflutter verify
    OUT/plant.json OUT/controller.json`` repeats the run's own verification."""
    from scipy.io import loadmat

    from casflutter.truth import load_problem

    _, out, s = reduced
    truth = load_problem("seed_wing")
    c = json.loads((out / "controller.json").read_text())
    assert c["time_base"] == {"domain": "continuous", "dt": None, "time_unit": "s",
                              "frequency_unit": "rad/s"}
    assert [i["name"] for i in c["inputs"]] == list(truth.modal_structure().sensor_names)
    # acceleration sensors: the unit of the truth's rows (tip deflections) per second squared
    assert [i["unit"] for i in c["inputs"]] == [f"{u}/s^2" for u in truth.sensor_units()]
    assert truth.sensor_units() == ("m", "m")
    assert [(o["name"], o["signal"], o["unit"]) for o in c["outputs"]] == [("v", "v", "rad")]
    assert c["sign_convention"].startswith("v = K zm")
    Vf = s["flutter"]["V"]
    # Vf and the certified intervals in speed index and in m/s (U = V U_ref, U_ref = 28.9)
    assert c["design"]["Vf"]["speed_index"] == Vf
    assert c["design"]["Vf"]["airspeed_m_s"] == pytest.approx(28.9 * Vf, rel=1e-12)
    cert = c["certified"]
    assert cert["lft"]["exact_V"]["speed_index"] == s["controller"]["lft_stable_V"]
    assert cert["lft"]["small_gain_V"]["speed_index"] == s["controller"]["small_gain_V"]
    design = s["controller"]["stable_interval"]
    assert cert["design"]["stable_interval"]["speed_index"] == design
    assert cert["design"]["stable_interval"]["airspeed_m_s"] == pytest.approx(
        [28.9 * v for v in design], rel=1e-12)
    assert c["casflutter_version"] == s["casflutter_version"]
    M = loadmat(out / "controller.mat")
    assert M["Ts"].item() == 0.0 and str(M["time_unit"][0]) == "s"
    assert [str(x[0]) for x in M["input_names"].ravel()] == [i["name"] for i in c["inputs"]]
    np.testing.assert_allclose(M["certified_V"].ravel(), design, rtol=1e-15)
    np.testing.assert_allclose(M["Vf_airspeed_m_s"].item(), 28.9 * Vf, rtol=1e-12)

    assert main(["verify", str(out / "plant.json"), str(out / "controller.json"),
                 "--json"]) == 0
    v = json.loads(capsys.readouterr().out)
    ctl = s["controller"]
    assert v["stable"] is ctl["stable"] is True and v["Vf"] == Vf
    assert v["hinf"]["gamma"] == pytest.approx(ctl["gamma"], rel=1e-6)
    assert v["small_gain_V"] == pytest.approx(ctl["small_gain_V"], rel=1e-6)
    assert v["exact_V"] == pytest.approx(ctl["lft_stable_V"], rel=1e-6)


def test_summary_and_manifest_record_version_seed_threads_and_units(reduced):
    import casflutter
    from casflutter._outputs import config_hash

    _, out, s = reduced
    assert s["seed"] == 3 and s["casflutter_version"] == casflutter.__version__
    assert set(s["threads"]) == {"env", "pools"} and s["threads"]["pools"]
    # the CLI pins every BLAS pool to one thread (bit-identical numbers)
    assert all(p["num_threads"] == 1 for p in s["threads"]["pools"])
    assert s["units"]["V"].startswith("speed index (V = U / U_ref")
    for key in ("flutter", "flutter_truth"):
        assert s[key]["airspeed_m_s"] == pytest.approx(28.9 * s[key]["V"], rel=1e-12)
    assert s["flags"]["controller_faster_than_nyquist"] is False
    m = json.loads((out / "manifest.json").read_text())
    assert m["complete"] is True and m["seed"] == 3
    assert m["casflutter_version"] == casflutter.__version__
    assert m["config_hash"] == config_hash(json.loads((out / "config.json").read_text()))
    assert m["completed_stages"] == [k for k in s["timings_s"] if k != "total"]
    assert set(m["files"]) == {p.name for p in out.iterdir()} - {"manifest.json"}
    assert m["threads"] == s["threads"]


def test_a_run_into_a_non_empty_folder_is_refused_before_any_work(reduced, monkeypatch,
                                                                  capsys):
    import casflutter.pipeline._model as driver

    cfg_path, out, _ = reduced
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}

    def no_work(*a, **k):
        raise AssertionError("the work started before the output folder was checked")

    monkeypatch.setattr(driver, "truth_records", no_work)
    assert main(["run", str(cfg_path), "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("casflutter: error: output folder ") and "--overwrite" in err
    assert "\n" not in err
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before


@pytest.mark.parametrize("flag", ["-q", "--quiet"])
def test_both_quiet_flags_silence_the_stage_progress(tmp_path, monkeypatch, flag):
    """``-q`` (the global flag) also silences the driver's stage lines, not only logging."""
    import casflutter.pipeline

    seen = {}

    class Stop(Exception):
        pass

    def fake_run(cfg, **kw):
        seen.update(kw)
        raise Stop

    monkeypatch.setattr(casflutter.pipeline, "run", fake_run)
    assert main(["run", "--out", str(tmp_path / "o"), flag]) != 0    # stopped in the driver
    assert seen["quiet"] is True
