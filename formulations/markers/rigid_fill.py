"""A closed gap filled by the rigid motion of the markers that move with it, from both sides.

Once a take is labeled, each gap of marker n (frames s..e) has a sighting on either side,
at a = s - 1 and b = e + 1. Its donors are the markers whose distance to n varied least
over the frames where both were labeled (spread sd_k, ``subject.distances.distance_spread``,
Ringer & Lasenby's D). In frame t, side r in {a, b} carries n by the weighted Kabsch motion
of the ``MAX_DONORS`` donors known at both r and t with the least variance
v_k = sd_k^2 + 1 mm^2 (+ their own fill's variance, below), weighted w_k = 1 / v_k:

    (R, c_r, c_t) = argmin sum_k w_k |R (x_k(r) - c_r) + c_t - x_k(t)|^2,
    y_r(t) = R (x_n(r) - c_r) + c_t,

and the fill is the blend y(t) = (1 - u) y_a(t) + u y_b(t), u = (t - a) / (b - a).

This is the rigid-body fill of commercial labeling tools, with the donors chosen from the
take's own labels and both sides blended: the fill keeps how the markers sit in this take,
and each carry counts most near the sighting it starts from, where it has drifted least.
Two refinements for markers lost together (a hand's three markers, a cluster's two of three):

- Donors on one line (two donors, or a forearm's markers once the hand is lost) fix no turn
  about the line, so they carry n by the least turn that follows the line
  (``rigid.line_motion``), and the blend turns it about the line from one sighting's roll
  to the other's; a free fit would take that turn from the noise.
- In a second round (``ROUNDS``) a donor lost too counts where the first round refilled it,
  with the variance (|y_a - y_b| / 2)^2 the disagreement of its own two carries gives it: a
  wrist marker refilled from the forearm then carries the finger lost beside it, while a
  donor whose sightings disagree (it was mislabeled) weighs nothing and yields its place.

A frame where either side has fewer than two donors keeps the fill it had (the marker's
segment pose or its neighbours' motion, tied to both sightings by ``gap_ends``): one side
alone drifts with nothing to tie it. A gap open at either end of the take has one sighting
only, and is carried from it alone (after the rounds), with the variance of the donors'
combined distance, 1 / sum_k (1 / v_k) over the ``MAX_DONORS`` most rigid: nothing else says
where the marker is there, and the fill it had came from a model or a motion that never saw
this take (CMU 135_02 from a first-half model: RTHI, grouped with the pelvis, was filled
from the pelvis for its first 21 unseen frames while the thigh swung, up to 171 mm off).

Measured over the accuracy matrix's 17 takes (``bench/fill_matrix.py``: lp-l1, 600 frames,
default and 30 % deletions in 60-frame bursts, against the clean truth), against the tied
fill: RMSE 103.7 -> 88.6 mm pooled and median 10.0 -> 6.6 mm, lower on 29 of 34 rows (seed
0); 98.9 -> 95.6 and 9.2 -> 6.0 mm, lower on 54 of 68 (seeds 1-2). Against the refill before
the line carry and the second round, the same labels: 89.5 -> 88.6 mm, lower on 24 rows and
higher on 10 (seed 0); 97.1 -> 95.6 mm, lower on 52 and higher on 16 (seeds 1-2; the tennis
serve at the strike +11 mm). The RMSE is dominated by gaps whose sightings are themselves
mislabeled, which no fill can mend.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.gap_ends import closed_gaps, open_gaps
from formulations.markers.rigid import MIN_SPAN_MM, line_motion, rigid_transform, span_across_line
from formulations.subject.distances import distance_spread

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
MAX_DONORS = 4  # fill RMSE was flat from 4 to 6 donors on the takes measured, worse at 3
ROUNDS = 2  # a third round changed the matrix's fill by 0.2 mm pooled
MIN_SHARED_FRAMES = 10  # a spread from fewer frames together says nothing of rigidity


def rigid_fill(positions: Array, filled: Array, guides: tuple[Array, Mask] | None = None) -> Array:
    """``rigid_refill``'s fill alone."""
    return rigid_refill(positions, filled, guides)[0]


def rigid_refill(positions: Array, filled: Array, guides: tuple[Array, Mask] | None = None) -> tuple[Array, Array]:
    """``filled`` ``(F, N, 3)`` with every closed gap of ``positions`` ``(F, N, 3)`` (NaN where
    not labeled) refilled by its donors' rigid motion where both sides have two donors;
    from the second round on (``ROUNDS``) a donor's own refill counts as a sighting, with
    the variance its two sides' disagreement gives it. ``guides`` are further donor tracks
    ``(F, K, 3)`` with ``(K, N)`` the markers each may serve (the subject model's joint
    centres, ``subject.joint_tracks``); their own gaps are refilled too, for the second
    round, but not returned. Also ``(F, N)`` each refill's variance, (|y_a - y_b| / 2)^2 of
    the last round: 0 where labeled, inf where not refilled."""
    markers = positions.shape[1]
    tracks, serves = guides if guides is not None else (np.empty((len(positions), 0, 3)), np.empty((0, markers), bool))
    positions, filled = np.concatenate([positions, tracks], axis=1), np.concatenate([filled, tracks], axis=1)
    seen: Mask = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    if seen[:, :markers].all():
        return filled[:, :markers].copy(), np.zeros(seen[:, :markers].shape)
    spread, _ = distance_spread(positions, MIN_SHARED_FRAMES)
    np.fill_diagonal(spread, np.inf)  # a marker is not its own donor
    spread[:markers, markers:][~serves.T] = np.inf
    donors = [np.argsort(row)[: int(np.isfinite(row).sum())] for row in spread]
    gaps = [closed_gaps(seen[:, marker]) for marker in range(positions.shape[1])]
    track, doubt = positions, np.where(seen, 0.0, np.inf)
    for _ in range(ROUNDS):
        refilled, fill_doubt = filled.copy(), np.full(seen.shape, np.inf)
        for marker, marker_gaps in enumerate(gaps):
            mine = donors[marker]
            for start, end in marker_gaps:
                around = slice(start - 1, end + 2)  # the gap and a sighting on either side
                fill_doubt[start : end + 1, marker] = _fill_gap(
                    refilled[start : end + 1, marker], track[around][:, [marker, *mine]],
                    doubt[around][:, mine], spread[marker, mine] ** 2 + 1.0,
                )
        carried = np.isfinite(fill_doubt)
        track, doubt = np.where(carried[..., None], refilled, positions), np.where(seen, 0.0, fill_doubt)
    variance = doubt[:, :markers].copy()  # the closed gaps' track and doubt stay what donors read
    for marker in (m for m in range(markers) if len(donors[m]) >= 2):  # two donors carry, fewer keep the fill
        combined = 1.0 / np.sum(1.0 / (spread[marker, donors[marker][:MAX_DONORS]] ** 2 + 1.0))
        for start, end in open_gaps(seen[:, marker]):
            done = _fill_open(refilled[start : end + 1, marker], track, doubt, marker, donors[marker], spread, start, end)
            variance[start : end + 1, marker][done] = combined
    return refilled[:, :markers], variance


def _fill_open(
    gap: Array, track: Array, doubt: Array, marker: int, mine: NDArray[np.intp], spread: Array, start: int, end: int,
) -> Mask:
    """Refill ``gap`` (frames start..end, open at one end of the take) in place by the donors'
    carry from its one sighting; returns the frames carried (two donors or more)."""
    leading = start == 0
    sighting = end + 1 if leading else start - 1
    frames = np.r_[start : end + 1, sighting] if leading else np.r_[sighting, start : end + 1]
    columns = [marker, *mine]
    # _carry reads a gap between two sightings; the missing one is padded and never read.
    pad, pad_doubt = np.full((1, len(columns), 3), np.nan), np.full((1, len(mine)), np.inf)
    around, around_doubt = track[frames][:, columns], doubt[frames][:, mine]
    around = np.concatenate([pad, around] if leading else [around, pad])
    around_doubt = np.concatenate([pad_doubt, around_doubt] if leading else [around_doubt, pad_doubt])
    side = len(around) - 1 if leading else 0
    carried, enough = _carry(around, around_doubt, spread[marker, mine] ** 2 + 1.0, side)
    gap[enough] = carried[enough]
    return enough


def _fill_gap(gap: Array, track: Array, donor_doubt: Array, variance: Array) -> Array:
    """Refill ``gap`` in place from ``track`` ``(G + 2, 1 + D, 3)``: the marker, then its donors
    most rigid first (distance ``variance`` ``(D,)``), over the gap's G frames and the
    sighting on either side; ``donor_doubt`` ``(G + 2, D)`` each donor's position variance
    (0 labeled, inf unknown). Returns ``(G,)`` the refill's variance, (|y_a - y_b| / 2)^2,
    inf where not refilled."""
    before, before_ok = _carry(track, donor_doubt, variance, 0)
    after, after_ok = _carry(track, donor_doubt, variance, len(track) - 1)
    both = before_ok & after_ok
    share = (np.arange(1, len(track) - 1) / (len(track) - 1))[:, None]
    gap[both] = ((1.0 - share) * before + share * after)[both]
    return np.where(both, np.sum((before - after) ** 2, axis=1) / 4.0, np.inf)


def _carry(track: Array, donor_doubt: Array, variance: Array, side: int) -> tuple[Array, Mask]:
    """Where the donors of sighting frame ``side`` carry the marker in the gap's frames, and in
    which of them two or more do: the ``MAX_DONORS`` known at both frames whose distance to
    the marker is surest (its variance plus their positions'), weighted by its inverse. Donors
    spread off a line carry it by their weighted Kabsch motion; donors on a line (the
    forearm's markers once the hand is lost) leave the turn about the line free, so they
    carry it by the least turn that follows the line (``line_motion``), and the blend of
    both sides' carries then turns it about the line from one sighting's roll to the other's."""
    total = variance + donor_doubt[side] + donor_doubt[1:-1]  # inf where either is unknown
    rank = np.argsort(np.argsort(total, axis=1, kind="stable"), axis=1)
    usable = np.isfinite(total) & (rank < MAX_DONORS)
    enough = usable.sum(axis=1) >= 2
    carried = np.full((len(track) - 2, 3), np.nan)
    if not enough.any():
        return carried, enough
    weight = np.where(usable, 1.0 / np.where(usable, total, 1.0), 0.0)[enough]
    source = np.broadcast_to(np.nan_to_num(track[side, 1:]), usable.shape + (3,))[enough]
    target = np.nan_to_num(track[1:-1, 1:][enough])
    rotation, c_s, c_t = rigid_transform(source, target, weight)
    on_line = (usable[enough].sum(axis=1) < 3) | (span_across_line(source, weight) < MIN_SPAN_MM)
    if on_line.any():
        rotation[on_line], c_s[on_line], c_t[on_line] = line_motion(source[on_line], target[on_line], weight[on_line])
    carried[enough] = np.einsum("tij,tj->ti", rotation, track[side, 0] - c_s) + c_t
    return carried, enough
