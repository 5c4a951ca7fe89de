"""``markers.lengths`` stands in for ``np.linalg.norm`` over the last axis: labels must not move."""

import numpy as np
import pytest

from formulations.markers.lengths import lengths


@pytest.mark.parametrize("shape", [(0, 3), (1, 3), (1000, 3), (62, 16, 3), (4, 9, 5, 3)])
def test_lengths_are_numpy_norms_bit_for_bit(shape):
    rng = np.random.default_rng(7)
    offsets = rng.normal(size=shape) * 10.0 ** rng.integers(-4, 5, size=shape)
    assert np.array_equal(lengths(offsets), np.linalg.norm(offsets, axis=-1))


def test_lengths_keep_nan_and_inf_as_norm_does():
    offsets = np.array([[np.nan, 0.0, 1.0], [np.inf, 2.0, 0.0], [0.0, 0.0, 0.0]])
    assert np.array_equal(lengths(offsets), np.linalg.norm(offsets, axis=-1), equal_nan=True)
