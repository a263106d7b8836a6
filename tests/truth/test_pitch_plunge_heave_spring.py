"""A hardening heave spring on the NATA rig (quasi-steady aerodynamics, linear pitch
spring): the LCO branch of the rig file against the equations of motion written out here
from Ko, Kurdila & Strganac (1997) and integrated with scipy (independent of the package's
truth, vector field and collocation).

    [m_T, m_W x_a b; m_W x_a b, I_a] [h'', a''] + diag(c_h, c_a) [h', a']
        + [k_h1 h + k_h3 h^3, k_a a] = [-L, M],
    L = rho U^2 b cl_a a_eff,  M = rho U^2 b^2 (1/2 + a) cl_a a_eff,
    a_eff = a + h'/U + (1/2 - a) b a'/U.
"""

from __future__ import annotations

import numpy as np
import pytest
from lco._helpers import measure
from scipy.integrate import solve_ivp

from casflutter.lco import lco_branch
from casflutter.truth import load_problem

K_H3 = 3.0e6        # N/m^3: hardening heave spring
SETS = ["k_alpha=2.82", f"k_h=2844.4,0,{K_H3}"]


def _rhs(p, U):
    b, a = p.b, p.a
    M = np.array([[p.m_heave, p.m_wing * p.x_alpha * b], [p.m_wing * p.x_alpha * b, p.I_alpha]])
    Minv = np.linalg.inv(M)

    def f(_t, s):
        h, al, hd, ad = s
        a_eff = al + hd / U + (0.5 - a) * b * ad / U
        lift = p.rho * U ** 2 * b * p.cl_alpha * a_eff
        moment = p.rho * U ** 2 * b ** 2 * (0.5 + a) * p.cl_alpha * a_eff
        force = np.array([-lift - p.c_h * hd - (p.k_h[0] * h + K_H3 * h ** 3),
                          moment - p.c_alpha * ad - p.k_alpha[0] * al])
        return np.concatenate([[hd, ad], Minv @ force])
    return f


def test_the_heave_spring_is_read_and_checked():
    p = load_problem("nata", SETS).params
    assert p.k_h == (2844.4, 0.0, K_H3) and p.k_alpha == (2.82,)
    assert load_problem("nata").params.k_h == (2844.4,)      # a number: linear


def test_lco_of_a_hardening_heave_spring_against_the_written_out_equations():
    truth = load_problem("nata", SETS)
    br = lco_branch(truth, (10.0, 14.0))
    assert br.kind == "supercritical"
    p = min(br.points, key=lambda q: abs(q.V - 1.03 * br.hopf.V))   # a branch point itself
    U = p.V
    t_end = 150.0
    sol = solve_ivp(_rhs(truth.params, U), (0.0, t_end), [0.0, 0.01, 0.0, 0.0], method="DOP853",
                    rtol=1e-10, atol=1e-12, dense_output=True)
    t = np.linspace(100.0, t_end, 50001)
    h, al = sol.sol(t)[:2]
    a_pitch, f = measure(t, al)
    a_heave, _ = measure(t, h)
    assert p.stable
    assert a_pitch == pytest.approx(p.amplitude["pitch"], rel=1e-3)
    assert a_heave == pytest.approx(p.amplitude["heave"], rel=1e-3)
    assert f == pytest.approx(p.freq_hz, rel=1e-3)
