"""Wing files (``kind = "wing"`` and ``"gaf"``): what they load, and a clear error for every
bad input, raised when the file is read (before any work)."""

import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from casflutter.errors import CasflutterError, ConfigError, DataError
from casflutter.pipeline import load_config
from casflutter.truth import GAFProblem, WingProblem, load_problem

ROOT = Path(__file__).resolve().parents[2] / "problems"
EXAMPLE = ROOT / "example_wing" / "problem.toml"
GOLAND = ROOT / "goland_gaf" / "problem.toml"


def _small_wing(tmp_path: Path, fmt: str = "csv", **edits) -> Path:
    """A two-mode wing with two records in ``fmt``, written to ``tmp_path``; ``edits``
    replace lines of the TOML by key (``"modes.alpha": "alpha = nan"``)."""
    rng = np.random.default_rng(0)
    K, dt = 300, 0.01
    t = np.arange(K) * dt
    for j in range(2):
        ch = {"t": t, "u1": rng.standard_normal(K) * (j == 0),
              "u2": rng.standard_normal(K) * (j == 1), "Q1": rng.standard_normal(K),
              "Q2": rng.standard_normal(K)}
        path = tmp_path / f"rec{j}.{fmt}"
        if fmt == "csv":
            names = list(ch)
            rows = np.column_stack([ch[c] for c in names])
            np.savetxt(path, rows, delimiter=",", header=",".join(names), comments="")
        elif fmt == "npz":
            np.savez(path, **ch)
        else:
            savemat(path, ch)
    lines = {
        "kind": 'kind = "wing"',
        "modes": "[modes]",
        "modes.frequencies_hz": "frequencies_hz = [2.0, 5.0]",
        "modes.damping": "damping = [0.02, 0.01]",
        "modes.alpha": "alpha = 3.0",
        "speed": "[speed]",
        "speed.U_ref": "U_ref = 30.0",
        "speed.rho": "rho = 1.2",
        "sensors": "[sensors]",
        "sensors.kind": 'kind = "displacement"',
        "sensors.names": 'names = ["tip"]',
        "sensors.rows": "rows = [[1.0, 0.5]]",
        "records": "[records]",
        "records.V0": "V0 = 0.8",
        "records.files": f'files = ["rec0.{fmt}", "rec1.{fmt}"]',
        "records.time": 'time = "t"',
        "records.displacements": 'displacements = ["u1", "u2"]',
        "records.forces": 'forces = ["Q1", "Q2"]',
    }
    lines.update(edits)
    path = tmp_path / "wing.toml"
    path.write_text("\n".join(v for v in lines.values() if v) + "\n")
    return path


def test_example_wing_loads_its_modes_sensors_and_records():
    w = load_problem("example_wing")
    assert isinstance(w, WingProblem) and w.name == "example_wing"
    ms = w.modal_structure()
    assert np.allclose(ms.omega / (2 * np.pi), [2.19, 10.07, 13.55, 16.48, 38.09], rtol=1e-15)
    assert ms.sensor == "acceleration" and ms.sensor_names == ("Acc1", "Acc2")
    assert w.sensor_units == ("m/s^2", "m/s^2") and ms.Hs.shape == (2, 5)
    assert len(w.records.records) == 6 and w.records.has_u and w.records.has_v
    assert w.records.dt == pytest.approx(0.004, rel=1e-9)
    assert w.V0 == 0.69 and w.airspeed(0.69) == pytest.approx(0.69 * 28.9)
    assert w.dynamic_pressure(1.0) == pytest.approx(0.5 * 1.225 * 28.9 ** 2)
    # the flap record moves the flap only, the first record the first mode only
    assert np.all(w.records.records[5].u == 0) and np.any(w.records.records[5].v != 0)
    assert np.all(w.records.records[0].u[:, 1:] == 0) and np.all(w.records.records[0].v == 0)
    # the same wing from its path
    assert load_problem(str(EXAMPLE)).records.n_samples == w.records.n_samples


@pytest.mark.parametrize("fmt", ["csv", "npz", "mat"])
def test_the_three_record_formats_give_the_same_records(tmp_path, fmt):
    (tmp_path / fmt).mkdir()
    (tmp_path / "ref").mkdir()
    w = load_problem(str(_small_wing(tmp_path / fmt, fmt)))
    ref = load_problem(str(_small_wing(tmp_path / "ref", "npz")))
    assert w.records.dt == pytest.approx(0.01, rel=1e-9)
    for a, b in zip(w.records.records, ref.records.records):
        assert np.allclose(a.y, b.y, rtol=1e-12, atol=1e-12)
        assert np.allclose(a.u, b.u, rtol=1e-12, atol=1e-12)
    assert w.records.output_names == ("Q1", "Q2") and w.records.u_names == ("u1", "u2")


@pytest.mark.parametrize("edit, error, words", [
    ({"modes.alpha": ""}, ConfigError, ["modes.alpha", "flow constant"]),
    ({"speed.U_ref": ""}, ConfigError, ["speed.U_ref", "m/s"]),
    ({"records.forces": ""}, ConfigError, ["records.forces"]),
    ({"modes": "", "modes.frequencies_hz": "", "modes.damping": "", "modes.alpha": ""},
     ConfigError, ["[modes]"]),
    ({"sensors.rows": "rows = [[1.0, 0.5, 0.2]]"}, ConfigError, ["sensors.rows", "3 entries",
                                                                 "2 frequencies"]),
    ({"modes.damping": "damping = [0.02]"}, ConfigError, ["modes.damping", "1 entries",
                                                          "2 modes"]),
    ({"records.forces": 'forces = ["Q1"]'}, ConfigError, ["records.forces", "1 names"]),
    ({"modes.alpha": "alpha = nan"}, ConfigError, ["modes.alpha", "finite"]),
    ({"modes.frequencies_hz": "frequencies_hz = [2.0, inf]"}, ConfigError,
     ["frequencies_hz[1]", "finite"]),
    ({"sensors.rows": "rows = [[1.0, nan]]"}, ConfigError, ["sensors.rows", "finite"]),
    ({"records.files": 'files = ["rec0.csv", "missing.csv"]'}, DataError,
     ["missing.csv", "not found", "records.files"]),
    ({"records.forces": 'forces = ["Q1", "Lift"]'}, DataError, ["Lift", "not in the header"]),
    ({"speed.rho": "rho = 1.2\nspan = 3.0"}, ConfigError, ["speed.span", "allowed"]),
    ({"records.time": ""}, ConfigError, ["records.time", "records.dt"]),
    ({"kind": 'kind = "wings"'}, ConfigError, ["kind", "'wing'", "'gaf'"]),
])
def test_bad_wing_files_fail_with_the_key_and_the_fix(tmp_path, edit, error, words):
    path = _small_wing(tmp_path, "csv", **edit)
    with pytest.raises(error) as exc:
        load_problem(str(path))
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_unknown_channel_of_an_npz_or_mat_record_is_named(tmp_path, fmt):
    path = _small_wing(tmp_path, fmt, **{"records.displacements":
                                          'displacements = ["u1", "u_2"]'})
    with pytest.raises(DataError, match="'u_2'.*the file holds"):
        load_problem(str(path))


def test_non_finite_samples_in_a_record_are_refused(tmp_path):
    path = _small_wing(tmp_path, "npz")
    z = dict(np.load(tmp_path / "rec1.npz"))
    z["Q2"][7] = np.nan
    np.savez(tmp_path / "rec1.npz", **z)
    with pytest.raises(DataError, match="NaN/inf.*sample 7"):
        load_problem(str(path))


def test_a_wing_file_has_no_parameters_to_set(tmp_path):
    with pytest.raises(ConfigError, match="no parameters to change"):
        load_problem(str(_small_wing(tmp_path)), {"alpha": 2.0})


def test_run_configuration_checks_the_wing_before_any_work(tmp_path):
    path = _small_wing(tmp_path, "csv", **{"records.files": 'files = ["gone.csv"]'})
    cfg = tmp_path / "run.toml"
    cfg.write_text(f'stages = []\n[problem]\nname = "{path.name}"\n')
    with pytest.raises(CasflutterError, match=r"\[problem\].*gone.csv.*records.files"):
        load_config(cfg)
    with pytest.raises(ConfigError, match="problem file.*not a run configuration"):
        load_config(path)


def test_goland_gaf_loads_its_table_and_modes():
    g = load_problem("goland_gaf")
    assert isinstance(g, GAFProblem)
    assert g.table.n_modes == g.n_modes == 7 and g.table.has_flap
    assert g.structure.sensor == "displacement" and g.structure.n_sensors == 2
    assert g.U_range == (60.0, 200.0) and g.rfa["poly_order"] == 0


def _gaf_copy(tmp_path: Path, old: str = "", new: str = "") -> Path:
    for f in ("problem.toml", "q_table.npz"):
        shutil.copy(GOLAND.parent / f, tmp_path / f)
    p = tmp_path / "problem.toml"
    if old:
        text = p.read_text()
        assert old in text
        p.write_text(text.replace(old, new))
    return p


@pytest.mark.parametrize("old, new, error, words", [
    ('file = "q_table.npz"', 'file = "q.npz"', DataError, ["gaf.file", "q.npz", "not found"]),
    ("U_ref = 79.", "U_ref = 80.", DataError, ["U_ref", "make them agree"]),
    ('"bending 4"]', '"bending 4", "x"]', ConfigError, ["modes.names", "8 names", "7"]),
    ("U_range = [60.0, 200.0]", "U_range = [200.0, 60.0]", ConfigError, ["gaf.U_range"]),
    ("n_lags = 6", "n_lags = 6\nlags = 3", ConfigError, ["gaf.lags", "allowed"]),
])
def test_bad_gaf_files_fail_with_the_key_and_the_fix(tmp_path, old, new, error, words):
    with pytest.raises(error) as exc:
        load_problem(str(_gaf_copy(tmp_path, old, new)))
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))


def test_gaf_table_of_other_modes_is_refused(tmp_path):
    p = _gaf_copy(tmp_path)
    z = dict(np.load(tmp_path / "q_table.npz"))
    z["Q"] = z["Q"][:, :6, :7]
    z["mode_names"] = z["mode_names"][:6]
    np.savez(tmp_path / "q_table.npz", **z)
    with pytest.raises(DataError, match="6 modes but \\[modes\\] has 7"):
        load_problem(str(p))


def test_bad_rfa_settings_of_a_gaf_file_fail_before_the_fit(tmp_path):
    from casflutter.pipeline import run

    p = _gaf_copy(tmp_path, 'method = "roger"', 'method = "karpel"')
    cfg = tmp_path / "run.toml"
    cfg.write_text('stages = []\n[problem]\nname = "problem.toml"\n[sensors]\n'
                   'kind = "displacement"\n')
    with pytest.raises(ConfigError, match=r"\[gaf\].*method='karpel'"):
        run(load_config(cfg), quiet=True, write=False)
    assert p.is_file()


def test_errors_are_casflutter_errors():
    assert issubclass(ConfigError, CasflutterError) and issubclass(DataError, CasflutterError)
