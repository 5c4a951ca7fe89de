"""Segments to joints (Ringer & Lasenby 2004, Sec. 3 on D', Sec. 4 on E) and limb lengths."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.subject.distances import mean_distance
from formulations.subject.joint_fit import JointFit, fit_joint
from formulations.subject.segment_fit import SegmentFit

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Skeleton:
    """Joints as (segment a, segment b, fit), and the pairs refused because they close a loop."""

    joints: list[tuple[int, int, JointFit]]
    inconsistent: list[tuple[int, int]]


def candidate_pairs(segments: list[SegmentFit], neighbours: int) -> list[tuple[int, int]]:
    """Each segment with its ``neighbours`` nearest by D'_{l1,l2}, the mean distance of the origins."""
    n = len(segments)
    near = np.full((n, n), np.inf)
    for i in range(n):
        for j in range(i + 1, n):
            near[i, j] = near[j, i] = mean_distance(segments[i].origin, segments[j].origin)
    pairs = set()
    for i in range(n):
        for j in np.argsort(near[i])[:neighbours]:
            if int(j) != i and np.isfinite(near[i, j]):
                pairs.add((min(i, int(j)), max(i, int(j))))
    return sorted(pairs)


def build_skeleton(segments: list[SegmentFit], positions: Array, joint_rms: float, neighbours: int = 4) -> Skeleton:
    """Joint the candidate pairs in order of their reconstruction error, as steps 1-6 do on D'.

    Each candidate pair gets its joint fit (``fit_joint``); visited by increasing rms
    sqrt(E / terms), a pair becomes a joint when it links two segments not yet connected
    (the association with the smallest E wins) and its rms is at most ``joint_rms`` (a ball
    joint, not two segments that merely stay near); a pair inside one tree is an inconsistency.
    """
    fits = []
    for a, b in candidate_pairs(segments, neighbours):
        try:
            fits.append((a, b, fit_joint(segments[a], segments[b], positions)))
        except ValueError:
            continue  # never seen together: no joint to fit
    root = list(range(len(segments)))

    def find(i: int) -> int:
        while root[i] != i:
            i = root[i]
        return i

    joints, inconsistent = [], []
    for a, b, fit in sorted(fits, key=lambda f: f[2].rms):
        if fit.rms > joint_rms:
            break
        if find(a) == find(b):
            inconsistent.append((a, b))
        else:
            root[find(a)] = find(b)
            joints.append((a, b, fit))
    return Skeleton(joints, inconsistent)


def limb_lengths(skeleton: Skeleton, count: int) -> list[tuple[int, int, int, float]]:
    """(segment, joint i, joint j, length) for each segment between two joints.

    The length is the mean over frames of |t_i(k) - t_j(k)|, the distance of the two joint
    trajectories; where they never exist in one frame (a gappy take: the segments on either
    side never posed together), the distance of the two centres in the segment's own frame,
    which is constant on a rigid segment (a model with an infinite length cannot be read back).
    """
    limbs = []
    for segment in range(count):
        touching = [i for i, (a, b, _) in enumerate(skeleton.joints) if segment in (a, b)]
        for n, i in enumerate(touching):
            for j in touching[n + 1:]:
                length = mean_distance(skeleton.joints[i][2].trajectory, skeleton.joints[j][2].trajectory)
                if not np.isfinite(length):
                    gap = _centre_on(skeleton, i, segment) - _centre_on(skeleton, j, segment)
                    length = float(np.linalg.norm(gap))
                limbs.append((segment, i, j, length))
    return limbs


def _centre_on(skeleton: Skeleton, joint: int, segment: int) -> Array:
    """The joint's centre in ``segment``'s own frame."""
    a, _, fit = skeleton.joints[joint]
    return fit.centre_a if segment == a else fit.centre_b
