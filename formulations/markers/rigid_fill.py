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

from collections.abc import Callable, Iterable

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
    donors = _Donors.of(spread)
    # Every frame of every gap carried at once: one fit per gap and side cost more in numpy's
    # per-call overhead than in the fits (03_rolling from 562: 1.1 -> 0.5 s, the same fill to 1e-9 mm).
    gaps = _gaps(seen, range(seen.shape[1]), closed_gaps)
    column, frame, gap = _gap_frames(gaps)
    before, after = gaps[gap, 1] - 1, gaps[gap, 2] + 1  # the sightings on either side
    track, doubt = positions, np.where(seen, 0.0, np.inf)
    for _ in range(ROUNDS):
        refilled, fill_doubt = filled.copy(), np.full(seen.shape, np.inf)
        from_before, before_ok = donors.carry(track, doubt, column, before, frame)
        from_after, after_ok = donors.carry(track, doubt, column, after, frame)
        both = before_ok & after_ok
        share = ((frame - before) / (after - before))[:, None]
        refilled[frame[both], column[both]] = ((1.0 - share) * from_before + share * from_after)[both]
        fill_doubt[frame, column] = np.where(both, np.sum((from_before - from_after) ** 2, axis=1) / 4.0, np.inf)
        carried = np.isfinite(fill_doubt)
        track, doubt = np.where(carried[..., None], refilled, positions), np.where(seen, 0.0, fill_doubt)
    variance = doubt[:, :markers].copy()  # the closed gaps' track and doubt stay what donors read
    gaps = _gaps(seen, np.flatnonzero(donors.count[:markers] >= 2), open_gaps)  # two donors carry, fewer keep the fill
    column, frame, gap = _gap_frames(gaps)
    sighting = np.where(gaps[:, 1] == 0, gaps[:, 2] + 1, gaps[:, 1] - 1)[gap]  # the one side seen
    carried, enough = donors.carry(track, doubt, column, sighting, frame)
    refilled[frame[enough], column[enough]] = carried[enough]
    variance[frame[enough], column[enough]] = donors.combined[column[enough]]
    return refilled[:, :markers], variance


class _Donors:
    """Each column's donors, most rigid first, padded to one width with a column that is
    never known (index = the number of columns: NaN track, inf doubt and variance)."""

    def __init__(self, table: NDArray[np.intp], variance: Array, count: NDArray[np.intp]) -> None:
        self.table, self.variance, self.count = table, variance, count
        # a gap open at one end: the variance of the donors' combined distance (module doc);
        # inf for a column with no donor (every spread inf: labeled in too few frames)
        with np.errstate(divide="ignore"):
            self.combined = 1.0 / np.sum(1.0 / variance[:, :MAX_DONORS], axis=1)

    @classmethod
    def of(cls, spread: Array) -> _Donors:
        """The donors of every column from the ``(C, C)`` spreads (inf: never a donor)."""
        count = np.isfinite(spread).sum(axis=1)
        width = max(int(count.max(initial=0)), 1)  # at most the other columns: a marker is not its own donor
        order = np.argsort(spread, axis=1, kind="stable")[:, :width]
        table = np.where(np.arange(width) < count[:, None], order, len(spread))
        variance = np.where(table < len(spread), np.take_along_axis(spread, order, axis=1) ** 2 + 1.0, np.inf)
        return cls(table, variance, count)

    def carry(self, track: Array, doubt: Array, column: NDArray[np.intp], side: NDArray[np.intp],
              frame: NDArray[np.intp]) -> tuple[Array, Mask]:
        """``(S, 3)`` where the donors of ``column`` at sighting frame ``side`` carry it in
        ``frame`` (each ``(S,)``), and ``(S,)`` where two or more do: the ``MAX_DONORS``
        known at both frames whose distance to the column is surest (its variance plus their
        positions'), weighted by its inverse. Donors spread off a line carry it by their
        weighted Kabsch motion; donors on a line (the forearm's markers once the hand is
        lost) leave the turn about the line free, so they carry it by the least turn that
        follows the line (``line_motion``), and the blend of both sides' carries then turns
        it about the line from one sighting's roll to the other's."""
        track = np.concatenate([track, np.full((len(track), 1, 3), np.nan)], axis=1)
        doubt = np.concatenate([doubt, np.full((len(doubt), 1), np.inf)], axis=1)
        table = self.table[column]
        total = self.variance[column] + doubt[side[:, None], table] + doubt[frame[:, None], table]  # inf where unknown
        pick = np.sort(np.argsort(total, axis=1, kind="stable")[:, :MAX_DONORS], axis=1)  # in the donors' order
        total, table = np.take_along_axis(total, pick, axis=1), np.take_along_axis(table, pick, axis=1)
        usable = np.isfinite(total)
        enough = usable.sum(axis=1) >= 2
        carried = np.full((len(column), 3), np.nan)
        if not enough.any():
            return carried, enough
        weight = np.where(usable, 1.0 / np.where(usable, total, 1.0), 0.0)[enough]
        source = np.nan_to_num(track[side[enough, None], table[enough]])
        target = np.nan_to_num(track[frame[enough, None], table[enough]])
        rotation, c_s, c_t = rigid_transform(source, target, weight)
        on_line = (usable[enough].sum(axis=1) < 3) | (span_across_line(source, weight) < MIN_SPAN_MM)
        if on_line.any():
            rotation[on_line], c_s[on_line], c_t[on_line] = line_motion(source[on_line], target[on_line], weight[on_line])
        own = track[side[enough], column[enough]]
        carried[enough] = np.einsum("tij,tj->ti", rotation, own - c_s) + c_t
        return carried, enough


def _gaps(seen: Mask, columns: Iterable[int], found: Callable[[Mask], list[tuple[int, int]]]) -> NDArray[np.intp]:
    """``(G, 3)`` the gaps ``found`` in each of ``columns`` of ``seen`` ``(F, C)``: column, first and last frame."""
    return np.array([(c, s, e) for c in columns for s, e in found(seen[:, c])], dtype=np.intp).reshape(-1, 3)


def _gap_frames(gaps: NDArray[np.intp]) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """Every frame of ``gaps`` (``_gaps``): its column, the frame, and its gap's row, each ``(S,)``."""
    length = gaps[:, 2] - gaps[:, 1] + 1
    gap = np.repeat(np.arange(len(gaps)), length)
    frame = np.arange(len(gap)) - np.repeat(np.cumsum(length) - length, length) + gaps[gap, 1]
    return gaps[gap, 0], frame, gap
