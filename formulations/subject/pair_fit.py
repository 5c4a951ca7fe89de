"""Two-marker groups made segments by the joint they turn about.

Steps 1-6 of Ringer & Lasenby (2004) also find rigid pairs: on the CMU 41-marker set the
thigh (THI, KNE) and the shank (SHN, ANK) carry two markers each. Two markers fix no
rotation, so Sec. 4 cannot pose them, and left as single markers their distances to the
nearest segments vary too much to name them. A pair that turns about a point c fixed in a
posed segment S keeps both its distances to c: in S's frame, y_m(k) = R_S(k)^T (z_m(k) - d_S(k))
lies on a sphere about c for both markers m. Subtracting each marker's mean of
|y|^2 = 2 y.c + r_m^2 - |c|^2 leaves the linear equations, over frames k and markers m,

    2 (y_m(k) - mean_k y_m) . c = |y_m(k)|^2 - mean_k |y_m|^2,

solved by least squares from a prior c_0 (the pair's centroid in S's frame) with small
singular values cut: about a hinge every point of the axis is such a centre, and the one
nearest the pair is taken. The fit's rms is that of |y_m(k) - c| about its mean. The pair
with its centre c(k) = R_S(k) c + d_S(k) is then a rigid triangle, posed every frame like
any segment (``fit_segment``), and may itself carry the next pair down the limb. The centre
is not kept: it is a fixed point of both frames, and ``build_skeleton`` fits the joint again.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from formulations.subject.distances import mean_distance
from formulations.subject.segment_fit import SegmentFit, fit_segment

Array = NDArray[np.float64]
RCOND = 1e-2  # a direction the motion barely excites (a hinge's axis) stays at the prior


@dataclass(frozen=True)
class PivotFit:
    """The centre ``(3,)`` in the parent's frame that both markers of a pair keep their distances to."""

    parent: int
    centre: Array
    rms: float


def attach_pairs(
    pairs: list[list[int]], segments: list[SegmentFit], positions: Array, joint_rms: float, min_frames: int,
    nearest: int = 4,
) -> list[SegmentFit]:
    """``segments`` followed by every pair that turns about a posed segment within ``joint_rms``.

    Pairs are attached best first, repeatedly, so a pair may hang from a pair attached before
    it. A pair is found in a frame only through its pivot, within a tolerance of three times
    its markers' spread: one that spreads more than twice the typical marker of this take's
    segments (two markers across a joint, skin that slides) would take its neighbours'
    points, so it stays two single markers.
    """
    segments = list(segments)
    typical = float(np.median(np.concatenate([s.spread for s in segments])))
    left = [list(p) for p in pairs]
    while left:
        fits = [(_best_pivot(pair, segments, positions, min_frames, nearest), pair) for pair in left]
        found = [(f, p) for f, p in fits if f is not None and f.rms <= joint_rms]
        if not found:
            break
        pivot, pair = min(found, key=lambda fit: fit[0].rms)
        left.remove(pair)
        triangle = _triangle(pair, segments[pivot.parent], pivot.centre, positions)
        if triangle.spread.max() <= 2 * typical:
            segments.append(triangle)
    return segments


def _best_pivot(
    pair: list[int], segments: list[SegmentFit], positions: Array, min_frames: int, nearest: int,
) -> PivotFit | None:
    """The pivot in the nearest posed segments (by mean distance of origins) with the smallest rms."""
    both: NDArray[np.bool_] = np.asarray(np.isfinite(positions[:, pair]).all(axis=(1, 2)), dtype=bool)
    centroid = np.where(both[:, None], np.nan_to_num(positions[:, pair]).mean(axis=1), np.nan)
    order = np.argsort([mean_distance(centroid, s.origin) for s in segments])[:nearest]
    pivots = [_pivot(int(s), segments[int(s)], positions[:, pair], min_frames) for s in order]
    found = [p for p in pivots if p is not None]
    return min(found, key=lambda p: p.rms) if found else None


def _pivot(parent: int, segment: SegmentFit, pair: Array, min_frames: int) -> PivotFit | None:
    """The least-squares centre of ``pair`` ``(K, 2, 3)`` in ``segment``'s frame (module doc)."""
    both = segment.valid & np.isfinite(pair).all(axis=(1, 2))
    if both.sum() < min_frames:
        return None
    rotation, origin = segment.rotation[both], segment.origin[both]
    local = np.einsum("kji,kmj->kmi", rotation, pair[both] - origin[:, None])  # (K, 2, 3)
    centred = local - local.mean(axis=0)
    square = np.einsum("kmi,kmi->km", local, local)
    lhs = 2 * centred.transpose(1, 0, 2).reshape(-1, 3)
    rhs = (square - square.mean(axis=0)).T.reshape(-1)
    prior = local.mean(axis=(0, 1))
    centre = prior + np.linalg.lstsq(lhs, rhs - lhs @ prior, rcond=RCOND)[0]
    reach = np.linalg.norm(local - centre, axis=2)
    rms = float(np.sqrt(np.mean((reach - reach.mean(axis=0)) ** 2)))
    return PivotFit(parent, centre, rms)


def _triangle(pair: list[int], parent: SegmentFit, centre: Array, positions: Array) -> SegmentFit:
    """The pair posed every frame as a rigid triangle with its pivot; coordinates centred on the pair.

    The pair's centroid is where identification puts a segment's origin; the pivot itself is
    a fixed point of both frames, so ``build_skeleton`` finds it again as the joint.
    """
    pivot = np.einsum("kij,j->ki", parent.rotation, centre) + parent.origin
    triangle = np.concatenate([positions[:, pair], pivot[:, None]], axis=1)
    fit = fit_segment(triangle, [0, 1, 2])
    shift = fit.coordinates[:2].mean(axis=0)
    return replace(
        fit, markers=list(pair), coordinates=fit.coordinates[:2] - shift,
        origin=fit.origin + np.einsum("kij,j->ki", fit.rotation, shift), spread=fit.spread[:2],
    )
