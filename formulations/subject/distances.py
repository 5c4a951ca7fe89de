"""The matrix D of Ringer & Lasenby (2004), Sec. 3: how much each inter-marker distance varies."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.lengths import lengths

Array = NDArray[np.float64]


def distance_spread(positions: Array, min_frames: int) -> tuple[Array, NDArray[np.int64]]:
    """Standard deviation of every inter-marker distance over the frames where both are seen.

    D_{n1,n2} = Var_k |y_{n1}(k) - y_{n2}(k)|; markers on one rigid segment keep their
    distance, so sqrt(D) is then the noise (about sqrt(2) sigma for sigma per coordinate).
    The square root is returned: it is in mm, comparable with a tolerance.

    Args:
        positions: ``(K, N, 3)`` mm, NaN where a marker is missing.
        min_frames: Pairs seen together in fewer frames get +inf (unknown, never rigid).

    Returns:
        ``(N, N)`` sd of the distance (0 on the diagonal) and ``(N, N)`` frames seen together.
    """
    n = positions.shape[1]
    sd, count = np.empty((n, n)), np.empty((n, n), dtype=np.int64)
    for marker in range(n):  # a row at a time: (K, N) distances, not (K, N, N, 3) differences
        dist = lengths(positions - positions[:, marker : marker + 1])
        seen = np.isfinite(dist)
        count[marker] = seen.sum(axis=0)
        filled = np.where(seen, dist, 0.0)
        mean = filled.sum(axis=0) / np.maximum(count[marker], 1)
        var = np.where(seen, (dist - mean) ** 2, 0.0).sum(axis=0) / np.maximum(count[marker], 1)
        sd[marker] = np.where(count[marker] >= min_frames, np.sqrt(var), np.inf)
    np.fill_diagonal(sd, 0.0)
    return sd, count


def mean_distance(a: Array, b: Array) -> float:
    """D'_{l1,l2}: mean distance between two ``(K, 3)`` trajectories over frames where both exist."""
    d = np.linalg.norm(a - b, axis=1)
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size else float("inf")
