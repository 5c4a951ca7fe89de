"""Means over one axis of small arrays, as ``ndarray.mean`` computes them.

``mean`` is ``np.add.reduce`` divided by the count behind a Python wrapper that checks its
arguments and counts the items; on the arrays labeling averages every frame (a marker's three
residual components, a rigid triple's three corners) the wrapper costs several times the
arithmetic. The same reduction divided by the same count gives the same floats, bit for bit.
"""

from __future__ import annotations

import numpy as np


def axis_mean(values: np.ndarray, axis: int = 1, keepdims: bool = False) -> np.ndarray:
    """``values.mean(axis=axis, keepdims=keepdims)``."""
    total = np.add.reduce(values, axis=axis, keepdims=True) if keepdims else np.add.reduce(values, axis=axis)
    mean: np.ndarray = total / values.shape[axis]
    return mean
