"""The linear ROM with one scalar denominator, identified by variable projection."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from casflutter.data import IOData
from casflutter.errors import DataError
from casflutter.ident import identify_common_denominator
from casflutter.truth import TypicalSection, truth_records


@pytest.fixture(scope="module")
def ts_data():
    return truth_records(TypicalSection(), V0=2.0, dt=0.1, duration=150.0, band=(0.005, 1.0))


def test_identification_is_exact_and_recovers_the_wagner_poles(ts_data):
    """On BDF2 data the truth is exactly a common-denominator ARX model whose poles are the
    sampled Jones lag rates exp(-b_j V dt) (independently from the truth's matrices)."""
    res = identify_common_denominator(ts_data, na=2, nb=6)
    assert res.relative_residual < 1e-10
    lams = np.array(TypicalSection().aero_matrices(2.0).lams)
    assert_allclose(np.sort(res.poles.real), np.sort(np.exp(-lams * 0.1)), rtol=1e-9)
    assert res.stable and res.V == 2.0
    assert res.model.orders.as_tuple() == (1, 2, 5, 0, 1, 1)
    # the model's own free run reproduces the forces of a record it was fitted on
    rec = ts_data.records[1]
    ysim = res.model.simulate(rec.u, rec.v, y0=rec.y[:res.model.max_lag])
    assert np.max(np.abs(ysim - rec.y)) < 1e-8 * np.max(np.abs(rec.y))


def test_non_exciting_input_is_refused(ts_data):
    rec = ts_data.records[0]
    dead = IOData.from_arrays(y=rec.y, u=np.zeros_like(rec.u), v=rec.v, dt=0.1)
    with pytest.raises(DataError, match="non-exciting"):
        identify_common_denominator(dead)
