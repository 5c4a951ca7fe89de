"""A closed gap filled by the rigid motion of the markers that move with it, from both sides.

Once a take is labeled, each gap of marker n (frames s..e) has a sighting on either side,
at a = s - 1 and b = e + 1. Its donors are the markers whose distance to n varied least
over the frames where both were labeled: spread sd_k, weight w_k = 1 / (sd_k^2 + 1 mm^2).
In frame t, side r in {a, b} carries n by the weighted Kabsch motion of its
``MAX_DONORS`` most rigid donors labeled at both r and t:

    (R, c_r, c_t) = argmin sum_k w_k |R (x_k(r) - c_r) + c_t - x_k(t)|^2,
    y_r(t) = R (x_n(r) - c_r) + c_t,

and the fill is the blend y(t) = (1 - u) y_a(t) + u y_b(t), u = (t - a) / (b - a).

This is the rigid-body fill of commercial labeling tools, with the donors chosen from the
take's own labels and both sides blended: the fill keeps how the markers sit in this take,
and each carry counts most near the sighting it starts from, where it has drifted least. A frame where either side
has fewer than three donors keeps the fill it had (the marker's segment pose or its
neighbours' motion, tied to both sightings by ``gap_ends``): one side alone drifts with
nothing to tie it. Gaps open at either end of the take are left as they are.

Measured with ``bench/model_start.py`` (fill RMSE against the clean truth, markers on segments
of three or more): CMU 85_02 labeled from a model of its first half 15.4 -> 11.9 mm,
Rajagopal's run from a template 20.0 -> 17.6 mm, gait2354's walk 8.9 -> 9.7 mm (one thigh gap
of a 151-frame take); medians 5-6 -> 4 mm.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.gap_ends import closed_gaps
from formulations.markers.rigid import rigid_transform

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
MAX_DONORS = 4  # fill RMSE was flat from 4 to 6 donors on the takes measured, worse at 3
MIN_SHARED_FRAMES = 10  # a spread from fewer frames together says nothing of rigidity


def rigid_fill(positions: Array, filled: Array) -> Array:
    """``filled`` ``(F, N, 3)`` with every closed gap of ``positions`` ``(F, N, 3)`` (NaN where
    not labeled) refilled by its donors' rigid motion where both sides have three donors."""
    refilled = filled.copy()
    seen: Mask = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    known = np.where(seen[:, :, None], positions, 0.0)
    for marker in range(positions.shape[1]):
        gaps = closed_gaps(seen[:, marker])
        if not gaps:
            continue
        spread = _distance_spread(known, seen, marker)
        donors = np.argsort(spread)[: int(np.isfinite(spread).sum())]
        weight = 1.0 / (spread[donors] ** 2 + 1.0)
        for start, end in gaps:
            around = slice(start - 1, end + 2)  # the gap and a sighting on either side
            track = positions[around][:, [marker, *donors]]
            _fill_gap(refilled[start : end + 1, marker], track, seen[around][:, donors], weight)
    return refilled


def _distance_spread(known: Array, seen: Mask, marker: int) -> Array:
    """``(N,)`` sd of each marker's distance to ``marker`` over the frames both were labeled
    (``known``: positions, 0 where not); inf for the marker itself and for pairs labeled
    together in too few frames."""
    both = seen[:, marker, None] & seen
    distance = np.where(both, np.linalg.norm(known - known[:, marker, None], axis=2), 0.0)
    count = both.sum(axis=0)
    mean = distance.sum(axis=0) / np.maximum(count, 1)
    variance = (np.where(both, distance - mean, 0.0) ** 2).sum(axis=0) / np.maximum(count - 1, 1)
    spread: Array = np.sqrt(variance)
    spread[count < MIN_SHARED_FRAMES] = np.inf
    spread[marker] = np.inf
    return spread


def _fill_gap(gap: Array, track: Array, donor_seen: Mask, weight: Array) -> None:
    """Refill ``gap`` in place from ``track`` ``(G + 2, 1 + D, 3)``: the marker, then its donors
    most rigid first, over the gap's G frames and the sighting on either side; ``donor_seen``
    ``(G + 2, D)`` where each donor is labeled."""
    before, before_ok = _carry(track, donor_seen, weight, 0)
    after, after_ok = _carry(track, donor_seen, weight, len(track) - 1)
    both = before_ok & after_ok
    share = (np.arange(1, len(track) - 1) / (len(track) - 1))[:, None]
    gap[both] = ((1.0 - share) * before + share * after)[both]


def _carry(track: Array, donor_seen: Mask, weight: Array, side: int) -> tuple[Array, Mask]:
    """Where the donors of sighting frame ``side`` carry the marker in the gap's frames, and in
    which of them they are three or more (``MAX_DONORS`` most rigid labeled at both frames)."""
    usable = donor_seen[side] & donor_seen[1:-1]
    usable &= np.cumsum(usable, axis=1) <= MAX_DONORS
    enough = usable.sum(axis=1) >= 3
    carried = np.full((len(track) - 2, 3), np.nan)
    if not enough.any():
        return carried, enough
    target = np.nan_to_num(track[1:-1, 1:][enough])
    source = np.broadcast_to(np.nan_to_num(track[side, 1:]), target.shape)
    rotation, c_s, c_t = rigid_transform(source, target, usable[enough] * weight)
    carried[enough] = np.einsum("tij,tj->ti", rotation, track[side, 0] - c_s) + c_t
    return carried, enough
