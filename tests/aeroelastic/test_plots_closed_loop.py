"""Closed loop v = K zm against python-control, and the flutter figures."""

import control
import numpy as np
import pytest
from matplotlib.figure import Figure
from numpy.testing import assert_allclose

from casflutter.aeroelastic import find_flutter, simulate_loop
from casflutter.structure import ModalStructure
from casflutter.errors import DimensionError
from casflutter.report import plot_lco, plot_pole_loci, plot_root_locus, plot_vg_vf

from ._cases import binary_system


def _sorted(z):
    return np.sort_complex(np.round(z, 8))


@pytest.mark.parametrize("sensor", ["acceleration", "state"])
def test_closed_loop_matrix_matches_control_feedback(sensor):
    sysae = binary_system(sensor, dynamic=True)
    m = sysae.structure.n_sensors
    rng = np.random.default_rng(7)
    K = control.ss([[-3.0, 1.0], [0.0, -5.0]], rng.standard_normal((2, m)),
                   rng.standard_normal((1, 2)), 0.1 * rng.standard_normal((1, m)))
    V = 1.7
    plant = sysae.loop(V).statespace()[:, 2]  # v -> zm
    ref = control.feedback(plant, K, sign=+1)
    assert_allclose(_sorted(np.linalg.eigvals(sysae.closed_loop_state_matrix(V, K))),
                    _sorted(ref.poles()), atol=1e-7)
    with pytest.raises(DimensionError, match="sensors"):
        sysae.closed_loop_state_matrix(V, control.ss([], [], [], [[1.0]]))


def test_figures_are_built():
    sysae = binary_system("velocity", dynamic=True)
    res = find_flutter(sysae, (0.0, 3.0), n_grid=31)
    for fig in (plot_vg_vf(res), plot_vg_vf(res.tracking, hz=False), plot_root_locus(res),
                plot_pole_loci(sysae, np.linspace(0, 3, 7),
                               control.ss([], [], [], -0.5 * np.ones((1, sysae.structure.n_sensors))))):
        assert isinstance(fig, Figure) and fig.axes
    assert "Vf" in fig_title(plot_vg_vf(res))
    # the closed-loop poles are coloured by speed: a colour bar over the grid's range
    bar = fig.axes[1]
    assert bar.get_ylabel() == "V (closed loop)" and bar.get_ylim() == (0.0, 3.0)


def fig_title(fig):
    return fig.axes[0].get_title()


def test_lco_figure():
    class Rayleigh:
        n_modes, max_lag, dt = 1, 1, 1e-3

        def step(self, y_hist, u_hist, v_hist):
            ud = (u_hist[0] - u_hist[1]) / self.dt
            return 0.9 * ud - 10.0 * ud ** 3

    s = ModalStructure([2 * np.pi * 4.0], [0.01], Hs=[[1.0]])
    sim = simulate_loop(Rayleigh(), s, 1.0, 8000, xs0=[0.01, 0.0])
    fig = plot_lco(sim)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    assert isinstance(plot_lco(sim, which="modes"), Figure)
