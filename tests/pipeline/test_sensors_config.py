"""``[sensors] rows``: the accelerometer rows ``Hs`` (eq. 7) as a run-configuration choice.

The default is the problem's own rows (the seed wing: the paper's §IV rows, checked
against the printed numbers).  Other rows must reach every stage the same way; since
``zm = Hs u''`` is linear in ``Hs``, rows ``R = S H0`` (``S`` invertible) must give the
measured outputs ``S zm(H0)`` of the same motion: the LFT's measured rows, the truth's
LCO record and the closed loop (with the controller ``K S^-1``, which commands the same
flap) are compared with that independent computation.
"""

import control
import numpy as np
import pytest

from casflutter.aeroelastic import AeroelasticSystem, build_lft
from casflutter.errors import ConfigError
from casflutter.pipeline import load_config
from casflutter.truth import closed_loop_truth, load_problem, suppression_run, truth_lco

#: paper §IV, the sensor locations in modal coordinates as printed
PAPER_ROWS = [[0.1299, -0.0006, -0.2866, -0.1130, 0.0766],
              [-0.0021, 0.1364, 0.0141, 0.0021, -0.0020]]
#: an invertible mixing of the two accelerometers
S = np.array([[2.0, 0.5], [-0.3, 1.5]])


@pytest.fixture(scope="module")
def wing():
    return load_problem("seed_wing")


def accelerometer_structure(truth, rows=None):
    """Σs of the truth read by accelerometers at ``rows`` (default: its own)."""
    return truth.modal_structure().with_sensors(rows, "acceleration")


def sensor_rows_of(truth, rows=None):
    """``Hs`` of the truth with ``rows`` (default: its own)."""
    return truth.modal_structure().with_sensors(rows).Hs


def _sigma_f(seed: int = 0, n: int = 8, N: int = 5) -> control.StateSpace:
    """A stable random Σf with inputs [u_1..u_N, v] and outputs y_1..y_N (any Σf will do:
    the sensor rows enter the LFT only through the measured output)."""
    rng = np.random.default_rng(seed)
    A = -np.diag(rng.uniform(5.0, 50.0, n)) + 0.5 * rng.standard_normal((n, n))
    return control.ss(A, rng.standard_normal((n, N + 1)), rng.standard_normal((N, n)),
                      0.1 * rng.standard_normal((N, N + 1)))


def test_default_rows_are_the_papers(wing):
    cfg = load_config()
    assert cfg.sensors.rows == []
    np.testing.assert_array_equal(sensor_rows_of(wing, cfg.sensors.rows), PAPER_ROWS)
    # the configured default gives exactly the structure the pipeline used before the option
    ms = wing.modal_structure()
    before = accelerometer_structure(wing)
    after = accelerometer_structure(wing, sensor_rows_of(wing, cfg.sensors.rows))
    for name in ("omega", "zeta", "Hs"):
        np.testing.assert_array_equal(getattr(after, name), getattr(before, name))
    np.testing.assert_array_equal(after.Hs, ms.Hs)
    assert after.sensor == "acceleration" and after.alpha == before.alpha


def test_explicit_paper_rows_equal_the_default(wing):
    cfg = load_config(updates={"sensors.rows": PAPER_ROWS})
    np.testing.assert_array_equal(sensor_rows_of(wing, cfg.sensors.rows),
                                  wing.modal_structure().Hs)


@pytest.mark.parametrize("rows, words", [
    ([[0.1, 0.2]], ["sensors.rows[0]", "2 entries", "5 modes"]),
    ([[0.1, 0.2, 0.3, 0.4, float("nan")]], ["sensors.rows[0][4]", "finite"]),
    ([[0.1, 0.2, 0.3, 0.4, float("inf")]], ["sensors.rows[0][4]", "finite"]),
    ([PAPER_ROWS[0], [0.1, 0.2, 0.3, 0.4, "a"]], ["sensors.rows[1][4]", "finite number"]),
    ([[0.1, 0.2, 0.3, 0.4, True]], ["sensors.rows[0][4]"]),
    ([0.1, 0.2, 0.3, 0.4, 0.5], ["sensors.rows[0]", "not a list"]),
    ([[0, 0, 0, 0, 0]], ["sensors.rows[0]", "all zeros"]),
    ("Acc1", ["sensors.rows", "expected a list"]),
])
def test_bad_rows_fail_at_load_naming_the_key(rows, words):
    with pytest.raises(ConfigError) as exc:
        load_config(updates={"sensors.rows": rows})
    for w in words:
        assert w in str(exc.value)


def test_rows_in_the_toml_file(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text("[sensors]\nrows = [[1.0, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 0, 0, 1, 0]]\n")
    assert load_config(path).sensors.rows == [[1.0, 0, 0, 0, 0], [0, 1, 0, 0, 0],
                                               [0, 0, 0, 1, 0]]
    path.write_text("[sensors]\nrows = [[1.0, 0, 0, 0, 0]]\nkinds = 'velocity'\n")
    with pytest.raises(ConfigError, match="unknown key 'kinds' in \\[sensors\\]"):
        load_config(path)
    # the row length follows the problem: the typical section has two modes
    path.write_text("[problem]\nname = 'typical_section'\n[sensors]\nrows = [[1.0, 0, 0]]\n")
    with pytest.raises(ConfigError, match="typical_section has 2 modes"):
        load_config(path)


def test_lft_measured_rows_are_linear_in_the_rows(wing):
    """C2, D21, D22 of eq. 14 with rows R equal R times those with identity rows (one
    accelerometer per mode), computed independently; the rest of the LFT is unchanged."""
    sf = _sigma_f()
    Vf = 1.1
    base = build_lft(AeroelasticSystem.from_parts(sf, accelerometer_structure(wing, np.eye(5)),
                                                  warn_unstable=False), Vf)
    H0 = np.asarray(PAPER_ROWS)
    for R in (H0, S @ H0, np.array([[0.0, 0.0, 1.0, -1.0, 0.5]])):
        lft = build_lft(AeroelasticSystem.from_parts(sf, accelerometer_structure(wing, R),
                                                     warn_unstable=False), Vf)
        assert lft.nmeas == R.shape[0]
        for name in ("C2", "D21", "D22"):
            np.testing.assert_allclose(getattr(lft, name), R @ getattr(base, name),
                                       rtol=1e-12, atol=1e-12, err_msg=name)
        for name in ("A", "B1bar", "B2", "C1", "D11", "D12"):
            np.testing.assert_array_equal(getattr(lft, name), getattr(base, name), name)
    # the default configuration reads the paper's rows
    dflt = build_lft(AeroelasticSystem.from_parts(
        sf, accelerometer_structure(wing, sensor_rows_of(wing, load_config().sensors.rows)),
        warn_unstable=False), Vf)
    np.testing.assert_allclose(dflt.C2, H0 @ base.C2, rtol=1e-12, atol=1e-12)


def test_truth_lco_reads_the_given_rows(wing):
    kw = dict(V=1.0, duration=0.4, mode=1, deflection=0.01, dt=0.002)
    ref = truth_lco(wing, **kw)
    mixed = truth_lco(wing, **kw, sensor_rows=S @ np.asarray(PAPER_ROWS))
    np.testing.assert_allclose(mixed.zm, ref.zm @ S.T, rtol=1e-10, atol=1e-12)
    single = truth_lco(wing, **kw, sensor_rows=[PAPER_ROWS[1]])
    np.testing.assert_allclose(single.zm[:, 0], ref.zm[:, 1], rtol=1e-10, atol=1e-14)


def test_closed_loop_with_mixed_rows_and_unmixed_controller_is_the_same_loop(wing):
    """Sensors R = S H0 with the controller K S^-1 command exactly the flap of H0 with K:
    the measured outputs are S zm(H0) throughout, the flap the same."""
    K = control.ss([[-30.0]], [[0.005, -0.001]], [[0.3]], [[1e-3, -5e-4]])
    Kmix = control.ss(K.A, K.B @ np.linalg.inv(S), K.C, K.D @ np.linalg.inv(S))
    t = np.arange(0.0, 0.3, 0.002)
    x0 = wing.displaced_state(1, 0.01)
    a = closed_loop_truth(wing, K, 1.2, t, x0, lambda tt: 1.0)
    b = closed_loop_truth(wing, Kmix, 1.2, t, x0, lambda tt: 1.0,
                          sensor_rows=S @ np.asarray(PAPER_ROWS))
    assert np.isfinite(a.zm).all() and np.abs(a.v).max() > 0
    np.testing.assert_allclose(b.v, a.v, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b.zm, a.zm @ S.T, rtol=1e-9, atol=1e-10)


def test_suppression_run_uses_the_configured_rows(wing):
    """The suppression run reads the configured rows (as the run's other stages do); the
    turbulence is the same for both (one seed), the sensor noise, drawn per configured
    sensor, is left out."""
    phases = {"settle": 0.15, "ramp": 0.05, "hold": 0.1, "release": 0.05, "noise": 0.0}
    base = load_config(updates={"suppression": phases})
    mixed = load_config(updates={"suppression": phases,
                                 "sensors.rows": (S @ np.asarray(PAPER_ROWS)).tolist()})
    K = control.ss([], [], [], [[3e-3, -1e-3]])
    Kmix = control.ss([], [], [], K.D @ np.linalg.inv(S))
    kw = dict(dt=0.002, mode=1, deflection=base.lco.initial_deflection)
    a = suppression_run(wing, K, 1.1, base.suppression, sensor_rows=base.sensors.rows or None,
                        **kw).simulation
    b = suppression_run(wing, Kmix, 1.1, mixed.suppression,
                        sensor_rows=mixed.sensors.rows or None, **kw).simulation
    np.testing.assert_allclose(b.zm, a.zm @ S.T, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(b.v, a.v, rtol=1e-9, atol=1e-12)


def test_sweep_parameter_reaches_the_configuration():
    """``sensors.rows`` as a swept parameter (a list of row sets) gives each point's config."""
    from casflutter.study import Parameter, Study
    from casflutter.study._pipeline_eval import pipeline_config

    alt = [[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0]]
    st = Study(name="s", evaluator="pipeline",
               parameters=(Parameter("sensors.rows", values=(PAPER_ROWS, alt)),
                           Parameter("controller.order", values=(1, 2))))
    pts = st.points()
    assert len(pts) == 4 and len({st.key(p) for p in pts}) == 4
    for p in pts:
        cfg = pipeline_config(p, st.resolved_settings())
        assert cfg.sensors.rows == p["sensors.rows"]
        assert cfg.controller.order == p["controller.order"]
    with pytest.raises(ConfigError, match=r"sensors\.rows\[0\] has 4 entries"):
        pipeline_config({"sensors.rows": [[1.0, 0.0, 0.0, 0.0]]})
