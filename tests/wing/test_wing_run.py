"""The driver and the CLI on wing files: route 1 (records) against the seed wing's own ROM,
route 2 (Q(ik)) against the published Goland flutter point."""

import json
from pathlib import Path

import numpy as np
import pytest

from casflutter.cli import main
from casflutter.pipeline import load_config, run
from casflutter.truth import problem_definition

ROOT = Path(__file__).resolve().parents[2] / "problems"
EXAMPLE_RUN = ROOT / "example_wing" / "run.toml"
GAF_RUN = ROOT / "goland_gaf" / "run.toml"

#: the settings make_records.py wrote the example wing's records with
RECORDS = {"data.V0": 0.69, "data.dt": 0.004, "data.duration": 4.0, "data.band": [0.2, 60.0],
           "data.amplitude": 0.01, "data.coupling_delay": 1}


def test_example_wing_flutter_equals_the_seed_wing_rom_from_its_own_records(monkeypatch,
                                                                             tmp_path):
    """Route 1: the wing file (modal data typed in Hz, records read from NPZ and .mat in
    single precision) gives the flutter point of the ROM identified on the seed-wing truth's
    records taken in memory with the same settings (an independent path through the truth
    simulator, its modal structure and its sensors).  Tolerance 1e-4: the records are stored
    in single precision (relative rounding 6e-8)."""
    monkeypatch.chdir(tmp_path)                     # the wing file is found beside run.toml
    wing = run(load_config(EXAMPLE_RUN, updates={"stages": []}), quiet=True, write=False)
    ref = run(load_config(EXAMPLE_RUN, updates={"stages": [], "problem.name": "seed_wing",
                                                **RECORDS}), quiet=True, write=False)
    assert ref.truth is not None and wing.truth is None
    assert wing.Vf == pytest.approx(ref.Vf, rel=1e-4)
    assert wing.flutter.omega_f == pytest.approx(ref.flutter.omega_f, rel=1e-4)
    assert wing.flutter.flutter_mode == ref.flutter.flutter_mode
    assert wing.config.data.V0 == 0.69
    assert wing.flutter_truth is None and "flutter_truth" in wing.skipped
    s = wing.summary()
    assert s["flutter"]["airspeed_m_s"] == pytest.approx(wing.Vf * 28.9)
    assert s["flutter_truth"] is None and "flutter_truth" in s["skipped"]


def test_example_wing_study_runs_every_stage_and_records_the_skipped_ones(tmp_path, capsys):
    """identify -> realize -> loop -> flutter -> LFT -> synthesis -> verify through
    ``casflutter run``; the truth's flutter search is skipped and listed (once on stdout
    with ``-q``, where the log does not say it)."""
    out = tmp_path / "out"
    assert main(["run", str(EXAMPLE_RUN), "--out", str(out), "--quiet", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert set(s["skipped"]) == {"flutter_truth"}
    assert all("truth simulator" in why for why in s["skipped"].values())
    assert s["suppression"] is None and s["lco"] is None
    # the controller's verified exact stable interval holds the configured [0.9, 1.05] Vf
    c = s["controller"]
    Vf = s["flutter"]["V"]
    assert c["stable"] and c["lft_stable_V"][0] <= 0.9 * Vf and c["lft_stable_V"][1] >= 1.05 * Vf
    assert c["stable_interval"][0] <= 0.9 * Vf and c["stable_interval"][1] >= 1.05 * Vf
    assert json.loads((out / "summary.json").read_text())["skipped"] == s["skipped"]
    assert (out / "controller.json").is_file() and not (out / "fig8_flap_pulses.png").exists()
    assert main(["-q", "run", str(EXAMPLE_RUN), "--out", str(out), "--overwrite"]) == 0
    text = capsys.readouterr()
    assert text.out.count("skipped") == 1 and "truth Vf" not in text.err + text.out


def test_lco_stage_on_a_linear_rom_is_skipped_with_its_reason(caplog):
    """A linear ROM has no limit cycle: the LCO stage is skipped before any work, with the
    reason logged once and recorded, instead of a 'divergence' reported as an LCO."""
    cfg = load_config(EXAMPLE_RUN, updates={"stages": ["lco"]})
    with caplog.at_level("INFO", logger="casflutter"):
        r = run(cfg, quiet=True, write=False)
    assert r.lco is None and "lco" in r.skipped
    assert "linear" in r.skipped["lco"] and 'rom.method = "hwl"' in r.skipped["lco"]
    notes = [m for m in caplog.messages if "lco" in m]
    assert len(notes) == 1 and "linear" in notes[0] and "has no limit cycle" in notes[0]
    assert "truth_lco" not in r.skipped              # the whole stage, said once


def test_goland_gaf_flutter_through_the_cli_within_one_percent_of_published(capsys):
    """Route 2: ``casflutter flutter problems/goland_gaf`` (Roger's RFA of the exact-
    Theodorsen Q(ik), ΣAE(U) in m/s) and the p–k solution on the same table, each within 1 %
    of Goland's published 137.2 m/s and 70.7 rad/s (read from problems/goland)."""
    ref = problem_definition("goland")["reference"]["flutter"]
    assert main(["flutter", str(ROOT / "goland_gaf"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["units"] == {"airspeed": "m/s", "omega": "rad/s", "k": "omega b / U"}
    for key in ("rfa_flutter", "pk"):
        assert doc[key]["airspeed_m_s"] == pytest.approx(ref["airspeed"], rel=0.01), key
        assert doc[key]["omega_rad_s"] == pytest.approx(ref["frequency"], rel=0.01), key
        assert doc[key]["mode"] == 2                       # torsion 1
    # the RFA and p-k agree with each other closer than with the published value
    assert doc["rfa_flutter"]["airspeed_m_s"] == pytest.approx(doc["pk"]["airspeed_m_s"],
                                                               rel=0.005)
    assert doc["rfa"]["poly_order"] == 0 and doc["rfa"]["fit_error"] < 0.05


def test_gaf_problem_flags_that_do_not_apply_are_refused(capsys):
    assert main(["flutter", str(ROOT / "goland_gaf"), "--v0", "100"]) != 0
    assert "--v0 does not apply" in capsys.readouterr().err
    assert main(["flutter", str(ROOT / "goland_gaf"), "--set", "alpha=2"]) != 0
    assert "no parameters to change" in capsys.readouterr().err


def test_flutter_command_on_a_records_wing_file_points_at_casflutter_run(capsys):
    assert main(["flutter", "example_wing"]) != 0
    assert "casflutter run" in capsys.readouterr().err


@pytest.mark.slow
def test_goland_gaf_study_designs_and_verifies_a_controller_on_the_rfa_lft():
    """The controller stage on Σf of the RFA frozen at Uf: the frozen ΣAE(V) flutters exactly
    at Uf / U_ref, and the closed loop with the designed controller is stable (dense
    eigenvalue sweep) at 1.05 and 1.1 Uf, where the RFA system itself is unstable."""
    r = run(load_config(GAF_RUN, updates={"verify.sweep": [1.05, 1.1], "verify.n_sweep": 11}),
            quiet=True, write=False)
    U_ref = r.problem.U_ref
    assert r.Vf == pytest.approx(r.rfa_flutter.Vf / U_ref, rel=1e-6)
    assert r.controller is not None and r.verification is not None
    assert np.all(r.rom_sweep.stable)
    lo, hi = r.verification.exact_V          # the exact interval holds the swept speeds
    assert lo < 1.05 * r.Vf and hi > 1.1 * r.Vf
    for f in (1.05, 1.1):
        A = r.rfa_system.state_matrix(f * r.rfa_flutter.Vf)
        assert np.max(np.linalg.eigvals(A).real) > 0
    assert set(r.skipped) == {"flutter_truth"}
