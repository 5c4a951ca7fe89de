"""``markers.means`` stands in for ``ndarray.mean``: the learned variances and turn fits must not move."""

import numpy as np
import pytest

from formulations.markers.means import axis_mean, column_nanmedian


@pytest.mark.parametrize("shape", [(0, 3), (1, 3), (62, 3), (17, 5), (9, 3, 3), (4, 6, 3, 3)])
@pytest.mark.parametrize("keepdims", [False, True])
def test_axis_mean_is_numpy_mean_bit_for_bit(shape, keepdims):
    rng = np.random.default_rng(3)
    values = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4, size=shape)
    for axis in range(1, len(shape)):
        assert np.array_equal(axis_mean(values, axis, keepdims), values.mean(axis=axis, keepdims=keepdims))
    assert np.array_equal(axis_mean(values[::2] ** 2), (values[::2] ** 2).mean(axis=1))


@pytest.mark.parametrize("seed", range(6))
def test_column_nanmedian_is_numpy_nanmedian_bit_for_bit(seed):
    """Odd and even counts, columns without NaN, with some, and all NaN (NaN, and no warning)."""
    rng = np.random.default_rng(seed)
    values = rng.normal(size=(int(rng.integers(1, 60)), 9)) * 10.0 ** rng.integers(-2, 4)
    values[rng.random(values.shape) < np.linspace(0.0, 0.9, 9)] = np.nan
    values[:, 4] = np.nan
    values[0, 5] = np.inf
    with pytest.warns(RuntimeWarning, match="All-NaN"):
        expected = np.nanmedian(values, axis=0)
    assert np.array_equal(column_nanmedian(values), expected, equal_nan=True)
