"""What the identification says about records that cannot identify a ROM: an input channel
that never moves is named, and a rank-deficient regression caused by a record much shorter
than the others names that record and its length (not "widen the chirp band")."""

import numpy as np
import pytest

from casflutter.data import IOData, Record, chirp_excitation
from casflutter.errors import DataError
from casflutter.ident import identify, identify_common_denominator

K, DT = 2000, 0.004


def _records(lengths=(K, K, K), zero=()):
    """Three records, each exciting one input (u1, u2, the flap) by a chirp; forces from a
    short FIR filter of the inputs. ``zero``: inputs identically zero in every record."""
    rng = np.random.default_rng(0)
    g = rng.standard_normal((3, 3, 2))   # lags x inputs x outputs
    recs = []
    for i, n in enumerate(lengths):
        w = np.zeros((K, 3))
        if i not in zero:
            w[:, i] = chirp_excitation(K, DT, band=(0.2, 20.0), seed=i)[:, 0]
        y = sum(np.roll(w, lag, axis=0) @ g[lag] for lag in range(3))
        recs.append(Record(y[:n], w[:n, :2], w[:n, 2], f"chirp_{i}"))
    return IOData(tuple(recs), DT, u_names=("u_bend", "u_tors"), v_name="flap")


@pytest.mark.parametrize("zero, names", [((2,), "['flap']"), ((1, 2), "['u_tors', 'flap']")])
def test_a_channel_that_never_moves_is_named(zero, names):
    data = _records(zero=zero)
    with pytest.raises(DataError, match="identically zero") as info:
        identify_common_denominator(data, na=2, nb=6)
    assert names in str(info.value)
    with pytest.raises(DataError, match="never move") as info:
        identify(data, (1, 1, 2, 0, 1, 1))
    assert names in str(info.value)


def test_a_too_short_record_is_named_with_its_length():
    data = _records(lengths=(K, 8, K))
    with pytest.raises(DataError) as info:
        identify_common_denominator(data, na=2, nb=6)
    msg = str(info.value)
    assert "rank-deficient" in msg and "'chirp_1' has only 8 samples (0.032 s)" in msg
    assert f"against {K}" in msg and "as long as the others" in msg
    assert "widen the chirp band" not in msg


def test_records_of_equal_length_keep_the_excitation_advice():
    # collinear inputs in long records: not a matter of length
    data = _records()
    recs = tuple(Record(r.y, np.column_stack([r.u[:, 0], 2 * r.u[:, 0]]), r.v, r.name)
                 for r in data.records)
    with pytest.raises(DataError) as info:
        identify_common_denominator(IOData(recs, DT), na=2, nb=6)
    msg = str(info.value)
    assert "widen the chirp band" in msg and "only" not in msg
