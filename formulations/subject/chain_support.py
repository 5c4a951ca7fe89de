"""What a segment's reading lets its jointed, unseen-by-constellation neighbours explain.

A segment with fewer than three visible markers has no hypothesis of its own (a pair never
has one); ``joint_place`` places it about its joint once a neighbour is posed. Two readings
of the neighbour that fit their own markers about as well (a foot read a quarter turn off,
where the model's toe marker sits away from where this take carries it) put the joint
centre in different places, and only the right one leaves the pair's markers on their
spheres about it. So each hypothesis h of segment s is credited with the markers of every
hypothesis-less segment t jointed to s that ``place_by_joint`` poses about h's centre,

    support(h) = sum_t |{p in t : placed about R_h c_s + d_h, from points h does not take}|,

counted only when t gets a pose (two markers at least): a single marker on a single sphere
is too weak to weigh against a hypothesis's own inliers.

Support only reorders readings of the same points that explain as many of the segment's
own markers: h is credited only when it has as many inliers as the segment's best reading
by its own markers (``segment_hypotheses`` ranks it first) and shares at least two points
with it, and the pair's points must be ones no segment's best reading takes. In a dense
cloud (CMU 03_rolling: 68 markers, many on pairs) some pair fits about almost any centre;
crediting readings elsewhere moved a right forearm onto the left one, whose hand pair was
in view, and crediting a reading with one inlier fewer turned a pelvis over.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from formulations.subject.constellation import Hypothesis
from formulations.subject.geometry import ModelGeometry
from formulations.subject.joint_place import place_by_joint

Array = NDArray[np.float64]


def chain_support(geometry: ModelGeometry, by_segment: Sequence[Sequence[Hypothesis]], points: Array) -> list[Array]:
    """Per segment, ``(|H_s|,)`` markers of hypothesis-less jointed segments each hypothesis places."""
    support = [np.zeros(len(h)) for h in by_segment]
    unclaimed = np.ones(len(points), bool)  # points no segment's best reading takes
    for hypotheses in by_segment:
        if hypotheses:
            unclaimed[list(_points(hypotheses[0]))] = False
    for joint in geometry.joints:
        for s, t, c_s, c_t in ((joint.a, joint.b, joint.centre_a, joint.centre_b),
                               (joint.b, joint.a, joint.centre_b, joint.centre_a)):
            if by_segment[t] or not by_segment[s]:
                continue
            first = by_segment[s][0]
            best = _points(first)
            for k, h in enumerate(by_segment[s]):
                if h.inliers < first.inliers:
                    break  # best first (``segment_hypotheses``): no later reading has more inliers
                if len(_points(h) & best) < 2:
                    continue
                free = unclaimed.copy()
                free[h.point[h.point >= 0]] = False
                pose, taken = place_by_joint(geometry.segments[t], c_t, h.pose.place(c_s), points, free)
                if pose is not None:
                    support[s][k] += int((taken >= 0).sum())
    return support


def _points(hypothesis: Hypothesis) -> set[int]:
    return {int(p) for p in hypothesis.point if p >= 0}
