"""The evaluators' pre-flight check: ``run_sweep`` validates every point before any runs
(the ``pipeline`` evaluator's case is in test_pipeline_sweep.py)."""

import pytest

from casflutter.errors import ConfigError
from casflutter.study import Parameter, PointStore, Study, get_evaluator, run_sweep

CALLS = []


def checked_square(params, settings):
    """A ``module:function`` evaluator whose ``check`` attribute rejects negative x."""
    CALLS.append(params["x"])
    return {"y": params["x"] ** 2}


def _check(params, settings):
    if params["x"] < 0:
        raise ConfigError(f"x = {params['x']}: must be >= 0")


checked_square.check = _check


def test_truth_flutter_rejects_a_misspelt_parameter_before_any_point(tmp_path):
    st = Study(name="tf", evaluator="truth_flutter",
               parameters=(Parameter("mu", values=(10.0, 20.0)),
                           Parameter("zeta_typo", values=(0.0,))),
               settings={"problem": "typical_section"})
    with pytest.raises(ConfigError, match=r"point 1 of 2 \(mu = 10\.0, zeta_typo = 0\.0\).*"
                                          r"zeta_typo"):
        run_sweep(st, store=tmp_path / "tf.jsonl", workers=0, progress=False)
    assert list(PointStore(tmp_path / "tf.jsonl")) == []


def test_synthesis_check_needs_an_existing_plant(tmp_path):
    ev = get_evaluator("synthesis")
    with pytest.raises(ConfigError, match="no file"):
        ev.check_point({"order": 1}, {"plant": "missing.json", "_base_dir": str(tmp_path)})
    with pytest.raises(ConfigError, match="'plant'.*'order'"):
        ev.check_point({}, {"plant": "x.json"})


def test_module_function_check_attribute_and_resumed_points(tmp_path):
    ref = f"{__name__}:checked_square"
    assert get_evaluator(ref).check is _check
    good = Study(name="sq", evaluator=ref, parameters=(Parameter("x", values=(1.0, 2.0)),))
    store = tmp_path / "sq.jsonl"
    CALLS.clear()
    res = run_sweep(good, store=store, workers=0, progress=False)
    assert (res.n_computed, res.n_failed) == (2, 0) and CALLS == [1.0, 2.0]
    bad = Study(name="sq", evaluator=ref, parameters=(Parameter("x", values=(1.0, 2.0, -3.0)),))
    CALLS.clear()
    with pytest.raises(ConfigError, match=r"point 3 of 3 \(x = -3\.0\).*must be >= 0"):
        run_sweep(bad, store=store, workers=0, progress=False)
    assert CALLS == [] and len(list(PointStore(store))) == 2
