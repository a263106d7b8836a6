"""Order selection by held-out free-run error."""

import pytest

from casflutter.errors import ConfigError, OrderError
from casflutter.ident import (HWLOrders, order_grid, parse_grid, random_hwl_model,
                              select_orders, synthetic_data)

TRUE = (1, 2, 1, 0, 2, 3)


@pytest.fixture(scope="module")
def selection():
    truth = random_hwl_model(1, TRUE, has_v=False, seed=3, nonlinearity=0.5, alpha_ratio=1.0,
                             ar_radius=0.8)
    data = synthetic_data(truth, 3000, seed=4, noise=0.01, amplitude=1.5)
    return select_orders(data, {"na": (1, 2, 3), "p": (1, 2, 3), "q": (1, 2, 3)}, base=TRUE)


def test_select_orders_picks_the_true_orders(selection):
    """27 candidates (p != q among them): the truth wins; every smaller candidate is worse
    by more than the tolerance and every larger one has more parameters."""
    assert selection.best.orders == HWLOrders(*TRUE)
    assert len(selection.candidates) == 27
    best = selection.best
    assert best.score < 1.1            # 1 % output noise: the error % is the noise level
    for c in selection.candidates:
        if c.ok and c.score <= best.score * (1 + selection.rel_tol):
            assert c.n_params >= best.n_params
    # nested smaller models (fewer lags or lower degrees) are clearly worse
    for o in [(1, 1, 1, 0, 2, 3), (1, 2, 1, 0, 1, 3), (1, 2, 1, 0, 2, 2)]:
        c = next(c for c in selection.candidates if c.orders.as_tuple() == o)
        assert c.score > 1.05 * best.score


def test_selection_table_lists_every_candidate(selection):
    text = selection.table()
    lines = text.splitlines()
    assert len(lines) == 27 + 2
    assert "params" in lines[0] and "held-out" in lines[0] and "time" in lines[0]
    chosen = [line for line in lines if line.endswith("*")]
    assert len(chosen) == 1 and "(1, 2, 1, 0, 2, 3)" in chosen[0]
    assert selection.best.model is not None
    assert all(c.model is None for c in selection.candidates if c is not selection.best)


def test_grid_parsing_and_expansion():
    assert parse_grid("na=1:3 p=1,2;q=2") == {"na": (1, 2, 3), "p": (1, 2), "q": (2,)}
    grid = order_grid({"na": (1, 2), "q": [1, 3]}, base=(2, 1, 1, 1, 2, 2))
    assert [o.as_tuple() for o in grid] == [(2, 1, 1, 1, 2, 1), (2, 1, 1, 1, 2, 3),
                                            (2, 2, 1, 1, 2, 1), (2, 2, 1, 1, 2, 3)]
    assert len(order_grid([(1, 1, 1, 0, 1, 1), (1, 1, 1, 0, 1, 1)])) == 1
    with pytest.raises(ConfigError, match="unknown name"):
        order_grid({"nx": (1,)})
    with pytest.raises(ConfigError, match="NAME=VALUES"):
        parse_grid("na")
    with pytest.raises(ConfigError, match="integers"):
        parse_grid("na=a:b")
    with pytest.raises(ConfigError, match="more than"):
        order_grid({"na": range(1, 20), "nb": range(0, 20), "p": range(1, 6)})
    with pytest.raises(OrderError):
        order_grid({"q": (0,)})


def test_select_orders_rejects_bad_arguments_before_work():
    truth = random_hwl_model(1, TRUE, has_v=False, seed=3)
    data = synthetic_data(truth, 300, seed=4)
    with pytest.raises(ConfigError, match="validation"):
        select_orders(data, [TRUE], validation=1.5)
    with pytest.raises(ConfigError, match="rel_tol"):
        select_orders(data, [TRUE], rel_tol=float("nan"))
    with pytest.raises(ConfigError, match="criterion"):
        select_orders(data, [TRUE], criterion="magic")


def _candidate(orders, n_params, score):
    from casflutter.ident import OrderCandidate

    return OrderCandidate(HWLOrders(*orders), n_params, score, None, None, "Solve_Succeeded",
                          "", 0.0)


def test_equal_sized_candidates_within_the_tie_tolerance_go_to_the_earlier():
    """The choice does not hinge on the last bits of the scores: of two candidates with the
    same number of parameters whose scores agree to 1e-6 relative, the first of the grid
    wins, whichever score is the lower; a clear difference still decides."""
    from casflutter.ident._select import SCORE_TIE_RTOL, _parsimonious

    a, b = (1, 1, 1, 0, 2, 2), (1, 1, 1, 0, 2, 3)
    for eps in (1e-15, -1e-15, 0.1 * SCORE_TIE_RTOL, -0.1 * SCORE_TIE_RTOL):
        first, second = _candidate(a, 10, 1.0), _candidate(b, 10, 1.0 * (1 + eps))
        assert _parsimonious([first, second], 0.02) is first
    better = _candidate(b, 10, 0.99)
    assert _parsimonious([_candidate(a, 10, 1.0), better], 0.02) is better
    # fewer parameters within rel_tol still win over a lower score
    small = _candidate(a, 8, 1.015)
    assert _parsimonious([_candidate(b, 10, 1.0), small], 0.02) is small
