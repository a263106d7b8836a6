"""Property-based: any value under any key of a run configuration either loads or is refused
by a ConfigError that names the key; nothing else comes out (no TypeError, no traceback from
deep inside a stage), and the verdict comes at load."""

import dataclasses
import math
import typing

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from casflutter.errors import ConfigError
from casflutter.pipeline import RunConfig, load_config


def _keys(cls, prefix=""):
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        typ = hints[f.name]
        base = typing.get_origin(typ) or typ
        if dataclasses.is_dataclass(base):
            out += _keys(base, f"{prefix}{f.name}.")
        else:
            out.append(f"{prefix}{f.name}")
    return out


KEYS = sorted(_keys(RunConfig))

scalars = st.one_of(
    st.booleans(), st.integers(-10**6, 10**6), st.sampled_from([0, 1, 2, 3, -1, 10**12]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, 1e-300, 1e300, -0.5, 0.5, 1.0, 1.05, 2.5]),
    st.text(max_size=6), st.sampled_from(["auto", "hwl", "lco", "seed_wing", "yes"]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6), st.dictionaries(st.text(max_size=4), inner, max_size=3)),
    max_leaves=12)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(key=st.sampled_from(KEYS), value=values)
def test_any_value_under_any_key_loads_or_is_named(key, value):
    try:
        cfg = load_config(updates={key: value})
    except ConfigError as exc:
        leaf = key.split(".")[-1]
        assert leaf in str(exc) or key.split(".")[0] in str(exc), (key, value, str(exc))
        return
    # accepted: then every number in it is finite
    def finite(x):
        if isinstance(x, float):
            return math.isfinite(x)
        if isinstance(x, dict):
            return all(finite(v) for v in x.values())
        if isinstance(x, (list, tuple)):
            return all(finite(v) for v in x)
        return True
    assert finite(cfg.to_dict()), (key, value)
