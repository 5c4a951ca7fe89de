"""Means and medians over one axis, as numpy computes them, without numpy's per-call overhead.

``mean`` is ``np.add.reduce`` divided by the count behind a Python wrapper that checks its
arguments and counts the items; on the arrays labeling averages every frame (a marker's three
residual components, a rigid triple's three corners) the wrapper costs several times the
arithmetic. The same reduction divided by the same count gives the same floats, bit for bit.

``np.nanmedian`` over the columns of an array with NaNs runs ``apply_along_axis``: one Python
call per column (``shape_breaks``: 11,470 columns, 0.9 s of 03_rolling's 4 s of assembly). One
sort of the whole array, NaN last, gives every column's middle values at once, averaged as
``np.median`` averages its two middle values.
"""

from __future__ import annotations

import numpy as np


def axis_mean(values: np.ndarray, axis: int = 1, keepdims: bool = False) -> np.ndarray:
    """``values.mean(axis=axis, keepdims=keepdims)``."""
    # two calls: numpy's stubs type ``keepdims`` as a literal, so a bool variable matches neither
    total = np.add.reduce(values, axis=axis, keepdims=True) if keepdims else np.add.reduce(values, axis=axis)
    mean: np.ndarray = total / values.shape[axis]
    return mean


def column_nanmedian(values: np.ndarray) -> np.ndarray:
    """``np.nanmedian(values, axis=0)`` of a 2D array, NaN (without a warning) for a column of NaNs."""
    ordered = np.sort(values, axis=0)  # NaN sorts last
    count = (~np.isnan(values)).sum(axis=0)
    low = np.take_along_axis(ordered, np.maximum(count - 1, 0)[None] // 2, axis=0)[0]
    high = np.take_along_axis(ordered, count[None] // 2 - (count[None] == 0), axis=0)[0]
    median: np.ndarray = np.where(count > 0, (low + high) / 2, np.nan)
    return median
