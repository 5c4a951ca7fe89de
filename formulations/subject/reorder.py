"""A contradicting segment read again on the points its own markers hold.

Two markers of one segment exchanged leave the segment contradicting its constellation
(``contradiction``), and recovery re-reads it from the frame's identification. That reading
can be wrong where the segment is not quite rigid (a hand marker grouped with the forearm)
and its mirror image is in view: CMU 135_02's left forearm, read on the right forearm's
points, was left exchanged for 80 frames. The labels themselves say where the segment is,
only not which marker is which: the points its labeled markers hold are assigned again, each
to one of the segment's markers, by the injective map phi (points -> markers) that fits best,

    phi* = argmin_phi sum_k |R u_phi(k) + d - x_k|^2   (Kabsch for each phi),

and taken when every residual is then within ``RIGID_WITHIN`` tau (the segment fits) and phi*
is not the present labeling. Every map is tried: a segment has at most ``MAX_MARKERS``
markers, 5040 maps of 4 points, one batched Kabsch.
"""

from __future__ import annotations

from itertools import permutations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import rigid_transform
from formulations.subject.geometry import ModelGeometry
from formulations.subject.segment_pose import RIGID_WITHIN

Array = NDArray[np.float64]
Index = NDArray[np.int64]
MAX_MARKERS = 7  # 7!/(7-k)! maps of k points stays one small batch


def reordered(geometry: ModelGeometry, segment: int, positions: Array) -> Index | None:
    """The segment's markers that should hold its labeled points, in the order of those points.

    ``positions`` ``(N, 3)`` are the labels (NaN where unlabeled). Returns ``(K,)`` model
    indices, one per labeled marker of the segment in ``markers[labeled]`` order (the marker
    that should hold that marker's point), or None when the present labels fit best, no map
    makes the segment fit, or the segment has fewer than three labels or too many markers.
    """
    seg = geometry.segments[segment]
    labeled = np.flatnonzero(np.isfinite(positions[seg.markers]).all(axis=1))
    if len(labeled) < 3 or len(seg.markers) > MAX_MARKERS:
        return None
    maps = np.array(list(permutations(range(len(seg.markers)), len(labeled))), dtype=np.int64)
    points = positions[seg.markers[labeled]]
    source = seg.coordinates[maps]
    target = np.broadcast_to(points, source.shape)
    rotation, c_s, c_t = rigid_transform(source, target, np.ones(maps.shape))
    placed = np.einsum("sij,skj->ski", rotation, source - c_s[:, None]) + c_t[:, None]
    residual = np.linalg.norm(placed - target, axis=2)
    fits = (residual <= RIGID_WITHIN * seg.tolerance[maps]).all(axis=1)
    best = int(np.argmin(np.where(fits, (residual**2).sum(axis=1), np.inf)))
    if not fits[best] or (maps[best] == labeled).all():
        return None
    order: Index = seg.markers[maps[best]]
    return order
