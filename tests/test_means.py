"""``markers.means`` stands in for ``ndarray.mean``: the learned variances and turn fits must not move."""

import numpy as np
import pytest

from formulations.markers.means import axis_mean


@pytest.mark.parametrize("shape", [(0, 3), (1, 3), (62, 3), (17, 5), (9, 3, 3), (4, 6, 3, 3)])
@pytest.mark.parametrize("keepdims", [False, True])
def test_axis_mean_is_numpy_mean_bit_for_bit(shape, keepdims):
    rng = np.random.default_rng(3)
    values = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4, size=shape)
    for axis in range(1, len(shape)):
        assert np.array_equal(axis_mean(values, axis, keepdims), values.mean(axis=axis, keepdims=keepdims))
    assert np.array_equal(axis_mean(values[::2] ** 2), (values[::2] ** 2).mean(axis=1))
