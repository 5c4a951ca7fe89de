"""Each segment's pose in every frame from the markers labeled there, and where it puts the rest.

A segment with three or more labeled markers is posed by Kabsch from its model coordinates
u_p to the labeled positions x_p:

    (R, d) = argmin sum_p |R u_p + d - x_p|^2.

A segment with fewer is posed through the joint chain: each joint to a posed segment t adds
the correspondence c_s -> R_t c_t + d_t (the centre as the posed side sees it), so two
labeled markers and one joint, or one marker and two joints, pose it; the passes repeat, so
a chain is followed outwards. Correspondences that lie nearly on one line leave a rotation
about that line free and pose nothing. With ``within`` a pose whose fit leaves some
correspondence farther than ``within`` times its tolerance (tau_p for a marker, the joint's
for a centre) is refused: the segment does not move rigidly there (a label is wrong, or the
model's segment bends), and what it would place is not to be trusted. R u_p + d is where the model puts marker p: its
prediction and its fill while it is occluded, and what its labeled position is checked against.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import MIN_SPAN_MM, rigid_transform, span_across_line
from formulations.subject.geometry import JointGeometry, ModelGeometry, SegmentGeometry

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
Index = NDArray[np.intp]
RIGID_WITHIN = 2.0  # a fit within twice every tolerance is a segment moving as the model says


@dataclass(frozen=True)
class SegmentPoses:
    """``rotation`` ``(F, S, 3, 3)`` and ``origin`` ``(F, S, 3)``: segment s in frame f puts u at
    R u + d; ``posed`` ``(F, S)`` says where a pose was found."""

    rotation: Array
    origin: Array
    posed: Mask

    def place(self, geometry: ModelGeometry) -> Array:
        """``(F, N, 3)`` where each marker's segment puts it; NaN unposed, and for singles."""
        placed = np.full((len(self.posed), len(geometry.names), 3), np.nan)
        for s, segment in enumerate(geometry.segments):
            at = np.einsum("fij,pj->fpi", self.rotation[:, s], segment.coordinates) + self.origin[:, s, None]
            placed[:, segment.markers] = np.where(self.posed[:, s, None, None], at, np.nan)
        return placed


def segment_poses(geometry: ModelGeometry, positions: Array, within: float = np.inf) -> SegmentPoses:
    """Poses from ``positions`` ``(F, N, 3)`` in the model's marker order, NaN where not labeled."""
    poses, count = marker_poses(geometry, positions, within), len(geometry.segments)
    chains = [_Chain.of(geometry, s, positions) for s in range(count)]
    # A try that poses nothing changes nothing, so it fails again until a jointed segment
    # is posed somewhere new: skipping it meanwhile leaves every pass as it was, faster.
    stale: set[int] = set()
    for _ in range(count):
        for s in range(count):
            if s in stale:
                continue
            stale.add(s)  # posed or not, its remaining frames lack what they lacked
            if _pose_by_joints(chains[s], poses, s, positions, within):
                stale -= {t for _, t, _ in chains[s].ends}
                break
        else:
            break
    return poses


@dataclass(frozen=True)
class _Chain:
    """Segment s's joints, each seen from s as (its centre in s, the other segment, the centre
    in that one), and ``(F, P)`` which of its markers are labeled: built once per call."""

    segment: SegmentGeometry
    joints: list[JointGeometry]
    ends: list[tuple[Array, int, Array]]
    labeled: Mask

    @classmethod
    def of(cls, geometry: ModelGeometry, s: int, positions: Array) -> _Chain:
        joints = [j for j in geometry.joints if s in (j.a, j.b)]
        ends = [(j.centre_a, j.b, j.centre_b) if j.a == s else (j.centre_b, j.a, j.centre_a) for j in joints]
        segment = geometry.segments[s]
        return cls(segment, joints, ends, np.asarray(np.isfinite(positions[:, segment.markers]).all(axis=2), dtype=bool))


def marker_poses(geometry: ModelGeometry, positions: Array, within: float = np.inf) -> SegmentPoses:
    """Poses of the segments with three or more labeled markers only (no joint chain).

    Every segment and frame in one batch (markers padded with weight 0): called on single
    template frames at every window, per-segment calls cost more than the fits.
    """
    frames, count = len(positions), len(geometry.segments)
    poses = SegmentPoses(np.tile(np.eye(3), (frames, count, 1, 1)), np.zeros((frames, count, 3)),
                         np.zeros((frames, count), bool))
    width = max((len(segment.markers) for segment in geometry.segments), default=0)
    source, target = np.zeros((count, width, 3)), np.zeros((frames, count, width, 3))
    weight, limit = np.zeros((frames, count, width), bool), np.full((count, width), np.inf)
    for s, segment in enumerate(geometry.segments):
        k = len(segment.markers)
        source[s, :k], limit[s, :k] = segment.coordinates, within * segment.tolerance
        target[:, s, :k] = positions[:, segment.markers]
        weight[:, s, :k] = np.isfinite(positions[:, segment.markers]).all(axis=2)
    frame, segment_index = np.nonzero(weight.sum(axis=2) >= 3)
    _fit(poses, frame, segment_index, source[segment_index], target[frame, segment_index],
         weight[frame, segment_index], limit[segment_index])
    return poses


def _pose_by_joints(chain: _Chain, poses: SegmentPoses, s: int, positions: Array, within: float) -> bool:
    """Pose segment ``s`` where it has no pose yet from its labeled markers and posed neighbours' joints."""
    ends, segment = chain.ends, chain.segment
    if not ends:
        return False
    ended = np.stack([poses.posed[:, t] for _, t, _ in ends], axis=1)
    frame = np.flatnonzero(~poses.posed[:, s] & (chain.labeled.sum(axis=1) + ended.sum(axis=1) >= 3))
    if not len(frame):
        return False  # no frame left with three correspondences (most calls)
    local = np.concatenate([segment.coordinates, np.stack([own for own, _, _ in ends])])
    seen = [np.einsum("fij,j->fi", poses.rotation[frame, t], c) + poses.origin[frame, t] for _, t, c in ends]
    target = np.concatenate([positions[frame][:, segment.markers], np.stack(seen, axis=1)], axis=1)
    weight = np.concatenate([chain.labeled[frame], ended[frame]], axis=1)
    limit = within * np.concatenate([segment.tolerance, [j.tolerance for j in chain.joints]])
    return _fit(poses, frame, np.full(len(frame), s), np.broadcast_to(local, target.shape), target, weight,
                np.broadcast_to(limit, weight.shape))


def _fit(poses: SegmentPoses, frame: Index, segment: Index, source: Array, target: Array, weight: Mask, limit: Array) -> bool:
    """Kabsch pose of each row's segment in its frame, ``(R, K)`` correspondences of which
    ``weight`` are used (three or more), kept where they span more than a line and each lies
    within ``limit`` mm of the fit; in place. Whether any row was posed."""
    w = weight.astype(float)
    a, b = source, np.where(weight[..., None], target, 0.0)
    keep = span_across_line(a, w) >= MIN_SPAN_MM
    if not keep.any():
        return False
    frame, segment, a, b, w, limit = frame[keep], segment[keep], a[keep], b[keep], w[keep], limit[keep]
    rotation, c_s, c_t = rigid_transform(a, b, w)
    origin = c_t - np.einsum("fij,fj->fi", rotation, c_s)
    residual = np.linalg.norm(np.einsum("fij,fkj->fki", rotation, a) + origin[:, None] - b, axis=2)
    fits = ~((residual > limit) & (w > 0)).any(axis=1)
    frame, segment = frame[fits], segment[fits]
    poses.rotation[frame, segment], poses.origin[frame, segment] = rotation[fits], origin[fits]
    poses.posed[frame, segment] = True
    return bool(fits.any())
