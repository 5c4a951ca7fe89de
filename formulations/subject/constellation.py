"""Where one segment's marker constellation lies in an unlabeled cloud: pose hypotheses.

A rigid body keeps its inter-marker distances, so three markers (a, b, c) of a segment can
only be three points (i, j, k) with

    | |x_i - x_j| - |u_a - u_b| | <= tau_ab,  | |x_i - x_k| - |u_a - u_c| | <= tau_ac,  | |x_j - x_k| - |u_b - u_c| | <= tau_bc,

tau_ab = sqrt(tau_a^2 + tau_b^2) (``ModelGeometry``). Each such triple is a correspondence;
its Kabsch pose (R, d) places every marker of the segment at R u_p + d, and a marker is an
inlier when a point lies within tau_p of it. The inliers are refitted by Kabsch, and the
hypotheses are ranked by inliers, then RMS residual. Every triple of markers serves as a
base, so a segment is found with any three of its markers visible.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import overload

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from formulations.markers.rigid import rigid_transform
from formulations.subject.geometry import SegmentGeometry

Array = NDArray[np.float64]
Index = NDArray[np.int64]


@dataclass(frozen=True)
class Pose:
    """Marker p of a segment lies at ``rotation @ u_p + origin``."""

    rotation: Array
    origin: Array

    def place(self, local: Array) -> Array:
        placed: Array = local @ self.rotation.T + self.origin
        return placed


@dataclass(frozen=True)
class Hypothesis:
    """A pose of one segment and the point each of its markers takes (-1: none within tau)."""

    segment: int
    pose: Pose
    point: Index
    rms: float

    @property
    def inliers(self) -> int:
        return int((self.point >= 0).sum())


@dataclass(frozen=True, eq=False)  # arrays: compared by identity, never element by element
class Hypotheses(Sequence[Hypothesis]):
    """A segment's hypotheses as arrays, best first; a ``Hypothesis`` is made only when one is
    read (a dense cloud's segments have thousands, and the tree choice reads the arrays)."""

    segment: int
    rotation: Array  # (H, 3, 3)
    origin: Array  # (H, 3)
    point: Index  # (H, S)
    rms: Array  # (H,)

    def __len__(self) -> int:
        return len(self.rms)

    @overload
    def __getitem__(self, k: int) -> Hypothesis: ...
    @overload
    def __getitem__(self, k: slice) -> Sequence[Hypothesis]: ...
    def __getitem__(self, k: int | slice) -> Hypothesis | Sequence[Hypothesis]:
        if isinstance(k, slice):
            return [self[i] for i in range(len(self))[k]]
        return Hypothesis(self.segment, Pose(self.rotation[k], self.origin[k]), self.point[k], float(self.rms[k]))


def segment_hypotheses(segment: int, geometry: SegmentGeometry, points: Array, distance: Array) -> Sequence[Hypothesis]:
    """Distinct hypotheses with at least three inliers, best first.

    Args:
        segment: The segment's index (carried into each hypothesis).
        geometry: Its constellation and tolerances.
        points: ``(P, 3)`` the frame's points; ``distance`` their ``(P, P)`` distances.
    """
    u, tau = geometry.coordinates, geometry.tolerance
    model_distance = np.linalg.norm(u[:, None] - u[None], axis=2)
    triples: list[Index] = []
    for a, b, c in combinations(range(len(u)), 3):
        near = [np.abs(distance - model_distance[p, q]) <= np.hypot(tau[p], tau[q]) for p, q in ((a, b), (a, c), (b, c))]
        i, j = np.nonzero(near[0])
        k_mask = near[1][i] & near[2][j]
        pair, k = np.nonzero(k_mask)
        found = np.column_stack([np.broadcast_to([a, b, c], (len(k), 3)), i[pair], j[pair], k])
        triples.append(found[(found[:, 3] != found[:, 5]) & (found[:, 4] != found[:, 5])])
    base = np.concatenate(triples).astype(np.int64) if triples else np.zeros((0, 6), np.int64)
    if not len(base):
        return []
    rotation, c_s, c_t = rigid_transform(u[base[:, :3]], points[base[:, 3:]], np.ones((len(base), 3)))
    placed = np.einsum("hij,pj->hpi", rotation, u) - np.einsum("hij,hj->hi", rotation, c_s)[:, None] + c_t[:, None]
    return _refined(segment, u, tau, placed, points)


def _refined(segment: int, u: Array, tau: Array, placed: Array, points: Array) -> Sequence[Hypothesis]:
    """Inliers of each placed constellation, refitted on them; duplicates dropped, best first.

    Vectorised over the hypotheses (a frame's segments have hundreds each): the nearest point
    of every placed marker by one k-d tree query, every refit at once, and no Python object
    per hypothesis (``Hypotheses``).
    """
    gap, nearest = cKDTree(points).query(placed.reshape(-1, 3))
    gap, nearest = gap.reshape(placed.shape[:2]), nearest.reshape(placed.shape[:2])
    inlier = gap <= tau
    keep = inlier.sum(axis=1) >= 3
    nearest, inlier = nearest[keep], inlier[keep]
    if not len(nearest):
        return []
    taken = np.where(inlier, nearest, -1)
    _, first = np.unique(taken, axis=0, return_index=True)
    taken, inlier = taken[first], inlier[first]
    source = np.broadcast_to(u, (len(taken),) + u.shape)
    rotation, c_s, c_t = rigid_transform(source, points[np.maximum(taken, 0)], inlier.astype(float))
    origin = c_t - np.einsum("hij,hj->hi", rotation, c_s)
    residual = np.linalg.norm(np.einsum("hij,pj->hpi", rotation, u) + origin[:, None] - points[np.maximum(taken, 0)], axis=2)
    ok = inlier & (residual <= tau)
    count = ok.sum(axis=1)
    claimed = np.sort(np.where(ok, taken, -1 - np.arange(taken.shape[1])), axis=1)  # -1-p: never equal
    distinct = (np.diff(claimed, axis=1) != 0).all(axis=1)  # no point taken twice
    rms = np.sqrt((np.where(ok, residual, 0.0) ** 2).sum(axis=1) / np.maximum(count, 1))
    good = np.flatnonzero((count >= 3) & distinct)
    good = good[np.lexsort((rms[good], -count[good]))]
    return Hypotheses(segment, rotation[good], origin[good], np.where(ok, taken, -1)[good], rms[good])
