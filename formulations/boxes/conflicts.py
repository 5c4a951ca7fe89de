"""Spatial conflict sets of boxes (Jiang Sec. II-B): boxes that cannot both be visible.

For a detection box v of frame m, its conflict set O(v) holds v and every other box of
the same frame that overlaps it so much that the two cannot be two visible people:

    e in O(v)  iff  corner_distance(v, e) <= corner_distance_max * mean height(v, e)
                or  overlap_ratio(v, e) >= overlap_ratio_min,

with the paper's city-block distance of the 4 corners (made scale-free by the mean box
height, since people far away are small) and its overlap ratio, intersection over mean
area. The window LP then lets at most one path through each O(v) (one resource per v,
consumed by v and by every e in O(v)); the occlusion node is in no set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from formulations.boxes.geometry import corner_distance, height, overlap_ratio


@dataclass(frozen=True)
class ConflictRule:
    """When two boxes of one frame are one spatial location.

    Attributes:
        corner_distance_max: Total city-block corner distance, in mean box heights, at or
            under which two boxes conflict (0 turns this measure off).
        overlap_ratio_min: Intersection over mean area at or over which two boxes
            conflict (above 1 turns this measure off).
    """

    corner_distance_max: float = 0.5
    overlap_ratio_min: float = 0.85

    def __post_init__(self) -> None:
        if not (self.corner_distance_max >= 0 and self.overlap_ratio_min > 0):
            raise ValueError("corner_distance_max must be >= 0 and overlap_ratio_min > 0")

    def conflicts(self, boxes: NDArray[np.float64]) -> NDArray[np.bool_]:
        """``(B, B)`` True where boxes i and j (corners) of one frame conflict; True on the diagonal."""
        heights = height(boxes)
        scale = 0.5 * (heights[:, None] + heights[None, :])
        near = corner_distance(boxes, boxes) <= self.corner_distance_max * scale
        result: NDArray[np.bool_] = near | (overlap_ratio(boxes, boxes) >= self.overlap_ratio_min)
        np.fill_diagonal(result, True)
        return result


def conflict_resources(rule: ConflictRule, frame: NDArray[np.int_], boxes: NDArray[np.float64]) -> sp.csr_matrix:
    """``(K, K)`` 0/1: detection k consumes resource j when k is in O(detection j).

    Detections of different frames never conflict, so the matrix is block diagonal by frame.
    """
    rows: list[NDArray[np.int_]] = []
    cols: list[NDArray[np.int_]] = []
    for f in np.unique(frame):
        index = np.flatnonzero(frame == f)
        i, j = np.nonzero(rule.conflicts(boxes[index]))
        rows.append(index[i])
        cols.append(index[j])
    k = len(frame)
    if not rows:
        return sp.csr_matrix((k, k))
    r, c = np.concatenate(rows), np.concatenate(cols)
    return sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(k, k))


def distinct_chains(chains: list[NDArray[np.int_]], conflicting: sp.csr_matrix) -> list[NDArray[np.int_]]:
    """The chains that are not another chain seen twice: longest first, a chain each of whose
    boxes is in the conflict set of a box of a chain already kept is dropped.

    Two detections of one person (a detector's duplicate, or two boxes overlapping past the
    conflict rule) link into two parallel chains; each would be born an object, and the two
    objects then share the person's boxes, one of them held occluded. A chain crossing a kept
    one shares only some frames with it and stays.
    """
    kept: set[int] = set()
    covered = np.zeros(conflicting.shape[0], dtype=bool)
    for i in sorted(range(len(chains)), key=lambda i: -len(chains[i])):
        if len(chains[i]) and covered[chains[i]].all():
            continue
        kept.add(i)
        covered[conflicting[chains[i]].indices] = True
    return [chain for i, chain in enumerate(chains) if i in kept]
