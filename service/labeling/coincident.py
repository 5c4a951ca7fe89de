"""Markers that sit on one position: copied columns, whose labels cannot be told apart.

Some files carry a marker twice (HDM05's ``*0``, ``*1`` and ``*2`` repeat LFHD, CLAV and
LFWT to the micrometre). Two points at one position are two equally good readings of each
of the two markers: the windows that hold them are fractional, and the fast-motion check
would read their zero spacing as aliasing. Either reading puts each label at that position,
so neither is counted against the other (``formulations.confidence.same_place``: before,
each such label was held at p = 1/2, doubtful though right). A pair
is reported when its median distance, over sampled frames where both are labeled, is below
``COINCIDENT_MM``; ``take_warnings`` leaves such partners out of a marker's spacing.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from formulations.markers.lengths import lengths
from service.words import counted

COINCIDENT_MM = 0.5  # under any marker's radius; two real markers are never this close
SAMPLED_FRAMES = 400  # distances read on this many evenly spaced frames (O(F N^2) otherwise)
LISTED = 4  # pairs named in the warning line


def coincident_pairs(names: list[str], positions: np.ndarray) -> list[tuple[str, str]]:
    """Pairs of markers of ``positions`` ``(F, N, 3)`` (mm, NaN unlabeled) on one position."""
    if len(positions) == 0 or len(names) < 2:
        return []
    median = np.full((len(names), len(names)), np.inf)
    for n, apart in enumerate(sampled_rows(positions)):
        both = np.isfinite(apart).any(axis=0)
        median[n, both] = np.nanmedian(apart[:, both], axis=0)
    first, second = np.nonzero(np.triu(median < COINCIDENT_MM, k=1))
    return [(names[a], names[b]) for a, b in zip(first.tolist(), second.tolist())]


def sampled_rows(positions: np.ndarray) -> Iterator[np.ndarray]:
    """Marker by marker, ``(S, N)`` its distance to every marker on ``SAMPLED_FRAMES`` evenly
    spaced frames (NaN where either is unlabeled): one row at a time, as the whole ``(S, N, N)``
    held 0.9 GB at 300 markers and 6 GB at 500 (with its ``(S, N, N, 3)`` differences)."""
    sampled = positions[np.unique(np.linspace(0, len(positions) - 1, SAMPLED_FRAMES).astype(int))]
    for n in range(sampled.shape[1]):
        yield lengths(sampled - sampled[:, [n]])


def coincident_warning(pairs: list[tuple[str, str]]) -> str | None:
    """One line naming the pairs (the first ``LISTED``), or None."""
    if not pairs:
        return None
    named = ", ".join(f"{a} and {b}" for a, b in pairs[:LISTED])
    more = f" and {len(pairs) - LISTED} more" if len(pairs) > LISTED else ""
    return (f"warning: {counted(len(pairs), 'pair')} of markers on one position ({named}{more}): copied columns? "
            "each pair's two labels cannot be told apart (both are at that position, so neither is doubtful)")
