"""A closed gap filled by the rigid motion of the markers that move with it, from both sides.

Once a take is labeled, each gap of marker n (frames s..e) has a sighting on either side,
at a = s - 1 and b = e + 1. Its donors are the markers whose distance to n varied least
over the frames where both were labeled (spread sd_k, ``subject.distances.distance_spread``,
Ringer & Lasenby's D), weighted w_k = 1 / (sd_k^2 + 1 mm^2). In frame t, side r in {a, b}
carries n by the weighted Kabsch motion of its ``MAX_DONORS`` most rigid donors labeled at
both r and t:

    (R, c_r, c_t) = argmin sum_k w_k |R (x_k(r) - c_r) + c_t - x_k(t)|^2,
    y_r(t) = R (x_n(r) - c_r) + c_t,

and the fill is the blend y(t) = (1 - u) y_a(t) + u y_b(t), u = (t - a) / (b - a).

This is the rigid-body fill of commercial labeling tools, with the donors chosen from the
take's own labels and both sides blended: the fill keeps how the markers sit in this take,
and each carry counts most near the sighting it starts from, where it has drifted least.
A frame where either side has fewer than three donors, or only donors on one line, keeps
the fill it had (the marker's segment pose or its neighbours' motion, tied to both sightings
by ``gap_ends``): one side alone drifts with nothing to tie it. Gaps open at either end of
the take are left as they are.

Measured over the accuracy matrix's 17 takes (``bench/fill_matrix.py``: lp-l1, 600 frames,
default and 30 % deletions in 60-frame bursts, against the clean truth): the median fill
error falls by about a third (seed 0: 10.0 -> 6.9 mm pooled; seeds 1-2: 9.2 -> 6.2 mm) and
the RMSE is lower on 27 of 34 rows (seed 0; 113.6 -> 91.6 mm pooled) and 47 of 68 (seeds
1-2; 100.3 -> 98.9 mm). It is higher where long bursts leave few donors moving with the
marker (BTS, Qualisys and 135_02 with deletions: up to +21 mm).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.gap_ends import closed_gaps
from formulations.markers.rigid import MIN_SPAN_MM, rigid_transform, span_across_line
from formulations.subject.distances import distance_spread

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
MAX_DONORS = 4  # fill RMSE was flat from 4 to 6 donors on the takes measured, worse at 3
MIN_SHARED_FRAMES = 10  # a spread from fewer frames together says nothing of rigidity


def rigid_fill(positions: Array, filled: Array) -> Array:
    """``filled`` ``(F, N, 3)`` with every closed gap of ``positions`` ``(F, N, 3)`` (NaN where
    not labeled) refilled by its donors' rigid motion where both sides have three donors."""
    refilled = filled.copy()
    seen: Mask = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    if seen.all():
        return refilled
    spread, _ = distance_spread(positions, MIN_SHARED_FRAMES)
    np.fill_diagonal(spread, np.inf)  # a marker is not its own donor
    for marker in range(positions.shape[1]):
        gaps = closed_gaps(seen[:, marker])
        if not gaps:
            continue
        donors = np.argsort(spread[marker])[: int(np.isfinite(spread[marker]).sum())]
        for start, end in gaps:
            around = slice(start - 1, end + 2)  # the gap and a sighting on either side
            track = positions[around][:, [marker, *donors]]
            _fill_gap(refilled[start : end + 1, marker], track, seen[around][:, donors], spread[marker, donors])
    return refilled


def _fill_gap(gap: Array, track: Array, donor_seen: Mask, spread: Array) -> None:
    """Refill ``gap`` in place from ``track`` ``(G + 2, 1 + D, 3)``: the marker, then its donors
    most rigid first (``spread`` ``(D,)``), over the gap's G frames and the sighting on either
    side; ``donor_seen`` ``(G + 2, D)`` where each donor is labeled."""
    before, before_ok = _carry(track, donor_seen, spread, 0)
    after, after_ok = _carry(track, donor_seen, spread, len(track) - 1)
    both = before_ok & after_ok
    share = (np.arange(1, len(track) - 1) / (len(track) - 1))[:, None]
    gap[both] = ((1.0 - share) * before + share * after)[both]


def _carry(track: Array, donor_seen: Mask, spread: Array, side: int) -> tuple[Array, Mask]:
    """Where the donors of sighting frame ``side`` carry the marker in the gap's frames, and in
    which of them they are three or more (``MAX_DONORS`` most rigid labeled at both frames)
    off one line: donors on a line (a bar's markers) leave the turn about it free, and a
    marker a hand's breadth away would go anywhere."""
    usable = donor_seen[side] & donor_seen[1:-1]
    usable &= np.cumsum(usable, axis=1) <= MAX_DONORS
    source = np.broadcast_to(np.nan_to_num(track[side, 1:]), usable.shape + (3,))
    enough = (usable.sum(axis=1) >= 3) & (span_across_line(source, usable.astype(float)) >= MIN_SPAN_MM)
    carried = np.full((len(track) - 2, 3), np.nan)
    if not enough.any():
        return carried, enough
    target = np.nan_to_num(track[1:-1, 1:][enough])
    rotation, c_s, c_t = rigid_transform(source[enough], target, usable[enough] / (spread**2 + 1.0))
    carried[enough] = np.einsum("tij,tj->ti", rotation, track[side, 0] - c_s) + c_t
    return carried, enough
