"""JSON round trips and the ``casflutter verify`` command (on temp files and on a
COMPleib plant copied into tests/verify/data)."""

from __future__ import annotations

import json
from pathlib import Path

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.cli import main
from casflutter.errors import DataError, DimensionError
from casflutter.verify import (controller_from_json, controller_to_json, load_plant,
                               plant_from_json, plant_to_json, save_json, verify_controller)
from verify_helpers import dense_peak, lqg_controller, wing, wing_lft, wing_plant_at

DATA = Path(__file__).parent / "data"


def test_plant_and_controller_round_trip(tmp_path):
    P = wing_lft(wing("accel"), 1.0)
    d = json.loads(json.dumps(plant_to_json(P, 2, 1, Vf=1.0, n_delta=2, name="toy")))
    back = plant_from_json(d)
    assert (back.nmeas, back.ncon, back.Vf, back.n_delta, back.name) == (2, 1, 1.0, 2, "toy")
    for a, b in zip((P.A, P.B, P.C, P.D), (back.sys.A, back.sys.B, back.sys.C, back.sys.D)):
        assert_allclose(np.asarray(b), np.asarray(a), rtol=0, atol=0)
    # static gain: 0 states survive the round trip
    Ks = controller_from_json(json.loads(json.dumps(controller_to_json(np.array([[1.0, -2.0]])))))
    assert Ks.nstates == 0 and Ks.ninputs == 2 and Ks.noutputs == 1
    # hand-written static controller with D only
    assert controller_from_json({"D": [[0.5, 0.5]]}).nstates == 0
    with pytest.raises(DimensionError, match="inconsistent shapes"):
        controller_from_json({"A": [[1.0]], "B": [[1.0, 2.0]], "C": [[1.0], [2.0]],
                              "D": [[0.0]]})
    with pytest.raises(DataError, match="'D' is missing"):
        controller_from_json({"A": [[1.0]]})


def test_compleib_plant_is_partitioned_from_the_file():
    raw = json.loads((DATA / "AC4.json").read_text())
    pd_ = load_plant(DATA / "AC4.json")
    assert pd_.source_format == "compleib"
    assert (pd_.nmeas, pd_.ncon) == (raw["ny"], raw["nu"])
    assert pd_.sys.ninputs == raw["nw"] + raw["nu"] and pd_.sys.noutputs == raw["nz"] + raw["ny"]
    assert_allclose(np.asarray(pd_.sys.B)[:, raw["nw"]:], raw["B"])
    assert_allclose(np.asarray(pd_.sys.C)[raw["nz"]:], raw["C"])
    assert_allclose(np.asarray(pd_.sys.D)[:raw["nz"], :raw["nw"]], raw["D11"])


def test_compleib_plant_with_b2_c2_keys_is_the_same_plant(tmp_path):
    """Some COMPleib exports name B and C as B2 and C2 (load_compleib reads both)."""
    raw = json.loads((DATA / "AC4.json").read_text())
    raw["B2"], raw["C2"] = raw.pop("B"), raw.pop("C")
    (tmp_path / "AC4.json").write_text(json.dumps(raw))
    a, b = load_plant(DATA / "AC4.json").sys, load_plant(tmp_path / "AC4.json").sys
    for x, y in zip((a.A, a.B, a.C, a.D), (b.A, b.B, b.C, b.D)):
        assert_allclose(np.asarray(y), np.asarray(x), rtol=0, atol=0)


def test_cli_on_compleib_plant_json_output(tmp_path, capsys):
    pd_ = load_plant(DATA / "AC4.json")
    A, B, C = (np.asarray(M) for M in (pd_.sys.A, pd_.sys.B, pd_.sys.C))
    P22 = control.ss(A, B[:, -1:], C[-2:], np.zeros((2, 1)))
    K = lqg_controller(P22, np.zeros((1, 2)))
    save_json(controller_to_json(K), tmp_path / "K.json")
    rc = main(["verify", str(DATA / "AC4.json"), str(tmp_path / "K.json"), "--json",
               "--method", "scipy"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["stable"] is True and out["hinf"]["method"] == "scipy"
    ref = verify_controller(pd_.sys, K, 2, 1, method="scipy")
    assert_allclose(out["hinf"]["gamma"], ref.gamma, rtol=1e-12)
    assert_allclose(out["hinf"]["gamma"], dense_peak(ref.closed_loop)[0], rtol=1e-6)
    # no controller order beats the full-order optimum of reference.json (0.55919, LMI)
    assert out["hinf"]["gamma"] >= 0.55919 * (1 - 1e-4)


def test_cli_text_report_with_delta_channel(tmp_path, capsys):
    w = wing("state")
    K = lqg_controller(wing_plant_at(w, 1.0), np.zeros((1, 2)))
    save_json(plant_to_json(wing_lft(w, 1.0), 2, 1, Vf=1.0, n_delta=2), tmp_path / "P.json")
    save_json(controller_to_json(K), tmp_path / "K.json")
    assert main(["verify", str(tmp_path / "P.json"), str(tmp_path / "K.json")]) == 0
    text = capsys.readouterr().out
    ref = verify_controller(wing_lft(w, 1.0), K, 2, 1, Vf=1.0, n_delta=2)
    report, last = text.strip().rsplit("\n", 1)
    assert report.strip() == ref.format().strip()
    assert last.strip().startswith("verdict: PASSED, stable")
    assert "exact stability" in text and f"{ref.exact_V[1]:.6g}" in text


def test_cli_errors_exit_with_code_1(tmp_path, capsys):
    save_json({"D": [[0.0, 0.0]]}, tmp_path / "K.json")
    assert main(["verify", str(tmp_path / "missing.json"), str(tmp_path / "K.json")]) == 1
    assert "file not found" in capsys.readouterr().err
    w = wing("state")
    save_json(plant_to_json(wing_lft(w, 1.0), 2, 1), tmp_path / "P.json")
    assert main(["verify", str(tmp_path / "P.json"), str(tmp_path / "K.json"),
                 "--vf", "1.0"]) == 1
    assert "--n-delta" in capsys.readouterr().err
    # unstable loop (K = 0 above flutter): reported, exit 1, gamma inf -> null (strict JSON)
    assert main(["verify", str(tmp_path / "P.json"), str(tmp_path / "K.json"), "--vf", "1.0",
                 "--n-delta", "2", "--json"]) == 1
    out = json.loads(capsys.readouterr().out, parse_constant=_no_constant)
    assert out["stable"] is False and out["hinf"]["gamma"] is None and out["exact_V"] is None
    assert out["verdict"]["passed"] is False and out["verdict"]["reason"].startswith("not stable")


def _no_constant(name):
    raise AssertionError(f"invalid JSON constant {name} in the output")


def _stable_case(tmp_path):
    w = wing("state")
    K = lqg_controller(wing_plant_at(w, 1.0), np.zeros((1, 2)))
    save_json(plant_to_json(wing_lft(w, 1.0), 2, 1, Vf=1.0, n_delta=2), tmp_path / "P.json")
    save_json(controller_to_json(K), tmp_path / "K.json")
    ref = verify_controller(wing_lft(w, 1.0), K, 2, 1, Vf=1.0, n_delta=2)
    return [str(tmp_path / "P.json"), str(tmp_path / "K.json")], ref


def test_unstable_loop_exits_1_and_says_so(tmp_path, capsys):
    files, _ = _stable_case(tmp_path)
    save_json({"D": [[0.0, 0.0]]}, tmp_path / "K0.json")  # no control above flutter
    assert main(["verify", files[0], str(tmp_path / "K0.json")]) == 1
    out = capsys.readouterr().out
    assert "UNSTABLE" in out and out.strip().splitlines()[-1].strip().startswith(
        "verdict: FAILED, not stable")


def test_required_speed_range_decides_robustness(tmp_path, capsys):
    files, ref = _stable_case(tmp_path)
    lo, hi = ref.exact_V
    assert ref.stable and 0 <= lo < 1.0 < hi < 10  # a bounded exact interval around Vf = 1
    inside = [f"{lo + 0.1 * (1 - lo):.12g}", f"{hi - 0.1 * (hi - 1):.12g}"]
    assert main(["verify", *files, "--require-v", *inside, "--json"]) == 0
    v = json.loads(capsys.readouterr().out, parse_constant=_no_constant)["verdict"]
    assert v["stable"] and v["robust"] and v["passed"]
    assert v["required_V"] == [float(x) for x in inside]
    # the small-gain interval of the paper is inside the exact one: covers less
    sg_lo, sg_hi = ref.small_gain_V
    assert v["small_gain_covers"] == (sg_lo < float(inside[0]) and float(inside[1]) < sg_hi)
    beyond = [f"{lo + 0.1 * (1 - lo):.12g}", f"{1.01 * hi:.12g}"]
    assert main(["verify", *files, "--require-v", *beyond]) == 1
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert "FAILED, not stable over the required" in last and f"{hi:.6g}" in last
    # a range without the delta channel cannot be checked: a clear error, before any work
    save_json(plant_to_json(wing_lft(wing("state"), 1.0), 2, 1), tmp_path / "P2.json")
    assert main(["verify", str(tmp_path / "P2.json"), files[1], "--require-v", "0.5",
                 "1.5"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--require-v needs the ΔV channel" in err


def test_json_of_verify_is_quiet_on_a_closed_pipe(tmp_path):
    import os
    import subprocess
    import sys

    files, _ = _stable_case(tmp_path)
    r, w = os.pipe()
    os.close(r)  # the reader has gone (as `| head` does after its lines)
    try:
        proc = subprocess.run([sys.executable, "-c", "import sys; from casflutter.cli import "
                               "main; sys.exit(main(sys.argv[1:]))", "verify", *files, "--json"],
                              stdout=w, stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(w)
    assert proc.stderr == "" and proc.returncode == 141


# ----------------------------------------------- property-based: the JSON loaders

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as hst  # noqa: E402

from casflutter.errors import CasflutterError  # noqa: E402
from casflutter.verify import load_controller  # noqa: E402

_JSON = hst.recursive(
    hst.none() | hst.booleans() | hst.integers(-3, 3) | hst.floats(allow_nan=True)
    | hst.text(max_size=3),
    lambda inner: hst.lists(inner, max_size=3) | hst.dictionaries(hst.text(max_size=2), inner,
                                                                  max_size=3),
    max_leaves=12)
_MATRIX = hst.one_of(_JSON, hst.lists(hst.lists(hst.floats(-2, 2), min_size=0, max_size=3),
                                      max_size=3))
_KEYS = ["A", "B", "C", "D", "B1", "C1", "D11", "D12", "D21", "D22", "nmeas", "ncon", "Vf",
         "n_delta", "name", "shape_A", "shape_B", "shape_D"]
_PROPS = settings(max_examples=150, deadline=None, derandomize=True, database=None)


@_PROPS
@given(doc=hst.one_of(_JSON, hst.dictionaries(hst.sampled_from(_KEYS), _MATRIX, max_size=9)))
def test_plant_and_controller_json_give_only_casflutter_errors(doc):
    for read in (plant_from_json, controller_from_json):
        try:
            read(doc)
        except CasflutterError:
            pass


@_PROPS
@given(data=hst.binary(max_size=400))
def test_plant_files_of_random_bytes_give_only_casflutter_errors(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("p") / "P.json"
    path.write_bytes(data)
    for read in (load_plant, load_controller):
        try:
            read(path)
        except CasflutterError:
            pass


def test_plant_file_that_is_a_folder(tmp_path):
    with pytest.raises(DataError, match="is a folder"):
        load_plant(tmp_path)
