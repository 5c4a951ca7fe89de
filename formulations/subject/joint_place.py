"""A segment with fewer than three visible markers, placed about a joint whose centre is known.

When a neighbouring segment has a pose, the joint centre x = R_t c_t + d_t is known, and
segment s turns about it: marker p lies on the sphere |y - x| = |u_p - c_s|. Two visible
markers (p, q) on their spheres at the right mutual distance, with the centre, are three
correspondences (c_s, u_p, u_q) -> (x, x_i, x_j): a Kabsch pose, which places the rest of
the segment. One visible marker gives no pose; it is named only when a single free point
lies on a single sphere. Either way an ambiguous reading names nothing, with one exception:
when the markers are about as far from the centre as each other, a pair's two readings
differ by a half turn about the triangle's axis of symmetry, and the model's rest
orientation of the joint (``joint_rest``) tells them apart. The reading turned least from
rest is kept when every other is turned at least ``REST_MARGIN`` more: the true reading is
turned by the joint's motion, the exchanged one by that and a half turn (close to 180
degrees), so a quarter turn of margin leaves room for a joint bent 90 degrees from its rest.

The centre comes from the neighbour's pose and is itself off by up to the joint's fit error
(a trunk that is not quite rigid moves the shoulder centre: on CMU 135_02 an upper-arm pair
sat 8 and 14 mm off its spheres for its first 38 frames, and stayed unnamed). When no pair
fits the spheres about the centre as given, they are widened by that error (``slack``).
Tight first: widened from the start, a unique reading became a tie and named nothing
(gait2354's arm pairs, 100 -> 98.6 % from the template).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import rigid_transform
from formulations.subject.constellation import Pose
from formulations.subject.geometry import SegmentGeometry
from formulations.subject.joint_rest import turned_from

Array = NDArray[np.float64]
Index = NDArray[np.int64]
REST_MARGIN = np.pi / 2  # radians (module doc)


def place_by_joint(
    geometry: SegmentGeometry, centre_local: Array, centre: Array, points: Array, free: NDArray[np.bool_],
    usual: Array | None = None, slack: float = 0.0,
) -> tuple[Pose | None, Index]:
    """The segment's pose (None when fewer than two markers fit) and each marker's point (-1: none).

    Args:
        geometry: The segment.
        centre_local: c_s, the joint centre in the segment's frame; ``centre`` x in the world.
        points: ``(P, 3)`` the frame's points; ``free`` ``(P,)`` those no other segment took.
        usual: The rotation the segment has at the joint's rest, its parent as posed (R_a Q of
            ``joint_rest``), or None: then readings that tie name nothing.
        slack: How far (mm) the centre may lie from where it is given; when no pair fits the
            spheres about the centre as given, each is widened by it, in quadrature with the
            marker's own tolerance (module doc).
    """
    none: Index = np.full(len(geometry.coordinates), -1, dtype=np.int64)
    candidates = np.flatnonzero(free)
    if not len(candidates):
        return None, none
    readings, on_sphere = _readings(geometry, centre_local, centre, points, candidates, 0.0)
    if not readings and slack > 0:
        readings, _ = _readings(geometry, centre_local, centre, points, candidates, slack)
    if readings:
        return _decided(readings, usual, none)
    marker, point = np.nonzero(on_sphere)
    if len(marker) == 1:
        none[marker[0]] = candidates[point[0]]
    return None, none


def _readings(
    geometry: SegmentGeometry, centre_local: Array, centre: Array, points: Array, candidates: Index, widen: float,
) -> tuple[list[tuple[int, Pose, Index]], NDArray[np.bool_]]:
    """Every pair reading (markers hit, pose, points), with spheres widened by ``widen`` mm;
    and which candidate lies on which marker's sphere ``(S, C)``."""
    u, tau = geometry.coordinates, geometry.tolerance
    loose = np.hypot(tau, widen)
    reach = np.linalg.norm(u - centre_local, axis=1)  # (S,)
    gap = np.abs(np.linalg.norm(points[candidates] - centre, axis=1)[None] - reach[:, None])  # (S, C)
    on_sphere = gap <= loose[:, None]
    readings = []
    for pose in _pair_poses(u, tau, centre_local, centre, points, candidates, on_sphere):
        distance = np.linalg.norm(pose.place(u)[:, None] - points[candidates][None], axis=2)
        nearest = distance.argmin(axis=1)
        hit = distance[np.arange(len(u)), nearest] <= loose
        if len(set(nearest[hit])) == hit.sum():
            readings.append((int(hit.sum()), pose, np.where(hit, candidates[nearest], -1)))
    return readings, on_sphere


def _decided(readings: list[tuple[int, Pose, Index]], usual: Array | None, none: Index) -> tuple[Pose | None, Index]:
    """The reading with the most markers if it is the only one naming its points, else the
    one nearest rest (``_nearest_rest``), else nothing."""
    most = max(r[0] for r in readings)
    best = [r for r in readings if r[0] == most]
    if len({tuple(r[2]) for r in best}) == 1:
        return best[0][1], best[0][2]
    chosen = None if usual is None else _nearest_rest(best, usual)
    return (chosen[1], chosen[2]) if chosen is not None else (None, none)


def _nearest_rest(readings: list[tuple[int, Pose, Index]], usual: Array) -> tuple[int, Pose, Index] | None:
    """The reading turned least from ``usual`` if every reading naming other points is turned
    at least ``REST_MARGIN`` more (module doc), else None."""
    turned = [turned_from(usual, pose.rotation) for _, pose, _ in readings]
    first = int(np.argmin(turned))
    rivals = [t for t, r in zip(turned, readings) if tuple(r[2]) != tuple(readings[first][2])]
    return readings[first] if min(rivals) - turned[first] >= REST_MARGIN else None


def _pair_poses(
    u: Array, tau: Array, centre_local: Array, centre: Array, points: Array, candidates: Index,
    on_sphere: NDArray[np.bool_],
) -> list[Pose]:
    """A pose for every pair of markers on their spheres at their mutual distance."""
    found: list[tuple[int, int, int, int]] = []
    for p in range(len(u)):
        for q in range(p + 1, len(u)):
            ci, cj = np.flatnonzero(on_sphere[p]), np.flatnonzero(on_sphere[q])
            if not len(ci) or not len(cj):
                continue
            span = np.linalg.norm(points[candidates[ci]][:, None] - points[candidates[cj]][None], axis=2)
            ok = np.abs(span - np.linalg.norm(u[p] - u[q])) <= np.hypot(tau[p], tau[q])
            found.extend(
                (p, q, int(candidates[ci[a]]), int(candidates[cj[b]])) for a, b in zip(*np.nonzero(ok)) if ci[a] != cj[b]
            )
    if not found:
        return []
    source = np.stack([np.stack([centre_local, u[p], u[q]]) for p, q, _, _ in found])
    target = np.stack([np.stack([centre, points[i], points[j]]) for _, _, i, j in found])
    rotation, c_s, c_t = rigid_transform(source, target, np.ones((len(found), 3)))
    return [Pose(r, t - r @ c) for r, c, t in zip(rotation, c_s, c_t)]
