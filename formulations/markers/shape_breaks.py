"""Stretches where a labeled marker leaves the shape its rigid neighbours keep.

A window is optimal under its model, not right: a label that moved onto another marker's
point (an exchange, a three-way rotation of a forefoot, an arm marker on the head) can stay
there for the rest of a take with every window integral and every confidence high. What
such a label cannot do is keep its distances to the markers that share its segment. This
check reads only the labeling, no ground truth:

- reference: for each pair (i, j), the median distance d0_ij over the first
  ``REFERENCE_SECONDS`` of frames where both are labeled (the frames the labeled start
  vouches for), and the spread s_ij = 1.4826 MAD of their distance over the whole take
  (robust to half of the frames being wrong);
- rigid neighbours N(i): the ``NEIGHBOURS`` markers of smallest s_ij among those with
  ``SPREADS`` s_ij < n_i, n_i being i's nearest-neighbour distance in the reference (a
  looser pair cannot tell i's point from its neighbour's; over a still take every pair is
  rigid, and then every pair may judge);
- in frame t, marker i is *off* when, of its labeled neighbours (at least two), a majority
  has |d_ij(t) - d0_ij| > tol_ij = max(``SPREADS`` s_ij, ``NEAREST_SHARE`` n_i): a label on
  a neighbour's point moves by about n_i, skin and soft-tissue motion by a few spreads;
- a break is a run of off frames (unlabeled frames neither end nor count in it) at least
  ``MIN_SECONDS`` long.

Which one of two markers that traded places is wrong is not decided: both leave the shape.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.lengths import lengths
from formulations.markers.means import column_nanmedian
from formulations.markers.runs import runs

REFERENCE_SECONDS = 2.0  # the labeled start's own stretch: short enough that its labels hold
MIN_REFERENCE_FRAMES = 10  # fewer joint sightings say nothing of a pair's distance
NEIGHBOURS = 4  # enough that one neighbour's own bad label cannot make a majority
SPREADS = 5.0  # in spreads: skin motion over a take, under the 1.4826 MAD scale
NEAREST_SHARE = 0.5  # of the nearest-neighbour distance: half a marker spacing (0.25 flags right labels on the tennis serve)
# a marker off its segment for a second is lost; a toe flexed or a kick is shorter (0.25-0.85 s off
# on the right labels of HDM05 and CMU 85_02)
MIN_SECONDS = 1.0


@dataclass(frozen=True)
class ShapeBreak:
    """Marker ``marker`` off its rigid neighbours over frames ``start .. stop - 1``.

    ``off_mm``: the median over the run of the median |d - d0| to its neighbours;
    ``neighbour``: the most rigid of its neighbours labeled most often in the run, whose
    distance was ``reference_mm`` and is ``seen_mm`` (median over the run)."""

    marker: int
    start: int
    stop: int
    off_mm: float
    neighbour: int
    reference_mm: float
    seen_mm: float


def shape_breaks(positions: NDArray[np.float64], rate: float) -> list[ShapeBreak]:
    """Every break in ``positions`` ``(frames, markers, 3)`` mm (NaN where unlabeled), longest first."""
    frames, markers, _ = positions.shape
    if frames < 2 or markers < 3:
        return []
    first = max(MIN_REFERENCE_FRAMES, int(round(REFERENCE_SECONDS * rate)))
    min_frames = max(2, int(MIN_SECONDS * rate))
    breaks = []
    for i in range(markers):
        distance = lengths(positions - positions[:, [i]])  # (frames, markers)
        distance[:, i] = np.nan
        reference, spread = _pair_figures(distance, first)
        if not np.isfinite(reference).any():
            continue
        nearest = np.nanmin(reference)
        # a judge must see a marker spacing: a pair looser than that cannot tell a neighbour's point
        judges = np.flatnonzero(np.isfinite(reference) & (SPREADS * np.nan_to_num(spread, nan=np.inf) < nearest))
        if len(judges) < 2:
            continue
        neighbours = judges[np.argsort(spread[judges], kind="stable")[:NEIGHBOURS]]
        tolerance = np.maximum(SPREADS * spread[neighbours], NEAREST_SHARE * nearest)
        breaks += _runs(i, distance[:, neighbours], neighbours, reference[neighbours], tolerance, min_frames)
    return sorted(breaks, key=lambda b: b.start - b.stop)


def _pair_figures(distance: NDArray[np.float64], first: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One marker's ``(markers,)`` reference distances, over the first ``first`` frames where
    both are labeled, and spreads (1.4826 MAD) over all; NaN where too few frames have both."""
    seen = np.isfinite(distance)
    early = np.where(seen & (np.cumsum(seen, axis=0) <= first), distance, np.nan)
    enough = seen.sum(axis=0) >= MIN_REFERENCE_FRAMES
    reference, spread = np.full(distance.shape[1], np.nan), np.full(distance.shape[1], np.nan)
    reference[enough] = column_nanmedian(early[:, enough])
    middle = column_nanmedian(distance[:, enough])
    spread[enough] = 1.4826 * column_nanmedian(np.abs(distance[:, enough] - middle))
    return reference, spread


def _runs(
    i: int, distance: NDArray[np.float64], neighbours: NDArray[np.int64], reference: NDArray[np.float64],
    tolerance: NDArray[np.float64], min_frames: int,
) -> list[ShapeBreak]:
    """Marker ``i``'s breaks, from its ``(frames, k)`` distances to its rigid neighbours."""
    labeled = np.isfinite(distance)
    deviation = np.abs(distance - reference)
    off_votes = (np.nan_to_num(deviation, nan=0.0) > tolerance).sum(axis=1)
    judged = labeled.sum(axis=1) >= 2
    off = judged & (2 * off_votes > labeled.sum(axis=1))
    out = []
    for start, stop in _off_runs(off, judged):
        run = off[start:stop]
        if run.sum() < min_frames:
            continue
        off_mm = float(np.median(np.nanmedian(deviation[start:stop][run], axis=1)))
        shown = int(np.argmax(labeled[start:stop].sum(axis=0)))  # the most rigid of those seen most there
        seen = distance[start:stop, shown]
        seen_mm = float(np.median(seen[np.isfinite(seen)]))
        out.append(ShapeBreak(i, start, stop, off_mm, int(neighbours[shown]), float(reference[shown]), seen_mm))
    return out


def _off_runs(off: NDArray[np.bool_], judged: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of off frames, frames not judged (too few labeled
    neighbours) bridged; a run ends at the first judged frame that is not off."""
    frames = np.flatnonzero(judged)
    return [(int(frames[start]), int(frames[start + length - 1]) + 1) for start, length in runs(off[frames])]
