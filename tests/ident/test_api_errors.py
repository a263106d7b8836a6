"""The identify API's bad inputs: casflutter errors naming the argument and the
fix, raised before any work; a property-based suite where only casflutter errors come out."""

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from casflutter.data import IOData
from casflutter.errors import CasflutterError, ConfigError, DataError, OrderError
from casflutter.ident import (IdentificationSettings, identify, random_hwl_model, stage1,
                              synthetic_data)
from casflutter.ident import _identify as identify_module


@pytest.fixture(scope="module")
def data():
    return synthetic_data(random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1), 400, seed=2)


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if stage 1 starts: the error must come before any work."""
    def boom(*a, **k):
        raise AssertionError("stage 1 ran before the argument was checked")
    monkeypatch.setattr(identify_module, "stage1", boom)


@pytest.mark.parametrize("orders,match", [
    (None, "orders=None"),
    ((3, 1, 1, 1, 2, float("nan")), "q=nan"),
    ((3, 1.5, 1, 1, 2, 2), "na=1.5"),
    ((3, 1, 1), "got 3 values"),
    (("a", 1, 1, 1, 2, 2), "mu='a'"),
    ((3, 1, 1, 1, True, 2), "boolean"),
    (5, "not a sequence"),
    ({"mu": 1, "nx": 2}, "unknown key"),
    ((0, 1, 1, 1, 2, 2), "mu=0 is out of range"),
])
def test_bad_orders(data, no_work, orders, match):
    with pytest.raises(OrderError, match=match):
        identify(data, orders)


@pytest.mark.parametrize("kwargs,match", [
    ({"criterion": "magic"}, "criterion='magic'.*prediction"),
    ({"regularization": -1.0}, "regularization=-1.0.*>= 0"),
    ({"regularization": float("nan")}, "regularization=nan"),
    ({"regularization": "1"}, "regularization='1'"),
    ({"solver": "newton"}, "solver"),
    ({"max_time": 0}, "max_time"),
    ({"max_iter": -1}, "max_iter"),
    ({"tol": 2.0}, "tol"),
    ({"offset": "yes"}, "offset"),
    ({"ipopt_options": {1: 2}}, "ipopt_options"),
    ({"shooting_intervall": 3}, "unknown identification setting.*shooting_interval"),
])
def test_bad_settings(data, no_work, kwargs, match):
    with pytest.raises(ConfigError, match=match):
        identify(data, (2, 1, 1, 1, 2, 2), **kwargs)


def test_settings_errors_are_valueerrors_too():
    with pytest.raises(ValueError):
        IdentificationSettings(criterion="magic")


def test_bad_initial(data, no_work):
    other = random_hwl_model(2, (1, 1, 1, 1, 2, 2), seed=1)
    with pytest.raises(OrderError, match="initial model"):
        identify(data, (2, 1, 1, 1, 2, 2), initial=other)
    with pytest.raises(ConfigError, match="needs"):
        identify(data, (2, 1, 1, 1, 2, 2), initial=np.zeros(3))
    with pytest.raises(DataError, match="IOData"):
        identify(np.zeros((10, 2)), (2, 1, 1, 1, 2, 2))


def test_high_orders_never_succeed_with_a_nan_fit(data):
    """Orders (10, 5, 5, 5, 5, 5): whatever stage 2 does, a returned result has a finite
    free-run fit; otherwise a casflutter error is raised."""
    big = synthetic_data(random_hwl_model(2, (2, 1, 1, 1, 2, 2), seed=1), 3000, seed=2,
                         noise=0.05)
    for criterion in ("prediction", "simulation"):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = identify(big, (10, 5, 5, 5, 5, 5), criterion=criterion, max_iter=30)
        except CasflutterError:
            continue
        assert np.all(np.isfinite(res.fit.error_percent))
        assert res.success == (res.return_status == "Solve_Succeeded")


# -- property-based: random orders, shapes, dtypes and values ---------------------------
orders_st = st.tuples(*[st.one_of(st.integers(-2, 6), st.floats(allow_nan=True),
                                  st.none(), st.text(max_size=2))] * 6)
value_st = st.sampled_from([0.0, 1.0, -1e300, 1e300, 1e-300, np.nan, np.inf])


@st.composite
def io_arrays(draw):
    K = draw(st.integers(0, 60))
    N = draw(st.integers(1, 3))
    dtype = draw(st.sampled_from([np.float64, np.float32, np.int64, np.int8, bool,
                                  np.complex128]))
    seed = draw(st.integers(0, 2 ** 16))
    rng = np.random.default_rng(seed)
    scale = draw(st.sampled_from([1e-200, 1e-3, 1.0, 1e3, 1e200]))
    with np.errstate(invalid="ignore", over="ignore"):
        y = (rng.normal(size=(K, N)) * scale).astype(dtype)
        u = (rng.normal(size=(K, N)) * scale).astype(dtype) if draw(st.booleans()) else None
        v = ((rng.normal(size=K) * scale).astype(dtype) if (u is None or draw(st.booleans()))
             else None)
    if K and draw(st.booleans()):
        y.flat[draw(st.integers(0, y.size - 1))] = draw(value_st) if dtype == np.float64 else 0
    return y, u, v


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(arrays=io_arrays(), orders=st.one_of(orders_st, st.tuples(*[st.integers(0, 4)] * 6)),
       criterion=st.sampled_from(["prediction", "simulation", "bogus"]),
       regularization=st.sampled_from([0.0, 1e-3, -1.0, np.nan, np.inf]))
def test_identify_raises_only_casflutter_errors(arrays, orders, criterion, regularization):
    y, u, v = arrays
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = IOData.from_arrays(y=y, u=u, v=v, dt=0.01)
            res = identify(data, orders, criterion=criterion, regularization=regularization,
                           max_iter=20)
    except CasflutterError:
        return
    # a returned result is usable: finite model and finite free-run fit
    assert np.all(np.isfinite(res.model.theta))
    assert np.all(np.isfinite(res.fit.error_percent) | (np.linalg.norm(y, axis=0) == 0))


def test_stage1_overflow_is_a_data_error():
    rng = np.random.default_rng(0)
    data = IOData.from_arrays(y=rng.normal(size=(200, 1)) * 1e200,
                              u=rng.normal(size=(200, 1)) * 1e200, dt=1.0)
    with pytest.raises(DataError):
        identify(data, (1, 1, 1, 0, 3, 3), scale_data=False)
    with pytest.raises(DataError):
        stage1(random_hwl_model(1, (1, 1, 1, 0, 3, 3), has_v=False).structure, data)


def test_ipopt_defaults_come_from_one_place(data, monkeypatch):
    """Stage 2 adds no Ipopt option of its own (the defaults live in _nlp), and max_iter
    maps onto ipopt.max_iter; the Gauss-Newton limit defaults to the same number."""
    from casflutter import _nlp
    from casflutter.ident import _refine

    seen = []
    real = _refine.make_solver

    def spy(nlp, options=None, name="nlp"):
        seen.append(dict(options or {}))
        return real(nlp, options, name)

    monkeypatch.setattr(_refine, "make_solver", spy)
    identify(data, (2, 1, 1, 1, 2, 2))
    assert "ipopt.max_iter" not in seen[-1]
    identify(data, (2, 1, 1, 1, 2, 2), max_iter=7)
    assert seen[-1]["ipopt.max_iter"] == 7
    assert (IdentificationSettings().iteration_limit
            == _nlp.DEFAULT_IPOPT_OPTIONS["ipopt.max_iter"] == 500)
