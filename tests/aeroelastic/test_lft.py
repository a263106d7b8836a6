"""The LFT of eq. 10-15 closed with wf = −ΔV zf equals ΣAE assembled at V² = Vf² + ΔV."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import build_lft, find_flutter
from casflutter.errors import ConfigError

from ._cases import binary_system


@pytest.mark.parametrize("sensor", ["state", "acceleration", "velocity"])
@pytest.mark.parametrize("dynamic", [False, True])
def test_lft_closure_equals_direct_assembly(sensor, dynamic):
    sysae = binary_system(sensor, dynamic=dynamic)
    Vf = find_flutter(sysae, (0.0, 3.0), n_grid=31).Vf
    lft = build_lft(sysae, Vf)
    assert lft.n_delta == 2 and lft.ncon == 1 and lft.nmeas == sysae.structure.n_sensors
    assert lft.P.ninputs == 2 * 2 + 1 and lft.P.noutputs == 2 + lft.nmeas
    rng = np.random.default_rng(20160706)
    for dV in rng.uniform(-0.8 * Vf ** 2, 2.0 * Vf ** 2, size=6):
        closed = lft.close(dV)
        direct = sysae.loop(np.sqrt(Vf ** 2 + dV))
        for got, want in ((closed.A, direct.A),
                          (closed.B, np.hstack([direct.B1, direct.B2[:, None]])),
                          (closed.C, direct.C2),
                          (closed.D, np.hstack([direct.D21, direct.D22[:, None]]))):
            assert_allclose(got, want, rtol=0, atol=1e-10 * max(1.0, np.abs(want).max()))


def test_lemma1_factorisation_and_paper_structure():
    """[ΔA ΔB1 ΔB2] = −Mx ΔV [Nx Nw Nv] (eq. 12); state sensors give D21 = D22 = 0 (eq. 14)."""
    sysae = binary_system("state", dynamic=True)
    Vf, dV = 1.5, 0.37
    lft = build_lft(sysae, Vf)
    lo, hi = sysae.loop(Vf), sysae.loop(np.sqrt(Vf ** 2 + dV))
    assert_allclose(hi.A - lo.A, -lft.Mx * dV @ lft.Nx, atol=1e-12)
    assert_allclose(hi.B1 - lo.B1, -lft.Mx * dV @ lft.Nw, atol=1e-12)
    assert_allclose((hi.B2 - lo.B2)[:, None], -lft.Mx * dV @ lft.Nv, atol=1e-12)
    assert np.all(lft.D21 == 0) and np.all(lft.D22 == 0)
    assert_allclose(lft.C2[:, :4], sysae.structure.Hs)


def test_lft_requires_a_flutter_speed():
    sysae = binary_system()
    res = find_flutter(sysae, (0.0, 1.0), n_grid=11)
    with pytest.raises(ConfigError, match="Vf"):
        build_lft(sysae, res.Vf)


def test_loop_shifting_of_d22():
    """Accelerometers with a flap feed-through: a controller designed on the plant with
    D22 removed, mapped back by physical_controller, gives the same closed-loop poles on
    ΣAE(Vf) as the shifted design loop (python-control's interconnection)."""
    import control
    sysae = binary_system("acceleration", dynamic=True)
    Vf = find_flutter(sysae, (0.0, 3.0), n_grid=31).Vf
    lft = build_lft(sysae, Vf)
    assert np.abs(lft.D22).max() > 0.1
    m = lft.nmeas
    rng = np.random.default_rng(3)
    Kt = control.ss([[-4.0]], rng.standard_normal((1, m)), [[0.7]], 0.05 * rng.standard_normal((1, m)))
    Pt = lft.plant_without_d22()
    assert np.all(Pt.D[-m:, -1] == 0)
    nz, nu = Pt.noutputs - m, Pt.ninputs - 1
    design_loop = control.feedback(Pt[nz:nz + m, nu:nu + 1], Kt, sign=+1)  # v -> z~m closed by K~
    K = lft.physical_controller(Kt)
    got = np.linalg.eigvals(sysae.closed_loop_state_matrix(Vf, K))
    assert_allclose(np.sort_complex(np.round(got, 7)), np.sort_complex(np.round(design_loop.poles(), 7)),
                    atol=1e-6)


@pytest.mark.parametrize("seed", range(6))
def test_lft_closure_random_systems(seed):
    """Random Σf (N = 1..3 modes, order 0..4, with/without flap) and random sensors."""
    import control
    from casflutter.aeroelastic import AeroelasticSystem
    from casflutter.structure import ModalStructure
    rng = np.random.default_rng(seed)
    N, nf = int(rng.integers(1, 4)), int(rng.integers(0, 5))
    sensor = ["acceleration", "velocity", "displacement", "state"][seed % 4]
    s = ModalStructure(rng.uniform(2, 20, N), rng.uniform(0, 0.1, N), alpha=rng.uniform(0.5, 2),
                       Hs=rng.standard_normal((2, 2 * N if sensor == "state" else N)), sensor=sensor)
    m_in = N + int(rng.integers(0, 2))
    if nf:
        Af = rng.standard_normal((nf, nf)) - 3 * np.sqrt(nf) * np.eye(nf)
        sf = control.ss(Af, rng.standard_normal((nf, m_in)), rng.standard_normal((N, nf)),
                        rng.standard_normal((N, m_in)))
    else:
        sf = control.ss([], [], [], rng.standard_normal((N, m_in)))
    sysae = AeroelasticSystem.from_parts(sf, s)
    Vf = rng.uniform(0.5, 2.0)
    lft = build_lft(sysae, Vf)
    for dV in rng.uniform(-0.9 * Vf ** 2, 3 * Vf ** 2, size=4):
        closed, direct = lft.close(dV), sysae.loop(np.sqrt(Vf ** 2 + dV))
        want = direct.statespace()
        for got_M, want_M in ((closed.A, want.A), (closed.B, want.B), (closed.C, want.C), (closed.D, want.D)):
            assert_allclose(got_M, want_M, rtol=0, atol=1e-10 * max(1.0, np.abs(want_M).max()))
