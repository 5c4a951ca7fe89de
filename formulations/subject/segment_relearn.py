"""A segment's constellation taken from the take, its joint centres carried along.

A reading of segment s with pose (R, d) names points x_p; in the segment's frame they are

    u'_p = R^T (x_p - d),

the take's constellation in the frame the model's joint centres are given in (a two-marker
segment read about a joint centre x takes that centre as R^T (x - d) likewise). A template
defines a centre as a mean of markers, so it keeps its place among the segment's markers:
each centre c of s moves by the affine map that takes the reading's model-side
correspondences A (markers, and a joint centre for a two-marker segment) onto their learned
positions A' and the constellation's normal n onto the new one's n' (unit; a plane's
correspondences leave the out-of-plane direction free, and a rigid body does not stretch it):

    c' = M (c - mean A) + mean A',   M = argmin |[A - mean A; n] M^T - [A' - mean A'; n']|.

A joint to a segment t posed in the same frame is then made to agree there: its centre as
s puts it and as t puts it, g = (R c'_s + d) - (R_t c_t + d_t) apart, each move half of g
(the least-norm correction of ``joint_fit``'s equation in one frame): a template's centre is a
mean of markers of both segments, so the change is not one side's alone.

The segment's spreads stay the model's: they describe noise and skin, not where a marker sits.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.subject.constellation import Pose
from formulations.subject.loose_read import LooseReading
from formulations.subject.model import SubjectModel

Array = NDArray[np.float64]


def relearned(model: SubjectModel, s: int, reading: LooseReading, poses: dict[int, Pose]) -> SubjectModel:
    """``model`` with segment ``s`` (index into ``model.segments``) as ``reading`` sees it;
    ``poses`` are the other segments' in the reading's frame, by index."""
    segment = model.segments[s]
    after = (reading.target - reading.pose.origin) @ reading.pose.rotation
    learned = after[: len(segment.markers)]
    move = _affine(reading.source, after)
    index = {m.name: k for k, m in enumerate(model.segments)}
    joints = []
    for joint in model.joints:
        centres = [np.asarray(c, float) for c in joint.centres]
        for side in (0, 1):
            if joint.segments[side] == segment.name:
                centres[side] = move(centres[side])
                other = index[joint.segments[1 - side]]
                if other in poses:
                    _meet(centres, side, reading.pose, poses[other])
        joints.append(replace(joint, centres=(centres[0].round(3).tolist(), centres[1].round(3).tolist())))
    segments = list(model.segments)
    segments[s] = replace(segment, coordinates=learned.round(3).tolist())
    return replace(model, segments=segments, joints=joints)


def _affine(before: Array, after: Array) -> Callable[[Array], Array]:
    """The map c -> M (c - mean A) + mean A' of the module docstring."""
    a, b = before - before.mean(axis=0), after - after.mean(axis=0)
    n_a, n_b = np.linalg.svd(a)[2][-1], np.linalg.svd(b)[2][-1]
    n_b = n_b if n_a @ n_b >= 0 else -n_b
    m_t = np.linalg.lstsq(np.vstack([a, n_a]), np.vstack([b, n_b]), rcond=None)[0]
    return lambda c: np.asarray((c - before.mean(axis=0)) @ m_t + after.mean(axis=0))


def _meet(centres: list[Array], side: int, pose: Pose, other: Pose) -> None:
    """In place: each side's centre moved by half the gap between where the two poses put them."""
    gap = pose.place(centres[side]) - other.place(centres[1 - side])
    centres[side] = centres[side] - pose.rotation.T @ gap / 2
    centres[1 - side] = centres[1 - side] + other.rotation.T @ gap / 2
