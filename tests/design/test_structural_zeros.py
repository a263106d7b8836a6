"""A measurement that no control reaches: COMPleib's REA3 (12 states, 1 control, 3
measurements; the first measurement has no path from the control).  Its control-to-
measurement gain is zero, which rounding makes 1e-16; the synthesis once scaled that
measurement by 1e-16 and returned a static gain of -3.4e13 with gamma = 8e18, "converged".

Truth: gamma of the loop recomputed by python-control's ``hinfnorm`` (independent of the
package), and the optimum of the static design, 74.2513, found independently by a
Nelder-Mead search over the three gains with a norm of its own and matched from above by
the full-order LMI optimum 74.2515 (an order-0 gamma cannot be below it by more than the
LMI's accuracy).
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from casflutter.design import load_compleib, synthesize
from casflutter.design._plant import partition
from casflutter.design._problem import _io_scales

REA3 = Path(__file__).resolve().parent / "data" / "REA3.json"
GAMMA_STATIC = 74.2513


@pytest.fixture(scope="module")
def rea3():
    return load_compleib(REA3)


def test_a_measurement_no_control_reaches_keeps_scale_one(rea3):
    P, nmeas, ncon, _ = rea3
    _, sy = _io_scales([partition(P, nmeas, ncon)])
    assert sy[0] == 1.0 and np.all((sy[1:] > 1e-3) & (sy[1:] < 1e3))


def test_the_static_design_reaches_the_independent_optimum(rea3):
    P, nmeas, ncon, _ = rea3
    res = synthesize(P, nmeas, ncon, 0, starts=3, seed=0)
    assert res.success and np.max(np.abs(res.controller.D)) < 1e3
    p = partition(P, nmeas, ncon)
    Dk = np.asarray(res.controller.D)
    cl = control.ss(p.A + p.B2 @ Dk @ p.C2, p.B1 + p.B2 @ Dk @ p.D21,
                    p.C1 + p.D12 @ Dk @ p.C2, p.D11 + p.D12 @ Dk @ p.D21)
    assert np.max(np.linalg.eigvals(cl.A).real) < 0
    gamma = float(control.norm(cl, "inf"))
    assert res.gamma == pytest.approx(gamma, rel=1e-6)
    assert res.gamma == pytest.approx(GAMMA_STATIC, rel=1e-3)


def test_verify_says_why_a_loop_with_absurd_gains_is_not_stable(tmp_path, capsys):
    """The loop of that -3.4e13 gain has its slowest pole at -0.0207, inside the rounding
    margin 100 eps ||A_cl|| = 0.77 of a 3.4e13-sized matrix: not 'a pole >= 0'."""
    from casflutter.cli import main

    K = tmp_path / "K.json"
    K.write_text('{"D": [[-34432987889699.83, -0.8796842951513001, -0.043956033494218304]]}')
    assert main(["verify", str(REA3), str(K)]) == 1
    out = capsys.readouterr().out
    assert "within rounding" in out and ">= 0" not in out
