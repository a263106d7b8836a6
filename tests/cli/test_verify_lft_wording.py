"""``casflutter verify PLANT.json CONTROLLER.json`` on the LFT route says what it checked
(stability over the interval by the LFT's exact or small-gain test, never "robust": no
margins are checked there), and a run's summary.json given as the plant is named for what
it is, with the file to pass instead (probe 5, P10)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.cli import main
from casflutter.verify import controller_to_json, plant_to_json, save_json

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verify"))
from verify_helpers import lqg_controller, wing, wing_lft, wing_plant_at  # noqa: E402

VF = 1.0


def _toy():
    """Two-mode toy wing of the verification tests (state sensors; the LFT of eq. 14 at
    Vf) and an LQG controller designed at Vf."""
    w = wing("state")
    Kk = lqg_controller(wing_plant_at(w, VF), np.zeros((1, w["N"])))
    return wing_lft(w, VF), Kk, lambda V: wing_plant_at(w, V)


def _upper_end(plant_at, Kk) -> float:
    """Independent check: the first speed above Vf where the closed loop ``u = K y`` at V
    (built directly, no LFT) has a pole in the right half-plane, by a dense sweep and
    bisection."""
    def abscissa(V):
        return np.max(np.linalg.eigvals(
            np.asarray(control.feedback(plant_at(V), Kk, sign=1).A)).real)

    grid = np.linspace(VF, 10.0, 4000)
    k = next(i for i, V in enumerate(grid) if abscissa(V) >= 0)
    lo, hi = grid[k - 1], grid[k]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if abscissa(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


@pytest.fixture
def files(tmp_path):
    lft, Kk, plant_at = _toy()
    save_json(plant_to_json(lft, 2, 1, Vf=VF, n_delta=2), tmp_path / "plant.json")
    save_json(controller_to_json(Kk), tmp_path / "controller.json")
    return tmp_path, _upper_end(plant_at, Kk)


def _verdict_line(capsys) -> str:
    return capsys.readouterr().out.strip().splitlines()[-1].strip()


def test_lft_verdict_says_stable_by_which_test_and_never_robust(files, capsys):
    folder, V_end = files
    P, K = str(folder / "plant.json"), str(folder / "controller.json")
    assert V_end > 1.2          # the toy's closed loop holds somewhat above Vf
    inside = ["0.9", f"{1 + 0.5 * (V_end - 1):.6g}"]
    assert main(["verify", P, K, "--require-v", *inside]) == 0
    line = _verdict_line(capsys)
    assert "robust" not in line
    assert line.startswith(f"verdict: PASSED, stable at every V in [{inside[0]}, {inside[1]}]")
    assert "exact stability interval" in line and "no gain or phase margins" in line
    # the exact interval it prints ends where the closed loop built at each V goes unstable
    ends = [float(x) for x in line.split("covers it")[0].rsplit("(", 1)[1].rstrip(") ")
            .split(",")]
    assert ends[1] == pytest.approx(V_end, rel=1e-4)
    # the JSON: the same verdict under its own name, and the small-gain test reported
    assert main(["verify", P, K, "--require-v", *inside, "--json"]) == 0
    v = json.loads(capsys.readouterr().out)["verdict"]
    assert v["stable_over_required"] is True and v["passed"] is True
    assert "robust" not in v["reason"]
    assert ("and so does the small-gain interval" in v["reason"]) is v["small_gain_covers"]
    # beyond the exact interval: FAILED, said as stability, with the interval's end
    beyond = ["0.9", f"{1.05 * V_end:.6g}"]
    assert main(["verify", P, K, "--require-v", *beyond]) == 1
    line = _verdict_line(capsys)
    assert line.startswith(f"verdict: FAILED, not stable over the required V in [0.9, "
                           f"{beyond[1]}]")
    assert "robust" not in line and f"{V_end:.4g}" in line


def test_run_summary_given_as_plant_names_the_plant_to_pass(files, capsys):
    folder, _ = files
    summary = {"problem": "nata.toml", "route": "truth", "flutter": None,
               "timings_s": {"total": 1.0}, "controller": None}
    (folder / "summary.json").write_text(json.dumps(summary))
    K = str(folder / "controller.json")
    assert main(["verify", str(folder / "summary.json"), K]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "None" not in err and "'D'" not in err
    assert "summary.json of a casflutter run" in err and "not a plant" in err
    assert f"pass {folder / 'plant.json'}" in err
    # given as the controller: the controller.json beside it
    assert main(["verify", str(folder / "plant.json"), str(folder / "summary.json")]) == 1
    err = capsys.readouterr().err
    assert "not a controller" in err and f"pass {folder / 'controller.json'}" in err
    # a run folder without plant.json (no controller stage): says what writes one
    other = folder / "run2"
    other.mkdir()
    (other / "summary.json").write_text(json.dumps(summary))
    assert main(["verify", str(other / "summary.json"), K]) == 1
    err = capsys.readouterr().err
    assert "has no plant.json" in err and "'controller' stage" in err
    # a plant family's run: the family (the run's problem) is what to verify
    fam = folder / "run3"
    fam.mkdir()
    (fam / "summary.json").write_text(json.dumps({**summary, "route": "family",
                                                  "problem": "goland_4flaps"}))
    assert main(["verify", str(fam / "summary.json"), K]) == 1
    assert "casflutter verify goland_4flaps" in capsys.readouterr().err
