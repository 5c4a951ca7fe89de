"""The body that hides markers from cameras (``visibility``): capsules posed per frame.

From a subject model (``segment_capsules``). Each segment is a capsule fixed in the
segment's frame. Its axis is the principal axis of its joint centres (a thigh: the line
from hip to knee), or with fewer than two joints of its markers and joint, spanning the
projections of its markers and joints (the thigh's hip and knee lie beyond its markers).
Its radius is the markers' RMS distance from that axis
less the marker radius m (markers sit on the skin, the capsule is the limb under them), at
least m. In a frame the segment is posed by Kabsch from its markers there (at least three
known), and the capsule goes with it; a segment with fewer known markers is left out.

Without a model (``marker_capsules``). A crude body from the markers alone: each marker
a and each of its rigid neighbours b (``rigid_neighbours``: the nearest markers whose
distance to it hardly varies) give a capsule between the points P_a, P_b pushed inwards
by s from the markers, P_a = X_a - s u_a, where u_a points from the centroid of a and its
rigid neighbours to a (inwards is towards the cluster; a marker at its cluster's centroid
is not pushed), and the radius is s - m. s is half the median distance of a marker to its
nearest neighbour: on a limb ringed by markers the capsules fill the ring. This knows
nothing of limbs without markers, and a flat cluster (a back plate) pushes its capsules
sideways, not inwards: use a subject model where it matters.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.cameras.visibility import Body, segment_distance
from formulations.errors import FormulationError
from formulations.markers.rigid import rigid_transform
from formulations.subject.model import SubjectModel

Array = NDArray[np.float64]
Index = NDArray[np.intp]


@dataclass(frozen=True)
class SegmentCapsules:
    """Capsules fixed in the segments' frames, posed per frame by ``at``.

    Attributes:
        markers: ``(S, K)`` index of each segment's markers in the caller's order, -1 padding.
        coordinates: ``(S, K, 3)`` their coordinates in the segment's frame.
        start, end: ``(S, 3)`` the axis in the segment's frame.
        radius: ``(S,)`` r_s.
    """

    markers: Index
    coordinates: Array
    start: Array
    end: Array
    radius: Array

    def at(self, positions: Array) -> Body:
        """The capsules of the segments with three or more known markers in ``positions`` ``(N, 3)``."""
        target = np.asarray(positions, dtype=float)[np.maximum(self.markers, 0)]
        weight = ((self.markers >= 0) & np.isfinite(target).all(axis=2)).astype(float)
        posed = weight.sum(axis=1) >= 3
        rotation, c_s, c_t = rigid_transform(self.coordinates[posed], np.nan_to_num(target[posed]), weight[posed])

        def place(local: Array) -> Array:
            placed: Array = np.einsum("sij,sj->si", rotation, local[posed] - c_s) + c_t
            return placed

        return Body(start=place(self.start), end=place(self.end), radius=self.radius[posed])


def segment_capsules(model: SubjectModel, names: list[str]) -> SegmentCapsules:
    """The model's segments as capsules (module doc), markers indexed by ``names``.

    Raises:
        FormulationError: a segment marker missing from ``names``.
    """
    index = {name: i for i, name in enumerate(names)}
    missing = [m for s in model.segments for m in s.markers if m not in index]
    if missing:
        raise FormulationError(f"visibility: subject model marker {missing[0]!r} is not among the capture's markers")
    joints: dict[str, list[Array]] = {s.name: [] for s in model.segments}
    for joint in model.joints:
        for name, centre in zip(joint.segments, joint.centres):
            joints[name].append(np.asarray(centre, dtype=np.float64))
    k = max((len(s.markers) for s in model.segments), default=0)
    markers = np.full((len(model.segments), k), -1, dtype=np.intp)
    coordinates = np.zeros((len(model.segments), k, 3))
    start, end, radius = np.zeros((len(model.segments), 3)), np.zeros((len(model.segments), 3)), np.zeros(len(model.segments))
    for s, segment in enumerate(model.segments):
        local = np.asarray(segment.coordinates, dtype=np.float64).reshape(-1, 3)
        markers[s, : len(local)], coordinates[s, : len(local)] = [index[m] for m in segment.markers], local
        start[s], end[s] = _axis(local, joints[segment.name])
        radius[s] = max(_rms_off_axis(local, start[s], end[s]) - model.marker_radius, model.marker_radius)
    return SegmentCapsules(markers=markers, coordinates=coordinates, start=start, end=end, radius=radius)


def marker_capsules(positions: Array, neighbours: Index, marker_radius: float) -> Body:
    """The crude body of the module doc from one frame's markers.

    Args:
        positions: ``(N, 3)`` markers, NaN where unknown (their capsules are left out).
        neighbours: ``(N, K)`` each marker's rigid neighbours (``rigid_neighbours``).
        marker_radius: m, mm.
    """
    x = np.asarray(positions, dtype=float)
    known = np.isfinite(x).all(axis=1)
    spacing = np.linalg.norm(x[:, None] - x[None], axis=2)
    np.fill_diagonal(spacing, np.inf)
    nearest = spacing[np.ix_(known, known)].min(axis=1) if known.sum() > 1 else np.zeros(0)
    if len(nearest) == 0:
        return Body(start=np.zeros((0, 3)), end=np.zeros((0, 3)), radius=np.zeros(0))
    shift = 0.5 * float(np.median(nearest))
    cluster = np.concatenate([x[:, None], x[neighbours]], axis=1)
    with np.errstate(invalid="ignore"):
        outward = x - np.nanmean(cluster, axis=1)
        length = np.linalg.norm(outward, axis=1, keepdims=True)
        unit = np.where(length > 1e-9, outward / np.where(length > 1e-9, length, 1.0), 0.0)
    inner = x - shift * unit
    a = np.repeat(np.arange(len(x)), neighbours.shape[1])
    b = neighbours.ravel()
    keep = known[a] & known[b]
    pairs = np.unique(np.sort(np.column_stack([a[keep], b[keep]]), axis=1), axis=0).reshape(-1, 2)
    return Body(
        start=inner[pairs[:, 0]], end=inner[pairs[:, 1]], radius=np.full(len(pairs), max(shift - marker_radius, 0.0)),
    )


def rigid_neighbours(track: Array, count: int, rigid_sd: float) -> Index:
    """``(N, count)`` for each marker the nearest markers whose distance to it varies by at most
    ``rigid_sd`` (sd over the frames of ``track`` ``(F, N, 3)`` where both are known); where
    fewer are rigid, the least varying fill the row."""
    x = np.asarray(track, dtype=float)
    n = x.shape[1]
    if not 1 <= count < n:
        raise FormulationError(f"visibility: need 1 <= rigid neighbours < {n} markers, got {count}")
    distance = np.linalg.norm(x[:, :, None] - x[:, None], axis=3)
    with warnings.catch_warnings():  # a pair never seen together is NaN here ("Mean of empty slice"), inf below
        warnings.simplefilter("ignore", RuntimeWarning)
        mean, sd = np.nanmean(distance, axis=0), np.nanstd(distance, axis=0)
    mean, sd = np.nan_to_num(mean, nan=np.inf), np.nan_to_num(sd, nan=np.inf)
    score = np.where(sd <= rigid_sd, mean, 1e12 + sd)  # rigid first, nearest first
    np.fill_diagonal(score, np.inf)
    chosen: Index = np.argsort(score, axis=1, kind="stable")[:, :count]
    return chosen


def _axis(markers: Array, joints: list[Array]) -> tuple[Array, Array]:
    """The segment's axis in its frame (module doc), spanning its markers' and joints' projections."""
    points = np.vstack([markers, *joints]) if joints else markers
    along_of = np.stack(joints) if len(joints) >= 2 else points
    centroid = along_of.mean(axis=0)
    direction = np.linalg.svd(along_of - centroid)[2][0] if len(along_of) > 1 else np.zeros(3)
    along = (points - centroid) @ direction
    return centroid + along.min() * direction, centroid + along.max() * direction


def _rms_off_axis(points: Array, start: Array, end: Array) -> float:
    """RMS distance of ``points`` from the segment start-end."""
    x = points[:, None, None, :]
    distance = segment_distance(x, x, start[None, None], end[None, None])[:, 0, 0]
    return float(np.sqrt(np.mean(distance**2)))
