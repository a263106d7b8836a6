"""Flutter suppression over a speed interval on the seed wing's ROM loop (eq. 8-16).

Fixture: ``default_rom_loop`` (``problems/seed_wing_rom/rom_loop_seed0.npz``), Σf (nf = 15) and Σs
of the default ``casflutter run`` (seed 0), saved once so that the test does not re-identify
the ROM.
Truth used: the independent verification layer's exact stable interval (guardian map) and
its H∞ norm.
"""

from __future__ import annotations

import numpy as np
import pytest

from casflutter.aeroelastic import build_lft
from casflutter.design import SynthesisOptions, design_flutter_controller, loop_abscissa
from casflutter.errors import ConfigError
from casflutter.verify import verify_controller

def test_fixture_flutters_at_its_vf(default_rom_loop):
    system, Vf = default_rom_loop
    for V, sign in ((0.95 * Vf, -1), (1.05 * Vf, 1)):
        a = np.max(np.linalg.eigvals(system.state_matrix(V)).real)
        assert np.sign(a) == sign


def test_interval_design_is_certified_by_the_verification_layer(default_rom_loop):
    system, Vf = default_rom_loop
    lo, hi = 0.05, 1.45
    res = design_flutter_controller(system, Vf, 2, interval=(lo, hi), n_speeds=10, steps=1,
                                    starts=1, seed=0,
                                    options=SynthesisOptions(max_outer=15, zero_start=False))
    assert res.met and res.reached == (lo, hi)
    lft = build_lft(system, Vf)
    ver = verify_controller(lft.P, res.controller, lft.nmeas, lft.ncon, Vf=Vf,
                            n_delta=lft.n_delta)
    assert ver.stable
    lo_v, hi_v = ver.exact_V
    assert lo_v <= lo and hi_v >= hi          # the exact interval contains the design's
    np.testing.assert_allclose(ver.gamma, res.gamma, rtol=1e-6)
    # the design's own scan agrees with the exact interval inside it
    assert np.all(loop_abscissa(system, res.controller, np.linspace(lo, hi, 50)) < 0)


def test_interval_must_contain_vf(default_rom_loop):
    system, Vf = default_rom_loop
    with pytest.raises(ConfigError, match="interval"):
        design_flutter_controller(system, Vf, 1, interval=(1.5 * Vf, 2 * Vf))


def test_interval_design_with_the_flap_rate_output(default_rom_loop):
    """The default configuration's flap-rate weight with an interval: the stability plants
    carry the flap-rate output too (before, every plant-size check refused the design)."""
    system, Vf = default_rom_loop
    lo, hi = 0.05, 1.45
    res = design_flutter_controller(system, Vf, 2, interval=(lo, hi), n_speeds=10, steps=1,
                                    starts=1, seed=0, flap_rate_weight=0.003,
                                    flap_rate_bandwidth=251.3,
                                    options=SynthesisOptions(max_outer=15, zero_start=False))
    assert res.met and res.reached == (lo, hi)
    lft = build_lft(system, Vf)
    ver = verify_controller(lft.P, res.controller, lft.nmeas, lft.ncon, Vf=Vf,
                            n_delta=lft.n_delta)
    assert ver.stable and ver.exact_V[0] <= lo and ver.exact_V[1] >= hi
    # γ of the design is the weighted plant's: at least the paper's γ on the LFT alone
    assert res.gamma >= ver.gamma * (1 - 1e-9)
