"""The best reading of a segment the model does not find, among the points nothing else explains.

When identification (``identify``) gives a segment no pose, its constellation may disagree
with the take by more than its tolerance tau_p (a marker placed elsewhere than in the static
trial). Among the free points of a frame (points no named marker took), each assignment of
its markers is read with no tolerance on distances, and the one with the smallest RMS Kabsch
residual

    e = sqrt(mean_p |R u_p + d - x_p|^2)

is returned, where p runs over the reading's correspondences:

- S >= 3 markers: each ordered triple of free points (i, j, k) for markers (0, 1, 2) gives a
  pose, and the other markers take the nearest free point. A reading must agree with every
  posed neighbour on their joint centre within the joint's tolerance (``tree_choice``'s test):
  the joints are what keep a constellation with no distance tolerance off unrelated points.
- two markers with a joint to a posed segment: each ordered pair of free points (i, j) and
  the joint centre x give the pose (c_s, u_0, u_1) -> (x, x_i, x_j), as in ``joint_place``;
  that centre is a correspondence, weighed in e, not a test (it is what is being relearned).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import rigid_transform
from formulations.subject.constellation import Pose
from formulations.subject.geometry import ModelGeometry

Array = NDArray[np.float64]
Index = NDArray[np.int64]


@dataclass(frozen=True)
class LooseReading:
    """``pose`` of the segment, ``point`` ``(S,)`` each marker's point, the correspondences'
    model side ``source`` and world side ``target`` ``(C, 3)`` (markers, then a joint centre),
    and the RMS residual (mm)."""

    pose: Pose
    point: Index
    source: Array
    target: Array
    rms: float


def loose_read(geometry: ModelGeometry, s: int, points: Array, free: NDArray[np.bool_],
               poses: dict[int, Pose]) -> LooseReading | None:
    """Segment ``s`` read from the ``free`` ones of ``points`` ``(P, 3)``, given the other segments'
    ``poses``; None when no reading has a marker on every point it needs or agrees with the joints."""
    u = geometry.segments[s].coordinates
    candidates = np.flatnonzero(free)
    joints = [(j.centre_a, j.centre_b, poses[j.b].place(j.centre_b), j.tolerance) if j.a == s else
              (j.centre_b, j.centre_a, poses[j.a].place(j.centre_a), j.tolerance)
              for j in geometry.joints if (j.a == s and j.b in poses) or (j.b == s and j.a in poses)]
    if len(u) < 2 or not joints or len(candidates) < min(len(u), 3):
        return None
    if len(u) == 2:
        own, _, centre, _ = joints[0]
        source = np.stack([u[0], u[1], own])
        index = np.array(list(permutations(candidates, 2)), dtype=np.int64)
        target = np.concatenate([points[index], np.broadcast_to(centre, (len(index), 1, 3))], axis=1)
    else:
        source = u[:3]
        index = np.array(list(permutations(candidates, 3)), dtype=np.int64)
        target = points[index]
    rotation, c_s, c_t = rigid_transform(np.broadcast_to(source, target.shape), target, np.ones(target.shape[:2]))
    origin = c_t - np.einsum("hij,hj->hi", rotation, c_s)
    placed = np.einsum("hij,pj->hpi", rotation, u) + origin[:, None]
    if len(u) > 3:  # the rest take their nearest free point; a reading uses each point once
        rest = np.linalg.norm(placed[:, 3:, None] - points[candidates][None, None], axis=3).argmin(axis=2)
        index = np.concatenate([index, candidates[rest]], axis=1)
        target, source = points[index], u
    residual = np.linalg.norm(np.einsum("hij,pj->hpi", rotation, source) + origin[:, None] - target, axis=2)
    ok = (np.diff(np.sort(index, axis=1), axis=1) != 0).all(axis=1)  # each point used once
    for own, _, centre, tolerance in joints[1:] if len(u) == 2 else joints:
        ok &= np.linalg.norm(np.einsum("hij,j->hi", rotation, own) + origin - centre, axis=1) <= tolerance
    if not ok.any():
        return None
    rms = np.sqrt(np.mean(residual**2, axis=1))
    best = int(np.flatnonzero(ok)[rms[ok].argmin()])
    return LooseReading(Pose(rotation[best], origin[best]), index[best][: len(u)], source, target[best],
                        float(rms[best]))
