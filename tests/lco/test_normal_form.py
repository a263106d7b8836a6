"""First Lyapunov coefficients against normal forms whose coefficients are known
analytically, for a flow (Hopf) and a map (Neimark--Sacker), and the predicted cycle against
the computed one on a system with quadratic terms."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.lco import LCOSettings, Outputs, continue_lco
from casflutter.lco._normal_form import (MultilinearForms, find_hopf, find_neimark_sacker,
                                         lyapunov_flow, lyapunov_map)


def hopf_normal_form(c, omega=2.0):
    """x' = (V-1) x - omega y + c x r^2, y' = omega x + (V-1) y + c y r^2, i.e. in
    z = (x + i y) / sqrt 2 with <q, q> = 1: z' = (V - 1 + i omega) z + 2 c z |z|^2."""
    x = ca.SX.sym("x", 2)
    V = ca.SX.sym("V")
    r2 = x[0] ** 2 + x[1] ** 2
    return ca.Function("f", [x, V], [ca.vertcat((V - 1) * x[0] - omega * x[1] + c * x[0] * r2,
                                                omega * x[0] + (V - 1) * x[1] + c * x[1] * r2)])


@pytest.mark.parametrize("c", [-1.0, 0.5])
def test_flow_lyapunov_coefficient(c):
    forms = MultilinearForms(hopf_normal_form(c))
    cp = find_hopf(forms, (0.5, 2.0))
    assert cp.V == pytest.approx(1.0, abs=1e-12)
    assert cp.eigenvalue.imag == pytest.approx(2.0, rel=1e-12)
    assert cp.crossing_rate == pytest.approx(1.0, rel=1e-12)
    # l1 = Re(2c) / omega
    assert lyapunov_flow(forms, cp) == pytest.approx(2 * c / 2.0, rel=1e-10)


@pytest.mark.parametrize("c", [-0.3, 0.7])
def test_map_lyapunov_coefficient(c):
    """x -> (1 + (V - 1)/10 + c r^2) R(theta) x: with <q, q> = 1, z -> e^{i theta} z
    (1 + beta + 2 c |z|^2), so d = 2 c and d|mu|/dV = 1/10."""
    th = 0.7
    x = ca.SX.sym("x", 2)
    V = ca.SX.sym("V")
    R = ca.DM([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    g = 1 + (V - 1) / 10 + c * (x[0] ** 2 + x[1] ** 2)
    forms = MultilinearForms(ca.Function("F", [x, V], [g * ca.mtimes(R, x)]))
    cp = find_neimark_sacker(forms, (0.5, 2.0))
    assert cp.V == pytest.approx(1.0, abs=1e-12)
    assert np.angle(cp.eigenvalue) == pytest.approx(th, rel=1e-12)
    assert cp.crossing_rate == pytest.approx(0.1, rel=1e-10)
    assert lyapunov_map(forms, cp) == pytest.approx(2 * c, rel=1e-10)


def test_quadratic_terms_enter_l1_and_the_computed_cycle_agrees():
    """With quadratic terms the coefficient is not the cubic one; the continued branch's
    speed offset at small amplitude agrees with the normal-form prediction."""
    x = ca.SX.sym("x", 3)
    V = ca.SX.sym("V")
    r2 = x[0] ** 2 + x[1] ** 2
    f = ca.Function("f", [x, V], [ca.vertcat(
        (V - 1) * x[0] - 2.0 * x[1] - 0.2 * x[0] * r2 + 0.8 * x[0] * x[2],
        2.0 * x[0] + (V - 1) * x[1] - 0.2 * x[1] * r2 + 0.6 * x[1] * x[2],
        -1.5 * x[2] + 1.2 * x[0] ** 2 + 0.5 * x[0] * x[1])])
    forms = MultilinearForms(f)
    cp = find_hopf(forms, (0.5, 2.0))
    l1 = lyapunov_flow(forms, cp)
    assert abs(l1 - (-0.2 * 2 / 2.0)) > 0.05          # the quadratic terms matter
    out = Outputs(("x",), ("",), ca.Function("h", [x, V], [x[0]]))
    br = continue_lco(f, out, (0.5, 1.3), LCOSettings(max_points=3, start_offset=1e-3))
    assert br.hopf.lyapunov == pytest.approx(l1, rel=1e-12)
    assert br.hopf.normal_form_agreement == pytest.approx(1.0, abs=0.01)
    assert br.hopf.consistent


def test_no_hopf_and_unstable_start_are_errors():
    forms = MultilinearForms(hopf_normal_form(-1.0))
    with pytest.raises(ConfigError, match="no flutter \\(Hopf\\) point in the speed range"):
        find_hopf(forms, (0.2, 0.9))
    with pytest.raises(ConfigError, match="already unstable at the start"):
        find_hopf(forms, (1.2, 1.9))
