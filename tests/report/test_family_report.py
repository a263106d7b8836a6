"""``report.html`` of a run on a plant family file: the family's design report in its own
units, not the paper's reproduction (no Table I, no paper column, no "ROM loop").

Truth used: the numbers of the run's own ``summary.json`` (the certified interval, the
open-loop flutter speed and frequency, the controller's order and interval), written here
with :func:`casflutter._format.sig` independently of the report's helpers, and the PNG files
the run wrote to its folder.  The paper's report is checked on a seed-wing summary.
"""

from __future__ import annotations

import copy
import json
import re

import pytest

from casflutter._format import sig
from casflutter.cli import main
from casflutter.report import html_report, write_html
from casflutter.report._html import PAPER_TABLE_I, _family_warnings

#: text of the paper's reproduction that a family report must not carry
PAPER_TEXT = ("Reproduction of K.-Y. Lum", "ACC 2016", "Table I", "ROM loop", "paper",
              "this run (ROM)", "flutter speed index Vf", "LCO attenuation", "order of ΣAE")


@pytest.fixture(scope="module")
def family_run(goland_family_run):
    """The order-2 design on goland_4flaps over [60, 150] m/s without an H∞ phase
    (tests/conftest.py) and its report."""
    out, summary = goland_family_run
    return out, summary, (out / "report.html").read_text(encoding="utf-8")


def _text(page: str) -> str:
    """The page's visible text, tags and embedded images removed, whitespace collapsed."""
    page = re.sub(r"<style>.*?</style>", " ", page, flags=re.S)
    page = re.sub(r"<[^>]+>", " ", page)
    return re.sub(r"\s+", " ", page.replace("&#x27;", "'"))


def _row(page: str, name: str) -> str:
    m = re.search(r"<tr><td>" + re.escape(name) + r"</td><td>(.*?)</td></tr>", page, re.S)
    assert m, f"no row {name!r}"
    return m.group(1)


def test_the_family_report_names_the_family_and_has_no_paper_comparison(family_run):
    out, s, page = family_run
    assert s["route"] == "family"
    h1 = re.search(r"<h1>(.*?)</h1>", page).group(1)
    assert "plant family goland_4flaps" in h1
    text = _text(page)
    for phrase in PAPER_TEXT:
        assert phrase not in text, phrase
    for quantity in PAPER_TABLE_I:
        assert f"<td>{quantity}</td>" not in page, quantity


def test_the_family_report_gives_its_description_in_its_own_units(family_run):
    _, s, page = family_run
    fam = s["family"]
    assert fam["speed_unit"] == "m/s" and fam["time_unit"] == "s"
    assert _row(page, "speed range") == f"{sig(fam['speed_range'], 4)} m/s"
    assert _row(page, "feedback sign").startswith("negative")
    assert "4: flap_1, flap_2, flap_3, flap_4" in _row(page, "controls (the controller&#x27;s "
                                                             "outputs)")
    for name in fam["measurements"]:
        assert name in _row(page, "measurements (the controller&#x27;s inputs)")
    assert _row(page, "states") == "50 analysed"


def test_the_open_loop_flutter_speed_and_frequency_are_in_the_familys_units(family_run):
    _, s, page = family_run
    fl = s["flutter"]
    c = s["family"]["crossings"][0]
    assert f"Open-loop flutter speed {sig(fl['V'], 4)} m/s, at {sig(fl['freq_hz'], 4)} Hz " \
           f"({sig(c['omega_rad_s'], 4)} rad/s)" in _text(page)


def test_the_controller_and_its_certificate_are_reported(family_run):
    _, s, page = family_run
    c = s["controller"]
    assert _row(page, "order") == str(c["order"]) == "2"
    assert _row(page, "design interval").startswith("(60, 150) m/s")
    held = ("held: the whole interval" if c["held"]
            else f"not held: reached up to {sig(c['reach'], 4)} m/s")
    assert _row(page, "interval held") == held
    # no H∞ phase with hinf_speeds = 0: no γ to report
    assert "no H∞ phase" in _row(page, "H∞ objective γ")
    lo, hi = c["stable_interval"]
    assert _row(page, "certified stable interval (design family)").startswith(
        f"({sig(lo, 4)}, {sig(hi, 4)}) m/s")
    assert _row(page, "absolute / robust flutter speed (design family)") == (
        f"{sig(c['absolute_flutter_speed'], 4)} m/s / {sig(c['robust_flutter_speed'], 4)} m/s")
    assert _row(page, "required interval") == "(60, 150) m/s: covered"


def test_every_figure_of_the_folder_is_embedded(family_run):
    out, _, page = family_run
    pngs = sorted(out.glob("*.png"))
    assert {p.name for p in pngs} >= {"vg_vf.png", "margins_design.png"}
    assert page.count('src="data:image/png;base64,') == len(pngs)
    assert "plant family goland_4flaps&#x27;s open-loop branches against the speed [m/s]" \
        in page


def test_the_warnings_of_the_run_are_listed(family_run):
    _, s, _ = family_run
    s = copy.deepcopy(s)
    c = s["controller"]
    c.update(held=False, reach=120.0, design_message="order 1 reaches [60, 120] only",
             hinf_converged=False, hinf_iterations=80, stable_interval=[60.0, 170.0],
             robust_flutter_speed=130.0,
             robust_flutter_reason="input 'flap_4': gain margin falls below 6 dB")
    c["poles"] = dict(c.get("poles") or {}, warnings=["the controller itself is unstable"])
    s["verification"] = dict(s["verification"], interval_ok=False, margins=[6.0, 45.0])
    warnings = _family_warnings(s)
    assert any("did not hold the requested interval (60, 150) m/s" in w
               and "order 1 reaches [60, 120] only" in w for w in warnings)
    assert any("stopped after 80 iterations without converging" in w for w in warnings)
    assert any("does not cover the required (60, 150) m/s" in w for w in warnings)
    assert any("margins (6 dB / 45 deg) hold only to 130 m/s (input 'flap_4': gain margin "
               "falls below 6 dB)" in w for w in warnings)
    assert any("the controller itself is unstable" in w for w in warnings)
    page = html_report(s, {})
    assert page.count('<li class="flag">') == len(warnings) == 5
    # a run with nothing to flag has no warnings
    c.update(held=True, hinf_converged=None, robust_flutter_speed=None)
    c["poles"]["warnings"] = []
    s["verification"]["interval_ok"] = True
    assert _family_warnings(s) == []
    assert "<h2>Warnings</h2>" not in html_report(s, {})


def test_gamma_is_said_for_what_it_is_from_the_runs_configuration(family_run, tmp_path):
    _, s, _ = family_run
    s = copy.deepcopy(s)
    s["controller"].update(design_gamma=1.437, hinf_converged=True, hinf_iterations=12)
    (tmp_path / "config.json").write_text(json.dumps(
        {"controller": {"hinf_objective": "sensitivity", "hinf_speeds": 5,
                        "flap_rate_weight": 0.0}}))
    page = write_html(tmp_path, s, {}).read_text(encoding="utf-8")
    gamma = _row(page, "H∞ objective γ")
    assert gamma.startswith("1.437: the largest H∞ norm, over the design&#x27;s 5 H∞ speeds")
    assert "output and input sensitivities" in gamma
    assert 'hinf_objective = &quot;sensitivity&quot;' in gamma
    assert _row(page, "H∞ phase converged") == "yes, after 12 iterations"


def test_a_family_in_the_speed_index_and_left_out_states(family_run):
    _, s, _ = family_run
    s = copy.deepcopy(s)
    s["family"].update(speed_unit="speed index", time_unit="b/U", n_states_file=52,
                       left_out_states=[3, 7])
    page = html_report(s, {})
    assert _row(page, "speed range") == "(60, 200) (speed index)"
    assert "cycles per b/U" in _text(page) and " Hz" not in _text(page)
    assert "50 analysed of the file's 52; left out (0-based) [3, 7]" in _row(page, "states")


#: a seed-wing run's summary (the paper's route)
PAPER_SUMMARY = {
    "problem": "seed_wing", "route": "truth", "seed": 0, "V0": 0.69, "n_sensors": 2,
    "orders": [3, 1, 1, 1, 2, 2], "fit_error_percent": [0.5, 2.8, 0.4, 0.2, 0.9], "nf": 15,
    "ns": 10, "nae": 25, "flutter": {"V": 1.19999, "mode": 2},
    "flutter_truth": {"V": 1.08499, "mode": 2},
    "lco": {"freq_hz": 9.2855, "truth_freq_hz": 9.3758, "truth_kind": "lco"},
    "controller": {"order": 3, "stable_interval": [0.0, 1.76]},
    "suppression": {"attenuation_percent": 99.99}, "timings_s": {"rom": 0.5, "total": 70.0},
}


def test_the_paper_problems_report_keeps_its_table_i(tmp_path):
    for route in ("truth", "wing", None):
        s = dict(PAPER_SUMMARY, route=route)
        page = write_html(tmp_path, s, {}).read_text(encoding="utf-8")
        assert "Reproduction of K.-Y. Lum et al., ACC 2016" in page
        assert "<h2>Table I</h2>" in page
        for quantity, paper in PAPER_TABLE_I.items():
            assert f"<td>{quantity}</td>" in page
        assert "plant family" not in page
