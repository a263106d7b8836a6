"""Study definitions: grid and Latin-hypercube designs, keys, validation."""

from pathlib import Path

import numpy as np
import pytest

from casflutter.errors import ConfigError
from casflutter.study import Parameter, Study, load_study, point_key


def _study(**kw):
    base = dict(name="s", evaluator="truth_flutter",
                parameters=(Parameter("mu", low=10.0, high=40.0, num=4, scale="log"),
                            Parameter("zeta", values=(0.0, 0.01, 0.02))))
    base.update(kw)
    return Study(**base)


def test_grid_is_full_factorial_in_order():
    pts = _study().points()
    assert len(pts) == 12
    mus = sorted({p["mu"] for p in pts})
    np.testing.assert_allclose(mus, [10.0, 10 * 4 ** (1 / 3), 10 * 4 ** (2 / 3), 40.0], rtol=1e-14)
    assert [p["zeta"] for p in pts[:3]] == [0.0, 0.01, 0.02]  # last parameter fastest
    assert len({tuple(p.items()) for p in pts}) == 12


def test_latin_hypercube_one_point_per_stratum_and_seeded():
    st = _study(design="lhs", samples=16, seed=3,
                parameters=(Parameter("a", low=-0.4, high=0.0),
                            Parameter("mu", low=10.0, high=40.0, scale="log"),
                            Parameter("order", low=0, high=3, integer=True)))
    pts = st.points()
    assert len(pts) == 16
    a = np.array([p["a"] for p in pts])
    strata = np.floor((a + 0.4) / 0.4 * 16).astype(int)
    assert sorted(strata) == list(range(16))  # exactly one sample per stratum
    lm = np.log(np.array([p["mu"] for p in pts]))
    strata = np.floor((lm - np.log(10)) / (np.log(40) - np.log(10)) * 16).astype(int)
    assert sorted(strata) == list(range(16))
    orders = [p["order"] for p in pts]
    assert all(isinstance(o, int) for o in orders)
    assert sorted(orders) == sorted([0, 1, 2, 3] * 4)  # equal-probability integers
    assert st.points() == pts  # same seed, same design
    assert _study(design="lhs", samples=16, seed=4, parameters=st.parameters).points() != pts


def test_point_key_is_stable_and_distinguishes_points():
    k = point_key("truth_flutter", {"problem": "typical_section"}, {"mu": 20.0})
    assert k == point_key("truth_flutter", {"problem": "typical_section"}, {"mu": np.float64(20.0)})
    assert k != point_key("truth_flutter", {"problem": "typical_section"}, {"mu": 20.000000001})
    assert k != point_key("truth_flutter", {"problem": "goland"}, {"mu": 20.0})
    assert k != point_key("truth_hopf", {"problem": "typical_section"}, {"mu": 20.0})


def test_load_study_and_validation(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[study]\nevaluator = "truth_flutter"\ndesign = "grid"\n'
                 '[settings]\nproblem = "typical_section"\n'
                 '[parameters]\nmu = [10.0, 20.0]\nsigma = {low = 0.3, high = 0.5, num = 3}\n')
    st = load_study(f)
    assert st.name == "s" and len(st.points()) == 6 and st.base_dir == str(tmp_path)
    f.write_text('[study]\nevaluator = "x"\nbogus = 1\n[parameters]\nmu = [1.0]\n')
    with pytest.raises(ConfigError, match="bogus"):
        load_study(f)
    with pytest.raises(ConfigError, match="both"):
        _study(settings={"mu": 3.0})
    with pytest.raises(ConfigError, match="design"):
        _study(design="sobol")
    with pytest.raises(ConfigError, match="high >= low"):
        Parameter("x", low=2.0, high=1.0)
    with pytest.raises(ConfigError, match="not found"):
        load_study(tmp_path / "missing.toml")


STUDIES = Path(__file__).resolve().parents[2] / "problems" / "studies"


@pytest.mark.parametrize("path", sorted(p.name for p in STUDIES.glob("*.toml")
                                        if not p.name.startswith("sensitivity")))
def test_example_studies_load(path):
    from casflutter.study import get_evaluator

    st = load_study(STUDIES / path)
    assert st.name == Path(path).stem
    assert len(st.points()) >= 3
    get_evaluator(st.evaluator)  # registered
