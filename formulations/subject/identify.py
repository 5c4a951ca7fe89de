"""Name the points of one unlabeled frame from a subject model (no labeled frame, no motion).

1. Each segment's constellation is fitted to the cloud (``constellation``): pose hypotheses
   from pairwise-distance signatures, Kabsch, inliers within tau_p (``geometry``).
2. One hypothesis (or none) per segment, chosen jointly over the skeleton (``tree_choice``):
   jointed segments must agree on their joint centre and share no point. This is what tells
   a left limb from a right one whose constellation is its mirror image. Of two chosen
   hypotheses that are not jointed but share a point, the one with more inliers stays.
3. Segments with fewer than three visible markers are placed about a joint to a placed
   segment (``joint_place``), repeatedly, so a chain is followed outwards.
4. Single markers are named when exactly one free point lies at their distances from the
   segments they are measured from.
5. The placed markers take points by one assignment (``linear_sum_assignment`` on the
   distance in units of tau_p, a miss costing 1): conflicts between segments resolve
   globally, and a marker farther than tau_p from every point stays unnamed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.distance import cdist

from formulations.markers.guide import assign_within_gates
from formulations.subject.chain_support import chain_support
from formulations.subject.constellation import Hypothesis, Pose, segment_hypotheses
from formulations.subject.geometry import ModelGeometry
from formulations.subject.joint_place import place_by_joint
from formulations.subject.tree_choice import choose_hypotheses

Array = NDArray[np.float64]
Index = NDArray[np.int64]


@dataclass(frozen=True)
class Identification:
    """The model's names on one frame's points.

    Attributes:
        point: ``(N,)`` the point each model marker takes, -1 where it is left unnamed.
        residual: ``(N,)`` mm from where the model puts the marker (for a single, the largest
            deviation from its model distances); NaN where unnamed.
        placed: ``(N, 3)`` where the model puts each marker: its segment's pose applied to its
            coordinates; NaN for markers whose segment has no pose, and for singles.
    """

    point: Index
    residual: Array
    placed: Array

    @property
    def named(self) -> NDArray[np.bool_]:
        named: NDArray[np.bool_] = self.point >= 0
        return named


def identify(geometry: ModelGeometry, points: Array, known: dict[int, Hypothesis] | None = None) -> Identification:
    """Name ``points`` ``(P, 3)`` (mm) with the markers of ``geometry``; segments in ``known``
    take that reading as their only hypothesis instead of a search (``labeled_reading``)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(geometry.names)
    poses = _compete(geometry, points, known or {}) if len(points) >= 3 else {}
    fixed = np.full(n, -1, dtype=np.int64)
    _follow_joints(geometry, points, poses, fixed)
    placed = np.full((n, 3), np.nan)
    for s, pose in poses.items():
        segment = geometry.segments[s]
        placed[segment.markers] = pose.place(segment.coordinates)
    free_rows = np.where((fixed >= 0)[:, None], np.nan, placed)
    point = _assign(free_rows, geometry.tolerance, points, _taken(fixed, len(points)))
    point = np.where(fixed >= 0, fixed, point)
    _name_singles(geometry, points, placed, point)
    residual = np.full(n, np.nan)
    named = point >= 0
    residual[named] = np.linalg.norm(placed[named] - points[point[named]], axis=1)
    for single in geometry.singles:
        if point[single.marker] >= 0:
            reach = np.linalg.norm(placed_origin(geometry, placed, single.segments) - points[point[single.marker]], axis=1)
            residual[single.marker] = float(np.abs(reach - single.distances).max())
    return Identification(point, residual, placed)


def placed_origin(geometry: ModelGeometry, placed: Array, segments: Index) -> Array:
    """``(len(segments), 3)`` each segment's origin (its markers' centroid: coordinates are centred there)."""
    return np.stack([placed[geometry.segments[s].markers].mean(axis=0) for s in segments])


def _compete(geometry: ModelGeometry, points: Array, known: dict[int, Hypothesis]) -> dict[int, Pose]:
    """Step 2: the jointly best hypotheses (``tree_choice``); of two sharing a point the better one stays."""
    distance = cdist(points, points)
    by_segment = [[known[s]] if s in known else segment_hypotheses(s, segment, points, distance)
                  for s, segment in enumerate(geometry.segments)]
    chosen = choose_hypotheses(geometry, by_segment, len(points), chain_support(geometry, by_segment, points))
    taken = np.zeros(len(points), bool)
    poses: dict[int, Pose] = {}
    for s, h in sorted(chosen.items(), key=lambda item: (-item[1].inliers, item[1].rms)):
        mine = h.point[h.point >= 0]
        if not taken[mine].any():
            poses[s] = h.pose
            taken[mine] = True
    return poses


def _follow_joints(geometry: ModelGeometry, points: Array, poses: dict[int, Pose], fixed: Index) -> None:
    """Step 3, in place: segments without a pose placed about joints to posed ones until nothing changes.

    Points within tau of a marker of a posed segment are that segment's; the rest are free.
    """
    claimed = np.zeros(len(points), bool)
    for pose_s, segment_s in ((p, geometry.segments[s]) for s, p in poses.items()):
        placed = pose_s.place(segment_s.coordinates)
        claimed |= _near(points, placed, segment_s.tolerance)
    tried: set[int] = set()
    # Segments with more markers first: a two-marker segment rests on its joint alone, and
    # the points it claims would decide between the readings of a fuller segment.
    joints = sorted(geometry.joints, key=lambda j: -min(len(geometry.segments[s].markers) for s in (j.a, j.b)))
    progress = True
    while progress:
        progress = False
        for joint in joints:
            rest = joint.rest
            for known, unknown, c_known, c_unknown, at_rest in (
                (joint.a, joint.b, joint.centre_a, joint.centre_b, rest),
                (joint.b, joint.a, joint.centre_b, joint.centre_a, None if rest is None else rest.T),
            ):
                if known not in poses or unknown in poses or unknown in tried:
                    continue
                tried.add(unknown)
                segment = geometry.segments[unknown]
                parent = poses[known]
                usual = None if at_rest is None else parent.rotation @ at_rest
                pose, taken = place_by_joint(
                    segment, c_unknown, parent.place(c_known), points, ~claimed, usual, geometry.sigmas * joint.rms,
                )
                fixed[segment.markers[taken >= 0]] = taken[taken >= 0]
                claimed[taken[taken >= 0]] = True
                if pose is not None:
                    poses[unknown] = pose
                    progress = True


def _name_singles(geometry: ModelGeometry, points: Array, placed: Array, point: Index) -> None:
    """Step 4, in place: a single is named when one free point alone fits its distances."""
    free = ~_taken(point, len(points))
    for single in geometry.singles:
        if not all(np.isfinite(placed[geometry.segments[s].markers]).all() for s in single.segments):
            continue
        origins = placed_origin(geometry, placed, single.segments)
        reach = np.linalg.norm(points[:, None] - origins[None], axis=2)  # (P, segments)
        fits = free & (np.abs(reach - single.distances) <= single.tolerance).all(axis=1)
        if fits.sum() == 1:
            point[single.marker] = int(np.flatnonzero(fits)[0])
            free[point[single.marker]] = False


def _assign(placed: Array, tolerance: Array, points: Array, unavailable: NDArray[np.bool_]) -> Index:
    """Step 5: placed markers to available points, distance in units of tau, a miss costing 1."""
    point = np.full(len(placed), -1, dtype=np.int64)
    rows = np.flatnonzero(np.isfinite(placed).all(axis=1))
    columns = np.flatnonzero(~unavailable)
    if not len(rows) or not len(columns):
        return point
    scaled = cdist(placed[rows], points[columns]) / tolerance[rows, None]
    chosen = assign_within_gates(scaled, np.ones(len(rows)), 1.0)
    hit = chosen >= 0
    point[rows[hit]] = columns[chosen[hit]]
    return point


def _near(points: Array, placed: Array, tolerance: Array) -> NDArray[np.bool_]:
    """``(P,)`` points within tau of some placed marker."""
    if not len(points):
        return np.zeros(0, bool)
    near: NDArray[np.bool_] = (cdist(points, placed) <= tolerance[None]).any(axis=1)
    return near


def _taken(point: Index, count: int) -> NDArray[np.bool_]:
    taken = np.zeros(count, bool)
    taken[point[point >= 0]] = True
    return taken
