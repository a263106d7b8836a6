import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="session")
def seed_wing_sigma_f():
    """Σf of the linear ROM identified from the seed wing's records at the paper's V0 = 0.69
    (``flutter.toml``'s records: amplitude 0.002, no coupling delay; common denominator
    na = 2, nb = 6; ERA at the exact order, Tustin).  Shared by the tests that close it
    around the wing's controllers."""
    from casflutter.ident import identify_common_denominator
    from casflutter.realize import realize
    from casflutter.truth import RecordSettings, SeedWing, truth_records

    records = RecordSettings(amplitude=0.002, coupling_delay=0)
    rom = identify_common_denominator(truth_records(SeedWing(), records, V0=0.69), 2, 6)
    return realize(rom.model).sigma_f


#: a run on the goland_4flaps family file (50 states, 4 flaps, 8 sensors, 41 airspeeds): the
#: order-2 multi-speed design over [60, 150] m/s without an H∞ phase, in seconds
GOLAND_FAMILY_RUN = """
seed = 0
stages = ["controller"]
[problem]
name = "goland_4flaps"
[controller]
order = 2
interval = [60.0, 150.0]
hinf_speeds = 0
"""


@pytest.fixture(scope="session")
def goland_family_run_toml() -> str:
    """The run configuration of :func:`goland_family_run` (:data:`GOLAND_FAMILY_RUN`)."""
    return GOLAND_FAMILY_RUN


@pytest.fixture(scope="session")
def goland_family_run(tmp_path_factory, goland_family_run_toml):
    """``(folder, summary)`` of ``casflutter run`` on :data:`GOLAND_FAMILY_RUN`, shared by the
    family-run and family-report tests."""
    import json

    from casflutter.cli import main

    folder = tmp_path_factory.mktemp("goland_family_run")
    cfg = folder / "run.toml"
    cfg.write_text(goland_family_run_toml)
    out = folder / "out"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 0
    return out, json.loads((out / "summary.json").read_text())


@pytest.fixture
def numpy_global_seed():
    """Seed numpy's global random state for the test and restore it afterwards: python-control's
    ``rss``/``drss`` draw from it, so a test that uses them is otherwise different on every run."""
    import numpy as np

    state = np.random.get_state()
    np.random.seed(0)
    yield
    np.random.set_state(state)


@pytest.fixture(scope="session")
def default_rom_loop():
    """``(ΣAE, Vf)``: the seed wing's default run's ROM loop (seed 0), the frozen loop of eq. 8
    kept in ``problems/seed_wing_rom/rom_loop_seed0.npz``; immutable, so shared by the session."""
    from casflutter._resources import problems_dir
    from casflutter.aeroelastic import load_rom_loop

    return load_rom_loop(problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz")


@pytest.fixture(scope="session")
def closed_loop_abscissa():
    """``abscissa(family, K, V)``: the spectral abscissa of ``v = K zm`` closed on
    ``family.loop(V).flap_to_sensors()`` by python-control (``control.feedback``, positive
    feedback), independently of the package's own closed-loop map."""
    import control
    import numpy as np

    def abscissa(family, K, V):
        cl = control.feedback(family.loop(V).flap_to_sensors(), K, sign=1)
        return float(np.max(np.linalg.eigvals(np.asarray(cl.A)).real))

    return abscissa
