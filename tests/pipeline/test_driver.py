"""One driver, ``run(config) -> RunResult``: the shipped configurations (the paper's study on
the seed wing and the flutter check on the typical section) run through it with a typed
result per stage, and the configuration's tables are the stages' own settings classes."""

import json
from dataclasses import fields, replace

import control
import numpy as np
import pytest

from casflutter._settings import field_names, settings_as
from casflutter.aeroelastic import AeroelasticLFT, AeroelasticSystem, FlutterResult
from casflutter.data import IOData
from casflutter.design import MultiSpeedDesign, SynthesisOptions
from casflutter.ident import (CommonDenominatorResult, IdentificationResult,
                              IdentificationSettings)
from casflutter.pipeline import (ClosedLoopChecks, ControllerSettings, DataSection, LcoResult,
                                 RomSection, RunResult, SuppressionStage, config_path,
                                 default_config_path, load_config, run)
from casflutter.realize import Realization
from casflutter.truth import RecordSettings, SuppressionResult, SuppressionSettings
from casflutter.verify import SpeedSweep, VerificationReport

#: the keys of summary.json of ``casflutter run`` (the report, sweeps and scripts read them)
SUMMARY_KEYS = {"problem", "V0", "n_sensors", "orders", "n_params", "fit_error_percent", "nf",
                "ns", "nae", "flutter", "flutter_truth", "lco", "controller", "suppression",
                "timings_s", "seed", "units", "flags", "casflutter_version", "threads", "route",
                "flutter_convective", "control_reversal_V"}

#: the default study (run.toml), cut to a few seconds per stage (an order-1 controller, a whole run)
STUDY_SMALL = {"data.duration": 4.0, "flutter.n_grid": 61, "lco.duration": 1.0,
               "controller.order": 1, "controller.max_outer": 1,
               "suppression": {"settle": 1.5, "ramp": 0.5, "hold": 1.5, "release": 1.0}}
#: the flutter check, with short simulations and sweeps
CHECK_SMALL = {"data.duration": 150.0, "controller.max_outer": 1, "closed_loop.duration": 30.0,
               "closed_loop.n_sweep": 40, "verify.n_sweep": 61, "flutter.n_grid": 121}


@pytest.fixture(scope="module")
def study():
    return run(load_config(default_config_path(), updates=STUDY_SMALL), quiet=True,
               write=False)


@pytest.fixture(scope="module")
def check():
    return run(load_config(config_path("typical_section", "flutter_check"),
                           updates=CHECK_SMALL), quiet=True, write=False)


def test_the_study_has_a_typed_field_per_stage(study):
    r = study
    assert isinstance(r, RunResult) and r.config.stages == ("lco", "controller", "suppression")
    assert isinstance(r.data, IOData) and isinstance(r.identification, IdentificationResult)
    assert isinstance(r.realization, Realization) and isinstance(r.system, AeroelasticSystem)
    assert isinstance(r.flutter, FlutterResult) and isinstance(r.flutter_truth, FlutterResult)
    assert isinstance(r.lco, LcoResult) and isinstance(r.lft, AeroelasticLFT)
    assert isinstance(r.design, MultiSpeedDesign) and r.synthesis is None   # method multispeed
    assert isinstance(r.controller, control.StateSpace)
    assert isinstance(r.verification, VerificationReport)
    assert isinstance(r.suppression, SuppressionStage)
    assert all(isinstance(s, SuppressionResult) for s in r.suppression.runs)
    assert r.closed_loop is None and r.parametric is None and r.flutter_frozen is None
    # the stages read one another's results: the LFT sits at the ROM's flutter speed, the
    # LCO a little above the flutter point of the sampled-data loop the ROM runs in, the
    # suppression above the truth's
    assert r.lft.Vf == r.flutter.Vf
    assert r.lco.V == pytest.approx(r.config.lco.speed_factor * r.lco.V_hopf_loop)
    assert r.suppression.V_flutter == r.Vf_truth and r.suppression.reference == "truth"
    assert [s.V for s in r.suppression.runs] == pytest.approx(
        [f * r.Vf_truth for f in r.config.suppression.speed_factors])
    assert [s.speed_factor for s in r.suppression.runs] == [1.05, 1.2]
    assert r.suppression.at(1.2) is r.suppression.runs[1]
    assert r.controller.nstates == r.config.controller.order == 1


def test_each_suppression_run_says_whether_the_truths_linear_loop_is_stable_there(
        study, wing_sensor_plant):
    """An attenuation is that of a suppressed LCO only where the truth's linearised loop with
    the controller is stable; each run says whether its speed lies inside the truth's
    certified interval, checked here against the loop's eigenvalues computed from the truth's
    state space (python-control's feedback, not the verification layer)."""
    r = study
    stage = r.suppression
    lower, upper = r.truth_stable_V
    assert stage.certified == (lower, upper)

    def worst(V):
        G = wing_sensor_plant(r, V)
        return float(np.max(control.feedback(G, r.controller, sign=1).poles().real))

    for run, ok in zip(stage.runs, stage.linear_loop_certified):
        assert ok == (lower <= run.V <= upper)
        if ok:
            assert worst(run.V) < 0
        else:      # the loop loses stability between the certificate's end and the run
            assert upper < run.V and worst(min(1.01 * upper, run.V)) > 0
    runs = r.summary()["suppression"]["runs"]
    assert [run["linear_loop_certified"] for run in runs] == list(stage.linear_loop_certified)
    # the same runs against a certificate that ends between them, and without one
    middle = 0.5 * (stage.runs[0].V + stage.runs[1].V)
    assert replace(stage, certified=(0.0, middle)).linear_loop_certified == (True, False)
    assert replace(stage, certified=None).linear_loop_certified == (None, None)


def test_the_rom_lco_speed_is_above_its_loops_own_flutter_point(study):
    """The LCO stage's flutter point of the ROM loop is the Neimark-Sacker point that the LCO
    continuation finds on the same map (an independent search: its own grid, its own
    crossing), and it is not the continuous exact-order ΣAE's Hopf speed: the sampling moves
    it by more than the 5 % the LCO is simulated above it (a speed above the continuous
    point lies below the loop's, where the ROM's response decays)."""
    from casflutter.lco import LCOSettings, rom_lco_branch

    r = study
    branch = rom_lco_branch(r.identification.model, r.system.structure, r.config.flutter.V_range,
                            LCOSettings(max_points=3, n_grid=241))
    assert r.lco.V_hopf_loop == pytest.approx(branch.hopf.V, rel=1e-6)
    assert r.lco.V_hopf_loop > r.config.lco.speed_factor * r.lco.V_hopf_exact_order


def test_summary_keeps_the_keys_of_summary_json(study):
    s = study.summary()
    # the multi-speed design has a required interval (controller.interval): its check too
    assert set(s) == SUMMARY_KEYS | {"verification"}
    lo, hi = study.config.controller.interval
    assert s["verification"]["required_V"] == [lo, hi]
    assert s["verification"]["interval_ok"] == (s["controller"]["stable_interval"][0] <= lo
                                                and s["controller"]["stable_interval"][1] >= hi)
    # one H∞ iteration (controller.max_outer = 1) cannot meet the stopping test: the run
    # says the optimisation did not converge, in the summary and in the design's message
    c = s["controller"]
    assert c["hinf_converged"] is False and c["hinf_iterations"] == 1
    assert "without converging" in c["design_message"]
    json.dumps(s, allow_nan=False)   # plain JSON values, no NaN
    assert s["flutter"]["V"] == study.flutter.Vf
    assert s["controller"]["lft_stable_V"] == list(study.verification.exact_V)
    assert s["controller"]["stable_interval"] == list(study.rom_stable_V)
    sup = study.suppression
    assert s["suppression"]["attenuation_percent"] == sup.runs[0].attenuation_percent
    runs = s["suppression"]["runs"]
    assert [run["speed_factor"] for run in runs] == list(study.config.suppression.speed_factors)
    assert [run["attenuation_percent"] for run in runs] == list(sup.attenuation_percent)
    assert {"V", "open_loop_rms", "closed_loop_rms", "flap_peak", "flap_rate_peak"} <= set(runs[0])
    assert set(s["timings_s"]) == {"data", "rom", "realize", "structure", "flutter", "lco",
                                   "controller", "suppression", "total"}


def test_the_flutter_check_is_a_configuration_of_the_same_driver(check):
    r = check
    assert r.config.stages == ("controller", "closed_loop")
    assert isinstance(r.identification, CommonDenominatorResult)
    assert isinstance(r.closed_loop, ClosedLoopChecks) and isinstance(r.rom_sweep, SpeedSweep)
    assert r.lco is None and r.suppression is None
    # identified again at the ROM's own flutter speed until the two agree
    V0, Vf = r.identification_history[-1]
    assert len(r.identification_history) > 1 and abs(Vf - V0) <= r.config.rom.v0_rtol * Vf
    assert r.config.data.V0 == r.identification_history[0][0]
    s = r.summary()
    hwl_only = {"flutter_convective", "control_reversal_V"}      # a common-denominator ROM
    assert SUMMARY_KEYS - hwl_only <= set(s) and s["lco"] is None and s["suppression"] is None
    assert {"v0_history", "verification", "closed_loop"} <= set(s)
    assert s["verification"]["interval_ok"] == r.interval_ok
    json.dumps(s, allow_nan=False)
    # the closed-loop stage has a flap actuator: the controller's poles are checked against
    # its bandwidth and against the Nyquist frequency of the records
    import numpy as np
    fastest = np.max(np.abs(np.linalg.eigvals(np.asarray(r.controller.A))))
    assert s["flags"] == {
        "controller_faster_than_nyquist": bool(fastest > np.pi / r.data.dt),
        "controller_faster_than_actuator": bool(fastest > r.config.closed_loop.actuator_omega)}
    assert s["units"]["V"].startswith("speed index (V = U / (b omega_theta)")
    assert s["units"]["airspeed_m_s"] is None and "airspeed_m_s" not in s["flutter"]


@pytest.mark.parametrize("section, stage_class", [
    (ControllerSettings, SynthesisOptions), (RomSection, IdentificationSettings),
    (DataSection, RecordSettings)])
def test_every_field_of_a_stages_settings_is_a_configuration_key(section, stage_class):
    """The sections extend the stages' own classes: a field the stage adds is a key at once,
    with the stage's default and the stage's own check."""
    keys = field_names(section)
    for f in fields(stage_class):
        assert f.name in keys
    # the defaults the sections change: those of the seed wing's study (run.toml)
    study = {RecordSettings: {"coupling_delay": 1},
             IdentificationSettings: {"regularization": 1e-6},
             SynthesisOptions: {"strictly_proper": True, "zero_start": False, "max_outer": 80,
                                "extra_outer": 320,
                                "max_stab_rounds": 300}}
    assert settings_as(section(), stage_class) == stage_class(**study[stage_class])


def test_a_configured_value_reaches_the_stage():
    cfg = load_config(updates={"controller.abandon_after": 7, "controller.tol": 1e-4,
                               "rom.shooting_interval": 20, "data.taper": 0.2,
                               "suppression.hold": 3.0})
    opts = settings_as(cfg.controller, SynthesisOptions)
    assert (opts.abandon_after, opts.tol) == (7, 1e-4)
    assert settings_as(cfg.rom, IdentificationSettings).shooting_interval == 20
    assert settings_as(cfg.data, RecordSettings).taper == 0.2
    assert isinstance(cfg.suppression, SuppressionSettings) and cfg.suppression.hold == 3.0


def test_the_rom_route_needs_no_controller():
    """Without a stage that needs the ROM's flutter speed, a range without flutter is a
    result (``no_crossing``), not an error."""
    cfg = load_config(config_path("typical_section", "flutter"),
                      updates={"stages": [], "data.duration": 100.0, "flutter.n_grid": 41,
                               "flutter.V_range": [0.5, 1.5]})
    r = run(cfg, quiet=True, write=False)
    assert r.flutter.status == "no_crossing" and r.Vf is None and r.verification is None
    assert r.summary()["controller"] is None and "Vf error n/a" in r.explanation()


# ---------------------------------------------------------------------- the output folder
def _tree(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_the_output_folder_is_replaced_whole_or_not_at_all(study, tmp_path, monkeypatch):
    import casflutter.pipeline._exports as exports
    from casflutter._outputs import config_hash
    from casflutter.errors import OutputError

    target = tmp_path / "out"
    files = exports.write_outputs(target, study)
    first = _tree(target)
    assert {"summary.json", "controller.json", "controller.mat", "plant.json", "config.json",
            "manifest.json", "report.html", "rom.npz", "fig7_rom_fit.png"} <= set(first)
    assert all(p.parent == target and p.is_file() for p in files.values())
    m = json.loads(first["manifest.json"])
    assert set(m["files"]) == set(first) - {"manifest.json"}
    assert m["config_hash"] == config_hash(json.loads(first["config.json"]))
    assert m["completed_stages"] == [k for k in study.timings if k != "total"]
    assert m["seed"] == study.config.seed and m["started"] <= m["finished"]
    # an existing non-empty folder is refused without overwrite
    with pytest.raises(OutputError, match="not empty"):
        exports.write_outputs(target, study)
    assert _tree(target) == first

    # a crash while the files are written leaves the previous run in place
    def crash(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr(exports, "write_figures", crash)
    with pytest.raises(RuntimeError, match="disk full"):
        exports.write_outputs(target, study, overwrite=True)
    assert _tree(target) == first and sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    # overwrite: the new folder replaces the old one as a whole (no stale figure stays)
    monkeypatch.setattr(exports, "write_figures", lambda out, result: {})
    exports.write_outputs(target, study, overwrite=True)
    new = _tree(target)
    assert "fig7_rom_fit.png" not in new and new["config.json"] == first["config.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_plant_and_controller_files_reproduce_the_verification(study, tmp_path, capsys):
    """``casflutter verify plant.json controller.json`` on a run's own exports gives the
    run's verification: stability, H-inf norm to 1e-6 and the same speed intervals."""
    import casflutter.pipeline._exports as exports
    from casflutter.cli import main
    from casflutter.verify import save_json

    ver = study.verification
    plant, ctrl = tmp_path / "plant.json", tmp_path / "controller.json"
    save_json(exports.plant_document(study), plant)
    save_json(exports.controller_document(study), ctrl)
    assert main(["verify", str(plant), str(ctrl), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["stable"] is ver.stable is True
    assert got["Vf"] == study.Vf and got["n_delta"] == study.lft.n_delta
    assert got["hinf"]["gamma"] == pytest.approx(ver.gamma, rel=1e-6)
    assert got["hinf_delta"]["gamma"] == pytest.approx(ver.hinf_delta.gamma, rel=1e-6)
    for key in ("small_gain_V", "small_gain_V_delta", "exact_V"):
        assert got[key] == pytest.approx(list(getattr(ver, key)), rel=1e-6), key


def test_the_controller_is_certified_on_the_truth_as_well(study, wing_sensor_plant):
    """The run's controller on the truth's own linearisation (flap behind the servo of
    controller.servo_omega): the certified interval against eigenvalues computed here
    from the truth's state space, its accelerometer rows and python-control's feedback."""
    r = study
    lower, upper = r.truth_stable_V
    assert lower < r.config.data.V0 < upper
    servo = r.config.controller.servo_omega

    def worst(V):
        G = wing_sensor_plant(r, V)
        return float(np.max(control.feedback(G, r.controller, sign=1).poles().real))

    assert worst(0.5 * (max(lower, 0.05) + upper)) < 0
    assert worst(0.999 * upper) < 0 < worst(1.01 * upper)
    s = r.summary()["controller"]
    assert s["truth_stable_interval"] == [lower, upper]
    assert s["servo_omega"] == servo
