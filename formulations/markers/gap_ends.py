"""A gap's fill tied to where the marker was seen on both sides of it.

The fill of an occluded marker is carried forward from its last sighting (its neighbours'
rigid motion, or its segment's pose), so its error grows through the gap and ends in a jump
where the marker is seen again. Once the gap is closed, both ends are known, and the fill
is corrected as a gap-filling spline would be tied to its end points: for a gap of frames
s..e between sightings at a = s - 1 and b = e + 1, the positions the sightings extrapolate
to (one frame of the velocity seen next to them, zero where unknown) are

    y_s = x_a + (x_a - x_{a-1}),    y_e = x_b - (x_{b+1} - x_b),

the mismatches at the ends are m_s = y_s - f_s and m_e = y_e - f_e, and every frame of the
gap moves by their linear blend,

    f'_t = f_t + (1 - w_t) m_s + w_t m_e,    w_t = (t - s) / (e - s)   (1/2 for a one-frame gap),

so the fill keeps the shape its model gave the gap and meets both extrapolated sightings. A gap open at
the start or the end of the take has one sighting and is left as it is: nothing says how far
the fill has drifted.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def tie_gap_ends(positions: Array, filled: Array) -> Array:
    """``filled`` ``(F, N, 3)`` with every gap closed on both sides tied to ``positions``'
    ``(F, N, 3)`` sightings (NaN where not seen); other frames as they were."""
    tied = filled.copy()
    seen: NDArray[np.bool_] = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    for marker in range(positions.shape[1]):
        for start, end in closed_gaps(seen[:, marker]):
            _tie(tied[start : end + 1, marker], positions[:, marker], start, end)
    return tied


def closed_gaps(seen: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``(s, e)`` of each run of unseen frames with a sighting before and after it."""
    change = np.flatnonzero(seen[:-1] != seen[1:])
    starts, ends = change[seen[change]] + 1, change[~seen[change]]
    if not len(starts):
        return []
    return [(int(s), int(e)) for s, e in zip(starts, ends[ends >= starts[0]])]


def open_gaps(seen: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``(s, e)`` of the unseen run at the start and at the end of a marker seen somewhere."""
    if not seen.any() or seen.all():
        return []
    first, last = int(np.argmax(seen)), len(seen) - 1 - int(np.argmax(seen[::-1]))
    return [(s, e) for s, e in ((0, first - 1), (last + 1, len(seen) - 1)) if e >= s]


def _tie(gap: Array, track: Array, start: int, end: int) -> None:
    """Move the fill ``gap`` (frames start..end of ``track``) to meet both sightings; in place."""
    if not np.isfinite(gap).all():
        return
    before, after = track[start - 1], track[end + 1]
    ahead = before - track[start - 2] if start >= 2 and np.isfinite(track[start - 2]).all() else 0.0
    back = track[end + 2] - after if end + 2 < len(track) and np.isfinite(track[end + 2]).all() else 0.0
    mismatch_start = before + ahead - gap[0]
    mismatch_end = after - back - gap[-1]
    w = (np.arange(len(gap)) / max(len(gap) - 1, 1))[:, None] if len(gap) > 1 else np.full((1, 1), 0.5)
    gap += (1.0 - w) * mismatch_start + w * mismatch_end
