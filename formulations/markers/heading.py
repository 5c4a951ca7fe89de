"""Where a labeled track was heading in each frame, its gaps crossed at constant velocity."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def track_heading(track: Array) -> Array:
    """``(F, 3)`` where the marker was heading in each frame: its last known position before
    it, moved on at the velocity between its last two known frames (none: still); NaN before
    the first."""
    frames = np.arange(len(track))
    seen = np.isfinite(track).all(axis=1)
    last = np.maximum.accumulate(np.where(seen, frames, -1))  # last labeled frame at or before t
    before = np.concatenate([[-1], last[:-1]])  # ... strictly before t
    previous = np.concatenate([[-1], last])[np.maximum(before, 0)]  # the labeled frame before that
    previous = np.where(before >= 0, previous, -1)
    step = np.where(((previous >= 0) & (before >= 0))[:, None],
                    (track[before] - track[np.maximum(previous, 0)]) / np.maximum(before - previous, 1)[:, None], 0.0)
    heading = track[np.maximum(before, 0)] + step * (frames - before)[:, None]
    return np.where((before >= 0)[:, None], heading, np.nan)
