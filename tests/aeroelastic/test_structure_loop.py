"""Σs (eq. 6-7) and ΣAE(V) (eq. 8-9) against analytic and independent results."""

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import AeroelasticSystem, aeroelastic_loop, split_sigma_f
from casflutter.structure import ModalStructure
from casflutter.errors import ConfigError, DimensionError

from ._cases import binary_system


def _sorted(z):
    return np.sort_complex(np.round(np.asarray(z), 10))


def test_structure_poles_are_analytic():
    omega, zeta = np.array([3.0, 17.0, 40.0]), np.array([0.0, 0.05, 0.3])
    s = ModalStructure(omega, zeta, alpha=2.0)
    analytic = np.concatenate([[-z * w + 1j * w * np.sqrt(1 - z * z), -z * w - 1j * w * np.sqrt(1 - z * z)]
                               for w, z in zip(omega, zeta)])
    assert_allclose(_sorted(np.linalg.eigvals(s.As)), _sorted(analytic), atol=1e-10)
    assert_allclose(_sorted(s.statespace(V=0.7).poles()), _sorted(analytic), atol=1e-10)
    assert_allclose(_sorted(s.eigenvalues()), _sorted(analytic), atol=1e-12)


def test_structure_acceleration_output_is_udd():
    """zm = Hs ü with ü from eq. 6 evaluated directly."""
    rng = np.random.default_rng(0)
    omega, zeta, alpha, V = np.array([4.0, 9.0]), np.array([0.01, 0.04]), 0.8, 1.7
    Hs = rng.standard_normal((3, 2))
    s = ModalStructure(omega, zeta, alpha=alpha, Hs=Hs)
    ss = s.statespace(V)
    x, y, w = rng.standard_normal(4), rng.standard_normal(2), rng.standard_normal(2)
    out = ss.C @ x + ss.D @ np.concatenate([y, w])
    u, ud = x[0::2], x[1::2]
    udd = -omega ** 2 * u - 2 * zeta * omega * ud + alpha * (V ** 2 * y + w)
    assert_allclose(out[:2], u, atol=1e-12)
    assert_allclose(out[2:], Hs @ udd, atol=1e-12)


def test_structure_bad_input():
    with pytest.raises(DimensionError, match="omega"):
        ModalStructure([1.0, 2.0], [0.1])
    with pytest.raises(ConfigError, match="sensor"):
        ModalStructure([1.0], [0.1], sensor="strain")
    with pytest.raises(DimensionError, match="Hs"):
        ModalStructure([1.0, 2.0], [0.1, 0.1], Hs=np.ones((1, 4)))  # 2N columns need sensor='state'


def test_static_sigma_f_gives_analytic_loop_frequencies():
    """Diagonal static Σf: ü + 2ζωu̇ + (ω² − αV²d) u = 0 mode by mode."""
    omega, zeta, alpha, d = np.array([5.0, 12.0]), np.array([0.02, 0.05]), 1.5, np.array([3.0, -7.0])
    s = ModalStructure(omega, zeta, alpha=alpha)
    sf = control.ss([], [], [], np.diag(d))
    V = 1.3
    w2 = omega ** 2 - alpha * V ** 2 * d
    analytic = np.concatenate([[-z * w + 1j * np.sqrt(w2i - (z * w) ** 2), -z * w - 1j * np.sqrt(w2i - (z * w) ** 2)]
                               for w, z, w2i in zip(omega, zeta, w2)])
    # with Σf static, ΣAE keeps ω in the damping term and shifts the stiffness
    loop = aeroelastic_loop(sf, s, V)
    assert_allclose(_sorted(loop.poles()), _sorted(analytic), atol=1e-10)


def test_dynamic_sigma_f_matches_characteristic_polynomial():
    """One mode, first-order Σf: (s²+2ζωs+ω²)(s+a) − αV²(cb + d(s+a)) = 0."""
    w, z, alpha, a, b, c, d, V = 6.0, 0.03, 1.2, 4.0, 2.0, -1.5, 0.8, 1.9
    s = ModalStructure([w], [z], alpha=alpha)
    sf = control.ss([[-a]], [[b]], [[c]], [[d]])
    p2 = np.array([1.0, 2 * z * w, w * w])
    poly = np.polysub(np.polymul(p2, [1.0, a]), alpha * V ** 2 * np.polyadd([c * b], [d, d * a]))
    loop = aeroelastic_loop(sf, s, V)
    assert_allclose(_sorted(loop.poles()), _sorted(np.roots(poly)), atol=1e-9)


@pytest.mark.parametrize("sensor", ["acceleration", "velocity", "displacement", "state"])
def test_loop_sensor_rows_follow_the_closed_loop(sensor):
    """zm equals the sensor applied to the loop's own state derivative / state."""
    rng = np.random.default_rng(1)
    sysae = binary_system(sensor, dynamic=True)
    s = sysae.structure
    V = 1.4
    loop = sysae.loop(V)
    for _ in range(3):
        x, w, v = rng.standard_normal(loop.A.shape[0]), rng.standard_normal(2), rng.standard_normal()
        xdot = loop.A @ x + loop.B1 @ w + loop.B2 * v
        zm = loop.C2 @ x + loop.D21 @ w + loop.D22 * v
        xs, xsd = x[:4], xdot[:4]
        expect = {"acceleration": lambda: s.Hs @ xsd[1::2], "velocity": lambda: s.Hs @ xs[1::2],
                  "displacement": lambda: s.Hs @ xs[0::2], "state": lambda: s.Hs @ xs}[sensor]()
        assert_allclose(zm, expect, atol=1e-10)
    ss = loop.statespace(include_modal=True)
    assert ss.ninputs == 3 and ss.noutputs == s.n_sensors + 2


def test_loop_bad_input_names_both_dimensions():
    s = ModalStructure([1.0, 2.0, 3.0], [0.1, 0.1, 0.1])
    sf = control.ss([[-1.0]], [[1.0, 0.0, 0.0]], [[1.0], [0.0]], np.zeros((2, 3)))
    with pytest.raises(DimensionError, match=r"2 outputs.*3 modes"):
        AeroelasticSystem.from_parts(sf, s)
    s2 = ModalStructure([1.0, 2.0], [0.1, 0.1])
    with pytest.raises(DimensionError, match="4 inputs"):
        split_sigma_f(control.ss([], [], [], np.zeros((2, 4))), 2)
    with pytest.raises(DimensionError, match="continuous"):
        AeroelasticSystem.from_parts(control.ss([[0.5]], [[1.0, 0.0]], [[1.0], [0.0]], np.zeros((2, 2)), 0.01), s2)


def test_unstable_rom_is_flagged():
    s = ModalStructure([1.0], [0.1])
    with pytest.warns(RuntimeWarning, match="unstable"):
        sysae = AeroelasticSystem.from_parts(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]]), s)
    assert not sysae.rom_stable and sysae.rom_spectral_abscissa == pytest.approx(0.5)
