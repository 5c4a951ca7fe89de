"""Batched rotations about the body-frame axes x, y, z."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
AXES = "xyz"


def axis_rotations(axis: str, angles: Array) -> Array:
    """``(N, 3, 3)`` rotations by ``angles`` (N,) radians about ``axis`` ("x", "y" or "z").

    With (i, j) the two other axes in cyclic order, R_ii = R_jj = cos a, R_ij = -sin a,
    R_ji = sin a and R_kk = 1 for the axis k itself: R_y(a) = [[c, 0, s], [0, 1, 0], [-s, 0, c]].
    """
    k = AXES.index(axis)
    i, j = (k + 1) % 3, (k + 2) % 3
    cosine, sine = np.cos(angles), np.sin(angles)
    rotations = np.zeros((len(angles), 3, 3))
    rotations[:, k, k] = 1.0
    rotations[:, i, i] = cosine
    rotations[:, j, j] = cosine
    rotations[:, i, j] = -sine
    rotations[:, j, i] = sine
    return rotations


def sequential_rotation(axes: str, angles: Array) -> Array:
    """``(N, 3, 3)`` product R_a1(angles[:, 0]) R_a2(angles[:, 1]) ... over the axes in order
    (the paper's "sequential rotations about perpendicular axes", Section 3.1); identity for no axes."""
    rotation = np.broadcast_to(np.eye(3), (len(angles), 3, 3)).copy()
    for column, axis in enumerate(axes):
        rotation = rotation @ axis_rotations(axis, angles[:, column])
    return rotation
