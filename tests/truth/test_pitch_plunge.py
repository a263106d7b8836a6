"""Rig pitch--plunge sections from TOML files: the NATA section's linear flutter speed against a
flutter determinant written out here from the published equations, the Wagner model against
Hodges & Pierce HP-1 (dimensional), the mass matrix, the flap, the pitch-spring conversion,
and the errors of bad files."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq, fsolve

from casflutter.cli import main
from casflutter.errors import ConfigError
from casflutter.truth import (PitchPlungeSection, TypicalSection, file_problem_names,
                              load_problem, problem_label)
from casflutter.aeroelastic import find_flutter

ROOT = Path(__file__).resolve().parents[2]
NATA = ROOT / "problems" / "nata" / "problem.toml"

# the README's NATA parameters (shared/validation/README.md), evaluated here
B, A, RHO = 0.135, -0.6847, 1.225
KH, CH, CA = 2844.4, 27.43, 0.036
MT, MW = 12.387, 2.049
XA = (0.0873 - (B + A * B)) / B
IA = 0.0517 + MW * XA ** 2 * B ** 2
CLA, CLB, CMB = 6.28, 3.358, -0.635
CMA = (0.5 + A) * CLA


def k_alpha_readme(alpha):
    """The README's stiffness coefficient; the moment is k_alpha(alpha) * alpha."""
    return 2.82 * (1 - 22.1 * alpha + 1315.5 * alpha ** 2 - 8580 * alpha ** 3
                   + 17289.7 * alpha ** 4)


def nata_matrices(U):
    """Ko, Kurdila & Strganac's quasi-steady equations, linearised, written out by hand:
    M q'' + C q' + K q = 0 with q = [h, alpha] (h down, alpha nose up)."""
    M = np.array([[MT, MW * XA * B], [MW * XA * B, IA]])
    # -L = -rho U^2 b cl_a (alpha + h'/U + (1/2 - a) b alpha'/U), M = rho U^2 b^2 cm_a (...)
    C = np.array([[CH + RHO * U * B * CLA, RHO * U * B ** 2 * CLA * (0.5 - A)],
                  [-RHO * U * B ** 2 * CMA, CA - RHO * U * B ** 3 * CMA * (0.5 - A)]])
    K = np.array([[KH, RHO * U ** 2 * B * CLA], [0.0, 2.82 - RHO * U ** 2 * B ** 2 * CMA]])
    return M, C, K


def nata_flutter_determinant(U0, w0):
    """Solve det(-w^2 M + i w C + K) = 0 for the flutter speed and frequency."""
    def res(z):
        M, C, K = nata_matrices(z[0])
        d = np.linalg.det(-z[1] ** 2 * M + 1j * z[1] * C + K)
        return [d.real, d.imag]

    U, w = fsolve(res, [U0, w0], xtol=1e-14)
    assert np.max(np.abs(res([U, w]))) < 1e-8
    return U, w


def test_nata_file_loads_by_name_and_path():
    m = load_problem("nata")
    assert isinstance(m, PitchPlungeSection) and m.name == "nata"
    assert "nata" in file_problem_names()
    assert problem_label(str(NATA)) == "nata"
    p = m.params
    assert_allclose([p.x_alpha, p.I_alpha], [XA, IA], rtol=1e-12)
    assert p.aero == "quasi_steady" and p.flap.cl_beta == CLB and p.flap.cm_beta == CMB
    assert load_problem(str(NATA)).params == p


def test_nata_pitch_spring_is_the_readme_polynomial_times_alpha():
    """k_alpha in the file is the MOMENT's polynomial: k_alpha(alpha) alpha of the README."""
    m = load_problem("nata")
    for alpha in (-0.08, -0.01, 0.003, 0.05, 0.1):
        lin = m.params.k_alpha[0] * alpha
        moment = lin + m._nonlinear_force(np.array([0.0, alpha]))[1] * m.params.m_heave
        assert moment == pytest.approx(k_alpha_readme(alpha) * alpha, rel=1e-12)


def test_nata_linear_flutter_matches_hand_written_determinant():
    m = load_problem("nata")
    fp = find_flutter(m, (2.0, 25.0), n_grid=200)
    assert fp.found
    U, w = nata_flutter_determinant(fp.Vf, fp.omega_f)
    assert fp.Vf == pytest.approx(U, rel=1e-9)
    assert fp.omega_f == pytest.approx(w, rel=1e-9)
    # and the eigenvalues of the hand-written first-order system cross at the same speed
    def abscissa(U):
        M, C, K = nata_matrices(U)
        Ainv = np.linalg.inv(M)
        Amat = np.block([[np.zeros((2, 2)), np.eye(2)], [-Ainv @ K, -Ainv @ C]])
        return np.max(np.linalg.eigvals(Amat).real)

    assert brentq(abscissa, 2.0, 25.0, xtol=1e-12) == pytest.approx(fp.Vf, rel=1e-9)


def test_wagner_rig_reproduces_hodges_pierce_hp1():
    """A dimensional rig with HP-1's ratios flutters at V_F = U_F / (b omega_theta) = 2.170
    (README, Jones' two lags), exactly where the nondimensional typical section does."""
    b, rho, wth = 0.5, 1.2, 10.0
    m = 20.0 * rho * math.pi * b * b
    rig = PitchPlungeSection.from_mapping({
        "kind": "pitch_plunge", "aero": "wagner", "b": b, "a": -0.2, "rho": rho,
        "m_heave": m, "m_wing": m, "x_alpha": 0.1, "I_alpha": 0.24 * m * b * b,
        "k_h": m * (0.4 * wth) ** 2, "c_h": 0.0, "c_alpha": 0.0,
        "k_alpha": [0.24 * m * b * b * wth ** 2]})
    fr = find_flutter(rig, (5.0, 20.0), n_grid=300)
    ft = find_flutter(TypicalSection(), (1.0, 3.0), n_grid=300)
    assert fr.Vf / (b * wth) == pytest.approx(ft.Vf, rel=1e-8)
    assert fr.omega_f / wth == pytest.approx(ft.omega_f, rel=1e-8)
    assert fr.Vf / (b * wth) == pytest.approx(2.170, rel=5e-3)
    assert fr.omega_f / wth == pytest.approx(0.644, rel=5e-3)


def test_total_mass_matrix_is_the_published_one():
    rig = load_problem("nata", ["aero=wagner"])
    p = rig.params
    pr = math.pi * p.rho
    expect = np.array([[p.m_heave + pr * p.b ** 2, p.m_wing * p.x_alpha * p.b - p.a * pr * p.b ** 3],
                       [p.m_wing * p.x_alpha * p.b - p.a * pr * p.b ** 3,
                        p.I_alpha + pr * p.b ** 4 * (0.125 + p.a ** 2)]])
    assert_allclose(rig.total_mass_matrix(), expect, rtol=1e-14)
    # the truth's coupled equations carry exactly this mass: M_struct - M_aero
    Mh, _ = rig._structure_matrices()
    am = rig.aero_matrices(10.0)
    assert_allclose((Mh - am.Mx) * p.m_heave, expect, rtol=1e-12)
    qs = load_problem("nata")
    assert_allclose(qs.total_mass_matrix(), [[p.m_heave, p.m_wing * p.x_alpha * p.b],
                                             [p.m_wing * p.x_alpha * p.b, p.I_alpha]], rtol=1e-14)


@pytest.mark.parametrize("aero", ["quasi_steady", "wagner"])
def test_steady_flap_forces(aero):
    """A flap held at beta on a held section: lift rho U^2 b cl_beta beta, moment
    rho U^2 b^2 cm_beta beta (Wagner: once the lags have settled)."""
    rig = load_problem("nata", [f"aero={aero}"])
    U, beta = 10.0, 0.02
    t = np.linspace(0.0, 6.0, 3001)
    y = rig.aero_forces(t, np.zeros((t.size, 2)), np.full(t.size, beta), U,
                        vdot=np.zeros(t.size), vddot=np.zeros(t.size))
    Phi = rig.modal_structure().shapes
    f = np.linalg.solve(Phi.T, y[-1]) * rig.alpha * U * U * rig.params.m_heave   # [-L, M]
    assert -f[0] == pytest.approx(RHO * U ** 2 * B * CLB * beta, rel=1e-6)
    assert f[1] == pytest.approx(RHO * U ** 2 * B ** 2 * CMB * beta, rel=1e-6)


def test_vector_field_matches_the_simulators_rhs():
    for aero in ("quasi_steady", "wagner"):
        rig = load_problem("nata", [f"aero={aero}"])
        f = rig.vector_field()
        rhs = rig.flap_dynamics
        rng = np.random.default_rng(3)
        for U in (4.0, 12.4, 19.0):
            x = rng.normal(size=f.size1_in(0)) * 0.05
            a = np.asarray(f(x, U)).ravel()
            b = rhs(U)(x, 0.0, 0.0, 0.0)[0]
            assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))


def test_sets_apply_to_the_file_values():
    m = load_problem("nata", ["k_h=3000", "k_alpha=3.0,-60", "flap.cl_beta=3.0"])
    assert m.params.k_h == (3000.0,) and m.params.k_alpha == (3.0, -60.0)
    assert m.params.flap.cl_beta == 3.0 and m.params.flap.cm_beta == CMB
    with pytest.raises(ConfigError, match="unknown parameter 'kh'.*k_h"):
        load_problem("nata", ["kh=1"])
    with pytest.raises(ConfigError, match="'k_h'.*positive"):
        load_problem("nata", ["k_h=-1"])


def _write(tmp_path, text):
    path = tmp_path / "rig.toml"
    path.write_text(text)
    return path


BASE = tomllib.loads(NATA.read_text())


def _toml(d):
    lines = []
    tables = {}
    for k, v in d.items():
        if isinstance(v, dict):
            tables[k] = v
        else:
            lines.append(f"{k} = {json.dumps(v)}")
    for name, t in tables.items():
        lines.append(f"[{name}]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in t.items()]
    return "\n".join(lines)


@pytest.mark.parametrize("change, match", [
    ({"drop": "k_h"}, "missing key.*'k_h'"),
    ({"add": ("kh", 1.0)}, "unknown key.*'kh'"),
    ({"set": ("k_h", -5.0)}, "'k_h'.*positive"),
    ({"set": ("a", 1.5)}, "'a'.*\\(-1, 1\\)"),
    ({"set": ("aero", "theodorsen")}, "'aero'.*'wagner'"),
    ({"set": ("kind", "wing")}, "'kind'"),
    ({"set": ("k_alpha", [])}, "'k_alpha'"),
    ({"set": ("k_alpha", [-1.0, 2.0])}, "'k_alpha'.*positive"),
    ({"set": ("I_alpha", 1e-6)}, "'I_alpha'.*parallel axes"),
    # m_heave I_alpha > S^2 (a positive definite mass matrix) but I_alpha below the wing's
    # own m_wing (x_alpha b)^2 = 0.0041 kg m^2 about the elastic axis
    ({"set": ("I_alpha", 0.002)}, "'I_alpha'.*m_wing \\(x_alpha b\\)\\^2 = 0.0041"),
    ({"lco": {"vrange": "4-16"}}, "\\[lco\\] vrange.*\\[low, high\\]"),
    ({"lco": {"vrange": [16.0, 4.0]}}, "\\[lco\\] vrange.*low < high"),
    ({"lco": {"npoints": 7}}, "unknown key.*'npoints' in \\[lco\\]"),
    ({"set": ("b", 1e300)}, "'I_alpha'.*= inf kg m\\^2.*check I_alpha, x_alpha and b"),
    ({"set": ("m_wing", 20.0)}, "'m_wing'.*m_heave"),
    ({"set": ("c_h", "soft")}, "'c_h'.*number"),
    ({"flap": {"cl_beta": 3.0}}, "missing key.*'cm_beta'"),
    ({"flap": {"cl_beta": 3.0, "cm_beta": -0.6, "hinge": 0.5}}, "unknown key.*'hinge'"),
])
def test_bad_files_name_the_key(tmp_path, change, match):
    d = {k: v for k, v in BASE.items() if k not in ("reference",)}
    if "drop" in change:
        d.pop(change["drop"])
    if "add" in change:
        d[change["add"][0]] = change["add"][1]
    if "set" in change:
        d[change["set"][0]] = change["set"][1]
    for table in ("flap", "lco"):
        if table in change:
            d[table] = change[table]
    path = _write(tmp_path, _toml(d))
    with pytest.raises(ConfigError, match=match):
        load_problem(str(path))


def test_missing_and_invalid_files(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_problem(str(tmp_path / "nope.toml"))
    bad = tmp_path / "bad.toml"
    bad.write_text("kind = \n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_problem(str(bad))


def test_cli_problems_and_flutter_take_a_file(capsys, tmp_path):
    path = tmp_path / "my_rig.toml"
    path.write_text(NATA.read_text())
    assert main(["problems", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    rows = {r["name"]: r for r in info[0]["parameters"]}
    assert info[0]["name"] == "nata" and rows["k_h"]["value"] == [KH]
    assert main(["problems"]) == 0
    assert "nata  (PitchPlungeSection)" in capsys.readouterr().out
    assert main(["flutter", str(path), "--no-parametric", "--figure", "none", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    U, _ = nata_flutter_determinant(12.0, 12.0)
    assert doc["truth"]["V_flutter"] == pytest.approx(U, rel=1e-6)
    assert doc["units"]["V_flutter"] == "m/s"
    assert doc["rom"]["V_flutter"] == pytest.approx(U, rel=0.06)


def test_a_rig_file_without_rom_settings_gets_the_truths_flutter(capsys, tmp_path):
    """No [rom] table: `casflutter flutter` gives the truth's own flutter speed (checked
    against the flutter determinant written out by hand), not a demand for chirp settings;
    --truth-only does the same for a problem that has them."""
    d = {k: v for k, v in BASE.items() if k not in ("reference", "rom", "lco")}
    path = _write(tmp_path, _toml(d))
    U, _ = nata_flutter_determinant(12.0, 12.0)
    for args in (["flutter", str(path), "--vrange", "2", "25", "--json"],
                 ["flutter", "nata", "--truth-only", "--vrange", "2", "25", "--json"]):
        assert main(args) == 0
        doc = json.loads(capsys.readouterr().out)
        assert doc["truth"]["V_flutter"] == pytest.approx(U, rel=1e-6)
        assert doc["rom"] is None and doc["note"].startswith("the truth only")
    assert main(["flutter", str(path)]) == 1
    assert "--vrange" in capsys.readouterr().err


def test_problems_shows_the_files_value_as_the_default(capsys):
    assert main(["problems", "nata", "--set", "rho=1.0", "--json"]) == 0
    (info,) = json.loads(capsys.readouterr().out)
    rho = next(r for r in info["parameters"] if r["name"] == "rho")
    assert (rho["value"], rho["default"]) == (1.0, 1.225)
