"""Flutter-speed sensitivities against finite differences of the flutter speed itself."""

import numpy as np
import pytest

from casflutter.study import (flutter_sensitivity, flutter_sensitivity_nlp, flutter_speed_fd,
                              hopf_point, quadratic_coefficients)
from casflutter.truth import load_problem, problem_definition

PARAMS = ["a", "e", "mu", "r2", "sigma", "zeta"]


@pytest.fixture(scope="module")
def hp1():
    return flutter_sensitivity("typical_section", PARAMS)


def test_nominal_flutter_speed_is_published_hp1(hp1):
    ref = problem_definition("typical_section")["reference"]["jones"]
    np.testing.assert_allclose(hp1.Vf, ref["flutter_speed"], rtol=ref["rtol"])
    np.testing.assert_allclose(hp1.omega_f, ref["flutter_frequency_ratio"], rtol=ref["rtol"])


@pytest.mark.parametrize("name", PARAMS)
def test_eigenvalue_perturbation_matches_finite_differences(hp1, name):
    # FD of the Brent-refined Vf (xtol 1e-10 relative) with step 1e-4: truncation O(1e-8)
    fd = flutter_speed_fd("typical_section", name)
    np.testing.assert_allclose(hp1[name].dVf_dp, fd, rtol=2e-6, atol=1e-7)


def test_zeta_at_bound_uses_one_sided_difference(hp1):
    assert hp1["zeta"].difference == "forward"
    assert hp1["zeta"].normalized_by == "unit"
    np.testing.assert_allclose(hp1["zeta"].normalized, hp1["zeta"].dVf_dp / hp1.Vf)


def test_frequency_sensitivity_matches_finite_differences(hp1):
    from casflutter.aeroelastic import find_flutter

    h = 1e-4 * 20.0

    def omega(mu):
        m = load_problem("typical_section", [f"mu={mu}"])
        return find_flutter(m.state_matrix, (0.02, 4.0), n_grid=81).omega_f

    fd = (omega(20.0 + h) - omega(20.0 - h)) / (2 * h)
    np.testing.assert_allclose(hp1["mu"].domega_dp, fd, rtol=1e-4, atol=1e-8)


def test_ranking_is_by_absolute_normalised_sensitivity(hp1):
    ranked = hp1.ranked()
    mags = [abs(s.normalized) for s in ranked]
    assert mags == sorted(mags, reverse=True)
    for s in ranked:
        if s.value != 0:
            np.testing.assert_allclose(s.normalized, s.value / hp1.Vf * s.dVf_dp)
    assert "rank" in hp1.table() and ranked[0].name in hp1.table().splitlines()[2]


def test_parametric_nlp_sensitivity_agrees(hp1):
    nlp = flutter_sensitivity_nlp("typical_section", PARAMS)
    np.testing.assert_allclose(nlp.Vf, hp1.Vf, rtol=1e-10)
    for name in PARAMS:
        np.testing.assert_allclose(nlp[name].dVf_dp, hp1[name].dVf_dp, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(nlp[name].domega_dp, hp1[name].domega_dp, rtol=1e-6,
                                   atol=1e-9)


def test_hopf_point_on_analytic_quadratic_family():
    # A(V) = [[V^2 + V - p, -w], [w, V^2 + V - p]] has λ = V^2 + V - p ± i w, stable at
    # small V; with p = 0.75 the crossing is V = (-1 + sqrt(1 + 4p)) / 2 = 0.5 at ω = w
    p, w = 0.75, 3.0
    A0 = np.array([[-p, -w], [w, -p]])
    A1 = np.eye(2)
    A2 = np.eye(2)
    A0q, A1q, A2q = quadratic_coefficients(lambda V: A0 + V * A1 + V * V * A2)
    np.testing.assert_allclose(A1q, A1, atol=1e-12)
    hp = hopf_point(A0, A1, A2, V_range=(0.01, 0.9), n_scan=11)
    np.testing.assert_allclose(hp.Vf, 0.5, rtol=1e-12)
    np.testing.assert_allclose(hp.omega_f, w, rtol=1e-12)


@pytest.mark.parametrize("name", ["rho", "zeta", "EI"])
def test_goland_sensitivity_matches_finite_differences(name):
    s = flutter_sensitivity("goland", [name], V_range=(0.5, 3.0), n_grid=61)
    fd = flutter_speed_fd("goland", name, V_range=(0.5, 3.0), n_grid=61)
    np.testing.assert_allclose(s[name].dVf_dp, fd, rtol=1e-5, atol=1e-7)


def test_a_rig_files_numbers_are_differentiated_and_its_lists_left_alone():
    """The NATA rig file: its spring polynomials (lists), aerodynamics (a word) and flap
    (a table) stay as the file has them; the numbers' sensitivities agree with finite
    differences of the refined flutter speed itself."""
    from casflutter.errors import ConfigError

    s = flutter_sensitivity("nata", V_range=(2.0, 25.0))
    by = {x.name: x for x in s.sensitivities}
    assert {"k_alpha", "k_h", "aero", "flap"}.isdisjoint(by) and {"rho", "c_alpha"} <= set(by)
    for n in ("rho", "c_alpha"):
        fd = flutter_speed_fd("nata", n, V_range=(2.0, 25.0))
        assert by[n].dVf_dp == pytest.approx(fd, rel=1e-4)
    with pytest.raises(ConfigError, match="k_alpha: not a single number"):
        flutter_sensitivity("nata", ["k_alpha"], V_range=(2.0, 25.0))
