"""The truth with its aerodynamics frozen at one speed (what a V²-scaled ROM represents)."""

import numpy as np
from numpy.testing import assert_allclose

from casflutter.truth import TypicalSection, frozen_aero_truth


def test_frozen_truth_equals_the_truth_at_v0():
    T = TypicalSection()
    assert_allclose(frozen_aero_truth(T, 1.7).state_matrix(1.7), T.state_matrix(1.7), atol=0)
    assert not np.allclose(frozen_aero_truth(T, 1.7).state_matrix(2.2), T.state_matrix(2.2))
