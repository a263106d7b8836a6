"""The F-16 ground-vibration records of the source tree's problems/f16gvt (real measured data;
not installed with the package)."""

from pathlib import Path

import numpy as np
import pytest

from casflutter.data import IOData
from casflutter.ident import fit_report, identify

FOLDER = Path(__file__).resolve().parents[2] / "problems" / "f16gvt"


def _load(name):
    return IOData.from_mat(FOLDER / name, y="Acceleration", v="Force", fs="Fs")


def test_records_load_as_documented():
    d = _load("F16Data_FullMSine_Level1.mat")
    assert d.dt == pytest.approx(1 / 400)
    assert d.n_modes == 3 and not d.has_u and d.has_v
    assert d.records[0].n_samples == 73728
    # 12.4 N RMS force on the low level, 24.6 N on the validation level (README)
    assert np.sqrt(np.mean(d.records[0].v ** 2)) == pytest.approx(12.4, rel=0.05)
    v2 = _load("F16Data_FullMSine_Level2_Validation.mat").records[0].v
    assert np.sqrt(np.mean(v2 ** 2)) == pytest.approx(24.6, rel=0.05)


def test_hwl_beats_linear_of_same_orders_on_validation_level():
    """Free-run RMS on the Level-2 record (after 50 samples): the HWL model with quadratic
    polynomials must beat the linear model of the same orders (measured: about 3 %)."""
    est = _load("F16Data_FullMSine_Level1.mat").window(8192, 9 * 8192).decimated(4)
    val = _load("F16Data_FullMSine_Level2_Validation.mat").window(8192, 9 * 8192).decimated(4)
    orders = (1, 8, 7, 0, 2, 2)
    nl = fit_report(identify(est, orders).model, val, "simulation", skip=50)
    lin = fit_report(identify(est, orders[:4] + (1, 1)).model, val, "simulation", skip=50)
    rms = lambda f: float(np.sqrt(np.mean(f.rms_error ** 2)))  # noqa: E731
    assert np.isfinite(rms(nl)) and np.isfinite(rms(lin))
    assert rms(lin) < np.sqrt(np.mean(val.records[0].y ** 2))   # the linear model is not trivial
    assert rms(nl) < 0.99 * rms(lin)
