"""A ROM loop unstable already at the low end of ``flutter.V_range`` has no flutter speed: the
run says so in one warning line (not a Python warning), ``summary.json`` flags it, and a later
stage that needs the flutter speed is refused with the reason.

The wing is a 2-mode model with rational aerodynamics written here (eq. 6 with ``Q(p) = A0 +
A1 p + A2 p / (p + 0.3)``, ``p = s b / U``; its Σf frozen at V0 = 1 flutters at V = 2.857,
6.02 Hz), its chirp records computed by ``lsim`` on a 10x finer grid.  On these noise-free
records the common-denominator ROM with na = 2, nb = 6 is unstable on its own; with na = 1 it
is stable and flutters at the frozen-aero point.
"""

import logging
import re
import warnings

import numpy as np
import pytest
from scipy.signal import lsim

from casflutter.errors import CasflutterError
from casflutter.pipeline import load_config, model_stages, run

B, U_REF, BETA = 1.0, 10.0, 0.3
A0 = np.array([[-20.0, 180.0, 30.0], [-60.0, -120.0, 60.0]])
A1 = np.array([[-25.0, 5.0, 2.0], [3.0, -15.0, 4.0]])
A2 = np.array([[-10.0, 40.0, 5.0], [-15.0, -20.0, 8.0]])

WING = """kind = "wing"
[problem]
name = "synth2"
[modes]
names = ["m1", "m2"]
frequencies_hz = [2.0, 5.0]
damping = [0.01, 0.01]
alpha = 1.0
[speed]
U_ref = 10.0
rho = 1.225
[sensors]
kind = "acceleration"
names = ["a1", "a2"]
units = ["m/s^2", "m/s^2"]
rows = [[1.0, 0.3], [0.2, 1.0]]
[records]
V0 = 1.0
files = ["rec0.npz", "rec1.npz", "rec2.npz"]
time = "t"
displacements = ["u1", "u2"]
flap = "flap"
forces = ["Q1", "Q2"]
"""

RUN = """seed = 0
stages = []
[problem]
name = "wing.toml"
[rom]
method = "common_denominator"
na = {na}
nb = 6
nf = "auto"
[flutter]
V_range = [0.3, 4.5]
n_grid = 111
max_refine = 3
[sensors]
kind = "acceleration"
"""


def _forces(V0, t, inp, dinp):
    """The generalised forces ``Q(s b / U) [u; v]`` of prescribed inputs at speed V0."""
    U = V0 * U_REF
    c = BETA * U / B
    y = inp @ A0.T + (B / U) * dinp @ A1.T
    lag = np.empty_like(inp)
    for j in range(inp.shape[1]):        # p / (p + beta) = 1 - c / (s + c)
        lag[:, j] = inp[:, j] - lsim(([c], [1, c]), inp[:, j], t)[1]
    return y + lag @ A2.T


def _chirp(t, f0, f1, amp):
    T = t[-1]
    rate = (f1 - f0) / T
    phase, dphase = 2 * np.pi * (f0 * t + 0.5 * rate * t ** 2), 2 * np.pi * (f0 + rate * t)
    taper, dtaper = np.sin(np.pi * t / T) ** 2, np.pi / T * np.sin(2 * np.pi * t / T)
    return amp * taper * np.sin(phase), amp * (dtaper * np.sin(phase)
                                               + taper * np.cos(phase) * dphase)


@pytest.fixture(scope="module")
def wing(tmp_path_factory):
    """The wing file and its run configurations (``na`` 2: unstable ROM, 1: stable)."""
    folder = tmp_path_factory.mktemp("unstable_rom")
    dt, T, fine = 0.004, 8.0, 10
    tf = np.arange(int(round(T / dt)) * fine + 1) * dt / fine
    for j in range(3):                   # one chirp per input: mode 1, mode 2, flap
        inp, dinp = np.zeros((tf.size, 3)), np.zeros((tf.size, 3))
        inp[:, j], dinp[:, j] = _chirp(tf, 0.2, 20.0, 0.01)
        y = _forces(1.0, tf, inp, dinp)[::fine]
        inp = inp[::fine]
        np.savez(folder / f"rec{j}.npz", t=tf[::fine], u1=inp[:, 0], u2=inp[:, 1],
                 flap=inp[:, 2], Q1=y[:, 0], Q2=y[:, 1])
    (folder / "wing.toml").write_text(WING)
    for na in (1, 2):
        (folder / f"run_na{na}.toml").write_text(RUN.format(na=na))
    return folder


def test_an_unstable_rom_loop_has_no_flutter_speed_and_says_so(wing, caplog):
    cfg = load_config(wing / "run_na2.toml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with caplog.at_level(logging.WARNING, logger="casflutter"):
            res = run(cfg, quiet=True, write=False)
    assert not res.system.rom_stable
    fl = res.flutter
    assert fl.unstable_at_start and fl.spectral_abscissa_start > 0
    assert res.flutters.Vf is None                   # the crossing is no flutter onset
    s = res.summary()["flutter"]
    assert s["unstable_at_start"] is True
    assert s["spectral_abscissa_start"] == pytest.approx(fl.spectral_abscissa_start)
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    note = [m for m in said if "unstable already at V = 0.3" in m]
    assert len(note) == 1, said
    assert "no flutter onset" in note[0] and "no flutter speed" in note[0]
    assert "Σf, the identified ROM, is unstable on its own" in note[0]
    assert any("unstable in free run" in m for m in said)    # the ROM's fit, one line
    # the stages' own warnings went to the log, not to Python's warnings
    leaked = [str(w.message) for w in caught if "unstable" in str(w.message)]
    assert leaked == []


def test_a_stage_that_needs_the_flutter_speed_is_refused_with_the_reason(wing):
    cfg = load_config(wing / "run_na2.toml", updates={"stages": ["controller"]})
    with pytest.raises(CasflutterError, match=r"unstable already at V = 0\.3.*stage 'controller' "
                                              r"needs the ROM's flutter speed"):
        model_stages(cfg, cfg.problem.load())


def test_a_stable_rom_loop_is_not_flagged(wing, caplog):
    """na = 1: the ROM is stable and its loop flutters at the frozen-aero point (V = 2.857,
    6.016 Hz, mode 2: the eigenvalues of the model above frozen at V0 = 1)."""
    with caplog.at_level(logging.WARNING, logger="casflutter"):
        res = run(load_config(wing / "run_na1.toml"), quiet=True, write=False)
    assert res.system.rom_stable and not res.flutter.unstable_at_start
    assert res.flutters.Vf == pytest.approx(2.857, rel=5e-3)
    s = res.summary()["flutter"]
    assert s["unstable_at_start"] is False and s["spectral_abscissa_start"] < 0
    assert s["mode"] == 2 and s["freq_hz"] == pytest.approx(6.016, rel=5e-3)
    assert not [r for r in caplog.records if "unstable" in r.getMessage()]


def test_casflutter_run_prints_no_flutter_speed_and_fails_its_checks(wing, tmp_path, capsys):
    """``casflutter run``: the flutter line says the loop is unstable already at the range's
    start instead of a flutter speed, and the run's checks fail (exit 3); summary.json says
    so.  With the stable ROM the line is the flutter point and the run passes (exit 0)."""
    from casflutter.cli import main

    out = tmp_path / "out"
    assert main(["-q", "run", str(wing / "run_na2.toml"), "--out", str(out)]) == 3
    text = capsys.readouterr()
    line = next(s for s in text.out.splitlines() if s.startswith("flutter (ROM)"))
    assert "none: the loop is unstable already at V = 0.3" in line
    assert re.search(r"its crossing at V = [\d.]+ is no flutter onset", line), line
    assert "checks passed: False" in text.out and "a check failed" in text.err
    assert main(["-q", "run", str(wing / "run_na1.toml"), "--out", str(out),
                 "--overwrite"]) == 0
    text = capsys.readouterr()
    V = float(re.search(r"flutter \(ROM\):   V = ([\d.]+)", text.out).group(1))
    assert V == pytest.approx(2.857, rel=5e-3) and "checks passed" not in text.out
