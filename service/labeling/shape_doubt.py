"""Labels that left the shape of their rigid neighbours (``formulations.markers.shape_breaks``):
marked doubtful, listed in the summary, and said in one line.

An integral window is optimal under the model, not right: on CMU 135_02 three forefoot
markers rotate for the last 716 frames at confidence 0.99+ with every window integral, and
on 03_rolling an upper-arm marker sits on the head's point for 738 frames at 0.9999. Their
distances to the markers of their own segment give them away, and the user is told where.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.markers.shape_breaks import ShapeBreak, shape_breaks
from service.io.recording import LabeledTrajectories

# The reported confidence of a label inside a break: of the labels in breaks on the real takes
# that have any (relabeled by ``bench/real_takes.py`` from docs/measured.md's start frames), 32 % were
# right on CMU 135_02 (1,911 labels), 1 % on 03_rolling (2,610) and 0 % on the basket sprint
# (328): 13 % pooled. The fourteen other takes had no break at all, and on the accuracy matrix's
# simulated takes (``bench/shape_breaks_matrix.py``) 1 run of 68 had one: 139 labels, none right.
SHAPE_BREAK_CONFIDENCE = 0.15
LISTED = 4  # breaks named in the warning line


def shape_doubted(labels: LabeledTrajectories) -> tuple[LabeledTrajectories, list[ShapeBreak]]:
    """``labels`` with the confidence of every label inside a break at most
    ``SHAPE_BREAK_CONFIDENCE``, and the breaks (longest first)."""
    breaks = shape_breaks(labels.positions, labels.rate)
    if not breaks or not labels.confidence.size:
        return labels, breaks
    confidence = labels.confidence.copy()
    seen = np.isfinite(labels.positions).all(axis=2)
    for b in breaks:
        run = confidence[b.start : b.stop, b.marker]
        run[seen[b.start : b.stop, b.marker]] = np.fmin(run, SHAPE_BREAK_CONFIDENCE)[seen[b.start : b.stop, b.marker]]
    return replace(labels, confidence=confidence), breaks


def shape_break_summary(breaks: list[ShapeBreak], names: list[str]) -> list[dict]:
    """Each break as ``{"marker", "frames": [start, stop], "off_mm", "neighbour", "reference_mm",
    "seen_mm"}`` (frames from 0, stop exclusive), for a summary."""
    return [{"marker": names[b.marker], "frames": [b.start, b.stop], "off_mm": round(b.off_mm, 1),
             "neighbour": names[b.neighbour], "reference_mm": round(b.reference_mm, 1),
             "seen_mm": round(b.seen_mm, 1)} for b in breaks]


def shape_break_warning(breaks: list[ShapeBreak], names: list[str], first_frame: int = 0) -> str | None:
    """One line naming the longest breaks (frames numbered from ``first_frame``), or None."""
    if not breaks:
        return None
    markers = len({b.marker for b in breaks})
    listed = "; ".join(_said(b, names, first_frame) for b in breaks[:LISTED])
    more = f"; {len(breaks) - LISTED} more in the summary" if len(breaks) > LISTED else ""
    return (f"warning: {markers} marker{'s' if markers > 1 else ''} left the shape their rigid neighbours keep, "
            f"so their labels there are likely wrong (optimal windows included; labels doubtful): {listed}{more}")


def _said(b: ShapeBreak, names: list[str], first_frame: int) -> str:
    return (f"{names[b.marker]} frames {first_frame + b.start}-{first_frame + b.stop - 1} ({b.off_mm:.0f} mm off; "
            f"{names[b.neighbour]} {b.seen_mm:.0f} mm away, was {b.reference_mm:.0f})")
