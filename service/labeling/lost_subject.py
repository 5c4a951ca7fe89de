"""Labels that stop while points keep coming: every marker lost at once, none named again.

A lost marker is sought again where its neighbours put it (prediction, shape
re-acquisition). When every marker is lost at once, the subject having left the capture
volume, no neighbour is left to put it anywhere; the lost group is then registered to the
returning points as one rigid body (``formulations.markers.reacquire.realign_lost``), which
finds a subject who comes back in the posture it left in, but not one who comes back in
another. On the wheelchair basketball sprint (kineticstoolkit, relabeled from frame 1632)
every marker is lost at frame 2181, and the points that return about a metre away (12 a
frame, median) stay unlabeled for the remaining 1497 frames, which hold 11 630 of the
11 865 missing labels of its 25 markers (the best rigid fit of the chair, wheel and arm
markers between frames 2150 and 3300 leaves 26-172 mm: the wheel turned, the arm moved).
A subject model names a frame from nothing (``track --model``): the warning says so
rather than leave a take that silently stops being labeled.

The span reported is the run of frames in which no marker is labeled with the most frames
that have at least ``MIN_POINTS`` points (three points are the fewest a constellation is
read from; fewer are a ghost or a stray marker), when those make at least a second.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.markers.runs import runs

MIN_POINTS = 3


@dataclass(frozen=True)
class UnnamedSpan:
    """Frames ``start .. start + frames - 1`` with no marker labeled; ``points``: the median
    number present in its frames that have at least ``MIN_POINTS``."""

    start: int
    frames: int
    points: float


def unnamed_span(occluded: np.ndarray, points_per_frame: np.ndarray, rate: float) -> UnnamedSpan | None:
    """The longest such span of a labeling (``occluded`` ``(F, N)``), or None (module doc)."""
    points = np.asarray(points_per_frame)
    readable = points >= MIN_POINTS
    spans = runs(np.all(occluded, axis=1))
    if not spans:
        return None
    start, length = max(spans, key=lambda span: int(readable[span[0] : span[0] + span[1]].sum()))
    inside = points[start : start + length][readable[start : start + length]]
    if len(inside) < rate:
        return None
    return UnnamedSpan(start, length, float(np.median(inside)))


def unnamed_warning(span: UnnamedSpan | None, rate: float, first_frame: int) -> str | None:
    """One line for ``span`` (frames numbered from ``first_frame``), or None."""
    if span is None:
        return None
    first = first_frame + span.start
    return (f"warning: no marker is labeled in frames {first}-{first + span.frames - 1} "
            f"({span.frames / rate:.1f} s) though {span.points:.0f} points a frame (median) are there: every marker "
            f"was lost and none was named again there; a subject model names them from nothing "
            f"(markerflow model on a labeled take of the subject, then label from frame {first} with it: "
            f"track --model MODEL --start {first}, or an upload's model and start={first})")


def away_span(occluded: np.ndarray, points_per_frame: np.ndarray, rate: float) -> tuple[int, int] | None:
    """``(start, frames)``: the longest run of at least a second in which the frames hold fewer
    than ``MIN_POINTS`` points (the subject out of view) and after which markers are labeled
    again, or None. Those labels come from the shape the markers had before the run alone
    (the lost group registered to the returning points): every marker of a walk that left
    the view for 500 frames came back named, 14-29 % of them right."""
    away = [(start, length) for start, length in runs(np.asarray(points_per_frame) < MIN_POINTS)
            if length >= rate and start > 0 and (~occluded[start + length :]).any()]
    return max(away, key=lambda span: span[1]) if away else None


def away_warning(span: tuple[int, int] | None, rate: float, first_frame: int) -> str | None:
    """One line for ``span`` (frames numbered from ``first_frame``), or None."""
    if span is None:
        return None
    first, back = first_frame + span[0], first_frame + span[0] + span[1]
    return (f"warning: frames {first}-{back - 1} ({span[1] / rate:.1f} s) hold no subject (under {MIN_POINTS} points a "
            "frame); the markers labeled after them were named from their shape before alone, so check them; a "
            f"subject model names them from nothing (track --model MODEL --start {back})")
