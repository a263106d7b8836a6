"""One ModalStructure for the truth simulators and the aeroelastic loop.

A truth's structure is the loop's structure: it goes into ΣAE as it is, and the loop's
flutter speed of an exact linear ROM equals the truth's own (the V² scaling is exact at the
identification speed, so it is checked on the truth frozen there).  Initial states are built
by each model, never by indexing its state vector.
"""

import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.aeroelastic import AeroelasticSystem, find_flutter, simulate_loop
from casflutter.errors import ConfigError, DimensionError
from casflutter.ident import identify_common_denominator
from casflutter.realize import realize
from casflutter.structure import ModalState, ModalStructure
from casflutter.truth import TypicalSection, frozen_aero_truth, load_problem, truth_records


def test_the_truths_structure_goes_into_the_loop_as_it_is():
    """The loop's flutter speed of the truth's exact ROM, closed around the truth's own
    structure, equals the frozen truth's own flutter speed."""
    truth = TypicalSection()
    ms = truth.modal_structure()
    assert isinstance(ms, ModalStructure) and ms.sensor == "displacement"
    data = truth_records(truth, V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))
    rom = identify_common_denominator(data).model
    system = AeroelasticSystem.from_parts(realize(rom).sigma_f, ms)
    res = find_flutter(system, (1.0, 3.0), n_grid=61)
    frozen = find_flutter(frozen_aero_truth(truth, 2.0), (1.0, 3.0), n_grid=61)
    assert_allclose(res.Vf, frozen.Vf, rtol=1e-3)
    assert ms.mode_names[res.flutter_mode] == "pitch"


def test_anything_else_is_refused_with_a_clear_error():
    sf = control.ss([], [], [], np.eye(2))
    with pytest.raises(DimensionError, match="casflutter.structure.ModalStructure"):
        AeroelasticSystem.from_parts(sf, {"omega": [1.0, 2.0], "zeta": [0.0, 0.0]})


class _SilentROM:
    """A five-mode discrete ROM that produces no force: the structure moves freely."""

    n_modes, max_lag, dt = 5, 1, 0.002

    def step(self, y, u, v):
        return np.zeros(5)


def test_displaced_state_follows_each_models_ordering():
    """The structure's state is [u_i, u̇_i] per mode, the truth's [u, u', lags]: a structural
    state is a ModalState (u and u̇ by name), which each model writes where it keeps it and
    reads back through its own displacement and velocity selectors."""
    wing = load_problem("seed_wing")
    ms = wing.modal_structure()
    state = ms.displaced_state(1, 0.02)
    assert isinstance(state, ModalState)
    xs = ms.layout.vector(state)
    assert_allclose(ms.Cs @ xs, [0.0, 0.02, 0.0, 0.0, 0.0])
    assert_allclose(ms.Cv @ xs, 0.0)
    x = wing.layout.vector(wing.displaced_state(1, 0.02))
    assert_allclose(x[:wing.n_modes], [0.0, 0.02, 0.0, 0.0, 0.0])
    assert_allclose(x[wing.n_modes:], 0.0)
    both = dict(u=[1, 2, 3, 4, 5], udot=[6, 7, 8, 9, 10])
    assert_allclose(ms.layout.vector(ms.modal_state(**both)), [1, 6, 2, 7, 3, 8, 4, 9, 5, 10])
    assert_allclose(wing.layout.vector(wing.modal_state(**both)),
                    [1, 2, 3, 4, 5, 6, 7, 8, 9, 10])
    assert ms.mode_states[2].tolist() == [4, 5] and wing.mode_states[2].tolist() == [2, 7]
    with pytest.raises(DimensionError, match="mode 5"):
        ms.displaced_state(5, 0.1)
    with pytest.raises(DimensionError, match="mode 7"):
        wing.displaced_state(7, 0.1)
    with pytest.raises(DimensionError, match="udot has 2 entries"):
        ms.modal_state(u=[0, 0, 0, 0, 0], udot=[1, 2])


def test_a_state_from_one_model_is_right_for_the_others():
    """The structure's state and the truth's are laid out differently; a state built by one
    (``displaced_state``, ``modal_state``) starts the other's simulation at the same modal
    displacements and velocities: the Σs loop's first sample and the truth's first sample
    read back the same u and u̇."""
    wing = load_problem("seed_wing")
    ms = wing.modal_structure()
    u, udot = [0.01, -0.02, 0.0, 0.005, 0.0], [0.0, 0.3, -0.1, 0.0, 0.2]
    for state in (ms.modal_state(u, udot), wing.modal_state(u, udot)):
        truth_sim = wing.simulate(np.linspace(0.0, 1e-3, 3), state, 0.5)
        assert_allclose(truth_sim.u[0], u)
        assert_allclose(truth_sim.udot[0], udot)
        loop = simulate_loop(_SilentROM(), ms, 1.0, 3, xs0=state)
        assert_allclose(loop.u[0], u)
        assert_allclose(ms.Cv @ loop.xs[0], udot)
        # the layouts read the same state back
        assert_allclose(ms.layout.state(loop.xs[0]).udot, udot)
        assert_allclose(wing.layout.state(truth_sim.states[0]).u, u)
    # a raw vector is the model's own full state only: the wrong length is refused
    with pytest.raises(DimensionError, match="x0 has 3 entries"):
        wing.simulate(np.linspace(0.0, 1e-3, 3), np.zeros(3), 0.5)


def test_the_loop_starts_where_the_structure_says():
    """simulate_loop from displaced_state: the first sample holds the displacement."""
    ms = load_problem("seed_wing").modal_structure()
    sim = simulate_loop(_SilentROM(), ms, 1.0, 3, xs0=ms.displaced_state(3, 0.05))
    assert_allclose(sim.u[0], [0, 0, 0, 0.05, 0])


def test_with_sensors_changes_rows_and_kind_only():
    wing = load_problem("seed_wing")
    ms = wing.modal_structure()
    assert ms.sensor == "acceleration" and ms.sensor_names[0].startswith("Acc1")
    same = ms.with_sensors()
    assert same is ms
    rows = [[1.0, 0, 0, 0, 0]]
    one = ms.with_sensors(rows, "displacement")
    assert one.n_sensors == 1 and one.sensor == "displacement"
    assert_allclose(one.Hs, rows)
    for name in ("omega", "zeta", "shapes"):
        assert_allclose(getattr(one, name), getattr(ms, name))
    assert one.alpha == ms.alpha and one.mode_names == ms.mode_names
    with pytest.raises(ConfigError, match="2 entries"):
        ms.with_sensors([[1.0, 0.0]])
    with pytest.raises(ConfigError, match="sensor"):
        ms.with_sensors(kind="strain")


def test_defaults_name_every_mode_and_sensor():
    s = ModalStructure([2.0, 5.0], [0.01, 0.02], Hs=[[1.0, 0.0]])
    assert s.mode_names == ("mode 1", "mode 2") and s.sensor_names == ("zm[0]",)
    assert_allclose(s.shapes, np.eye(2))
    with pytest.raises(DimensionError, match="mode_names"):
        ModalStructure([2.0, 5.0], [0.01, 0.02], mode_names=("a",))
