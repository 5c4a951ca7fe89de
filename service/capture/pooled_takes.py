"""Takes pooled into one model should be of one subject: their rigid marker distances agree.

``markerflow model a.c3d b.c3d`` pools takes that share a marker set. Two subjects with the
same set share names but not distances, and the pooled fit then finds little rigid: CMU
85_02's subject with 135_02's gave 5 segments and every leg and arm marker a single, without
a word. Pairs of markers whose distance is steady within each take (MAD under 3 mm) are
compared between takes: between halves of one real take (85_02, 135_02, walking2, the tennis
serve, BTS) none of them moves by more than 15 mm; 85_02 against 135_02 (names made the same
case), 52 % of 23 pairs do over the whole takes, 69 % of 58 over their first halves.
"""

from __future__ import annotations

import numpy as np

from service.io.recording import Recording

STEADY_MAD_MM = 3.0  # a pair this steady within a take is on one rigid body
MOVED_MM = 15.0  # between takes of one subject no steady pair changes this much
MOVED_SHARE = 0.3  # of the steady pairs, this many moved: another subject (or the markers were re-placed)
MIN_STEADY_PAIRS = 5
SAMPLED_FRAMES = 400  # evenly spread: the distances' medians need no more


def other_subject_warning(first: Recording, other: Recording, name: str) -> str | None:
    """A line when ``other`` (the take called ``name``) looks like another subject than ``first``."""
    shared = [n for n in first.names if n in other.names]
    median_a, mad_a = _distances(first, shared)
    median_b, mad_b = _distances(other, shared)
    steady = (mad_a < STEADY_MAD_MM) & (mad_b < STEADY_MAD_MM) & np.triu(np.ones_like(mad_a, dtype=bool), 1)
    if steady.sum() < MIN_STEADY_PAIRS:
        return None
    moved = float((np.abs(median_a - median_b)[steady] > MOVED_MM).mean())
    if moved <= MOVED_SHARE:
        return None
    return (f"warning: {name}: {moved:.0%} of the marker pairs rigid in both takes differ from the first take's by "
            f"more than {MOVED_MM:.0f} mm: another subject, or markers placed again? Pooled, the model finds little "
            "rigid; fit each subject's takes on their own")


def _distances(take: Recording, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(N, N)`` median and MAD of each pair's distance over sampled frames (NaN where never both seen)."""
    columns = [take.names.index(n) for n in names]
    step = max(1, take.n_frames // SAMPLED_FRAMES)
    positions = np.where(take.missing()[::step, columns, None], np.nan, take.positions[::step, columns])
    apart = np.linalg.norm(positions[:, :, None] - positions[:, None], axis=3)
    seen = np.isfinite(apart).any(axis=0)
    median = np.full(seen.shape, np.nan)
    mad = np.full(seen.shape, np.inf)
    median[seen] = np.nanmedian(apart[:, seen], axis=0)
    mad[seen] = np.nanmedian(np.abs(apart[:, seen] - median[seen]), axis=0)
    return median, mad
