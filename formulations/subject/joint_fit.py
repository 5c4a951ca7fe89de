"""A ball joint between two segments, in closed form (Ringer & Lasenby 2004, Sec. 4; Gamage et al.)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.subject.segment_fit import SegmentFit

Array = NDArray[np.float64]
RCOND = 1e-3  # directions the motion barely excites (a near-hinge) stay at the prior, not at noise


@dataclass(frozen=True)
class JointFit:
    """The joint centre of segments a and b.

    Attributes:
        centre_a, centre_b: ``(3,)`` c_a, c_b: the centre in each segment's frame.
        trajectory: ``(K, 3)`` t(k), NaN where either segment has no pose.
        error: E of eq. (5) over the markers of both segments.
        rms: sqrt(E / number of terms), mm.
    """

    centre_a: Array
    centre_b: Array
    trajectory: Array
    error: float
    rms: float


def fit_joint(a: SegmentFit, b: SegmentFit, positions: Array) -> JointFit:
    """Eq. (4) R_l(k) e_l^p + t(k) = z_l^p(k) for l in {a, b}, with e_l^p = u_l^p - c_l.

    With the segment poses (R_l, d_l) fixed, the marker equations give t(k) = R_l(k) c_l + d_l(k)
    for both l; eliminating t gives, per frame, the linear equation
    [R_a(k)  -R_b(k)] [c_a; c_b] = d_b(k) - d_a(k), solved by least squares over all frames
    (relative to the prior c0: the midpoint of the two origins, in each frame).
    Then t(k) = mean over the seen markers of z - R_l(k) e_l (the least-squares t for fixed R, e),
    and E = sum_k sum_l sum_p |R_l(k) e_l^p + t(k) - z_l^p(k)|^2.
    """
    lhs, rhs = joint_system(a, b)
    both = a.valid & b.valid
    ra, rb = a.rotation[both], b.rotation[both]
    da, db = a.origin[both], b.origin[both]
    mid = (da + db) / 2
    prior = np.concatenate([
        np.einsum("kji,kj->i", ra, mid - da) / len(ra), np.einsum("kji,kj->i", rb, mid - db) / len(rb)
    ])
    step = np.linalg.lstsq(lhs, rhs - lhs @ prior, rcond=RCOND)[0]
    centre = prior + step
    ca, cb = centre[:3], centre[3:]
    trajectory, error, terms = centre_trajectory(a, b, ca, cb, positions)
    return JointFit(ca, cb, trajectory, error, float(np.sqrt(error / max(terms, 1))))


def joint_system(a: SegmentFit, b: SegmentFit) -> tuple[Array, Array]:
    """``(3K, 6)`` [R_a(k)  -R_b(k)] and ``(3K,)`` d_b(k) - d_a(k) over the K frames posing both.

    Raises:
        ValueError: fewer than 3 such frames.
    """
    both = a.valid & b.valid
    if both.sum() < 3:
        raise ValueError("the two segments share fewer than 3 frames")
    lhs = np.concatenate([a.rotation[both], -b.rotation[both]], axis=2).reshape(-1, 6)
    return lhs, (b.origin[both] - a.origin[both]).reshape(-1)


def centre_trajectory(
    a: SegmentFit, b: SegmentFit, ca: Array, cb: Array, positions: Array
) -> tuple[Array, float, int]:
    """t(k) and E of eq. (5) given R, e; frames where either segment has no pose are NaN."""
    both = a.valid & b.valid
    guesses = []
    for seg, centre in ((a, ca), (b, cb)):
        offsets = seg.coordinates - centre  # e_l^p
        z = positions[:, seg.markers]
        guesses.append(z - np.einsum("kij,pj->kpi", seg.rotation, offsets))  # z - R e
    stacked = np.concatenate(guesses, axis=1)
    seen = np.isfinite(stacked).all(axis=2) & both[:, None]
    values = np.where(seen[:, :, None], stacked, 0.0)
    trajectory = values.sum(axis=1) / np.maximum(seen.sum(axis=1), 1)[:, None]
    trajectory[~both] = np.nan
    residual = np.where(seen[:, :, None], values - trajectory[:, None], 0.0)
    return trajectory, float(np.sum(residual**2)), int(seen.sum())
