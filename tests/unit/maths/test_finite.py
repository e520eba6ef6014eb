"""`cloudcore.maths.finite.nan_to_num` against numpy's own, whose answers it must give."""

import math

import numpy as np
import pytest

from cloudcore.maths.finite import nan_to_num


@pytest.mark.parametrize("nan", [0.0, 1.0, -2.5, math.inf, -math.inf])
def test_nan_to_num_gives_numpys_answer_for_every_kind_of_float(nan):
    values = np.array([1.0, np.nan, np.inf, -np.inf, -3.0, 0.0, -0.0, 1e308, -1e-320, np.nan])
    ours, numpys = nan_to_num(values, nan=nan), np.nan_to_num(values, nan=nan)
    assert ours.dtype == np.float64
    np.testing.assert_array_equal(ours, numpys)
    np.testing.assert_array_equal(np.signbit(ours), np.signbit(numpys))  # -0.0 stays -0.0


def test_nan_to_num_keeps_shapes_and_leaves_its_input_alone():
    values = np.array([[np.nan, 2.0], [np.inf, -1.0]])
    before = values.copy()
    result = nan_to_num(values, nan=7.0)
    assert result.shape == (2, 2) and result[0, 0] == 7.0 and result[1, 0] == np.finfo(np.float64).max
    np.testing.assert_array_equal(values, before)
    assert nan_to_num(np.zeros(0)).shape == (0,)
