"""Where a recording's own labels jump to another marker: its ground truth is not truth there.

Hand-labeled takes with real gaps carry identity errors. After a gap the file's label can go
on along another physical marker: on numediart's 03_rolling, LL_HME's distances to four
markers rigid with it (LLUA1, LLF2, LL_RSP, LL_USP; s.d. 2-3 mm within a run) fall from
~220 to ~140 mm across a gap near frame 690 and rise back later. Scored against such a
label, a labeler that follows the file counts as right, and one that doubts the broken
shape counts as a false alarm; neither is known to be right.

A marker's seen runs are judged in order against the last run of at least ``min_frames``
frames taken as its own (the first such run is taken as its own: the labels are trusted
until their shape says otherwise). A run has *jumped* when, over its partners rigid with
the marker in both runs (distance s.d. within each run at most ``rigid_mm``, the partner
seen in at least 3 frames of each), there are at least ``min_partners`` and the median
change of their median distances exceeds ``jump_mm``:

    jumped(r) = |R| >= min_partners  and  median_{k in R} |d_r(k) - d_ref(k)| > jump_mm

A median over several partners keeps one jumped partner from accusing the marker. A run
that jumped is not a reference; the next run that matches the reference again is. A marker
held still against partners on another segment before and after a gap, with the joint
turned during it, reads as a jump: such marker-frames are left out of a score, not counted
wrong, so the cost of that error is a smaller sample.

A label can also be handed over with no gap: marker B's label leaves its track in frame t,
landing where marker A's track, whose label ends at t - 1, was heading, while A's label is
gone. With x^_m(t) = 2 x_m(t - 1) - x_m(t - 2) a track's constant-velocity continuation
(x_m(t - 1) when it has no step), B's run is handed over from t to its end when

    |x_B(t) - x^_B(t)| > jump_mm   and   |x_B(t) - x^_A(t)| < |x_B(t) - x^_B(t)| / handoff_ratio.

The KTK basket sprint's ForearmL:Marker1 label at frame 732 moves 73 mm onto the point of
ForearmL:Marker4 (0.1 mm from where that track was heading), whose label ends there; on no other
take of ``service.evaluation.matrix.RECORDINGS`` does a label do this.

A rigid plate can also come back from a gap with its labels exchanged, which moves each
marker's distance to one partner only (``plate_flips``): its marker-frames are left out too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.runs import runs
from service.evaluation.plate_flips import plate_flips
from service.io.recording import Recording

Mask = NDArray[np.bool_]
Array = NDArray[np.float64]


@dataclass(frozen=True)
class LabelJumpRule:
    """When a run's rigid distances say its label sits on another marker (module doc).

    ``rigid_mm`` is a few times the noise of a good lab's markers on one segment; ``jump_mm``
    is far beyond what skin motion moves a marker relative to its segment neighbours and
    short of the spacing of markers on a body.
    """

    rigid_mm: float = 5.0
    jump_mm: float = 25.0
    min_partners: int = 3
    min_frames: int = 10
    handoff_ratio: float = 5.0


def label_jumps(recording: Recording, rule: LabelJumpRule = LabelJumpRule()) -> Mask:
    """``(frames, markers)`` the seen marker-frames of runs whose label jumped (module doc)."""
    seen = ~recording.missing()
    jumped = np.zeros_like(seen)
    for marker in range(seen.shape[1]):
        reference: tuple[Array, Array] | None = None
        for start, length in runs(seen[:, marker]):
            span = slice(start, start + length)
            shape = _run_shape(recording.positions[span], marker)
            if reference is not None and _moved(reference, shape, rule):
                jumped[span, marker] = True
            elif length >= rule.min_frames:
                reference = shape
    return jumped | _handed_over(recording.positions, seen, rule) | plate_flips(recording)


def _handed_over(positions: Array, seen: Mask, rule: LabelJumpRule) -> Mask:
    """``(frames, markers)`` the marker-frames of runs whose label was handed over (module doc)."""
    handed = np.zeros_like(seen)
    for t in range(2, len(seen)):
        ended = seen[t - 1] & ~seen[t]
        if not ended.any():
            continue
        heading = np.where((seen[t - 1] & seen[t - 2])[:, None], 2 * positions[t - 1] - positions[t - 2],
                           positions[t - 1])
        kept = np.flatnonzero(seen[t] & seen[t - 1])
        own = np.linalg.norm(positions[t, kept] - heading[kept], axis=1)
        other = np.linalg.norm(positions[t, kept][:, None] - heading[ended][None], axis=2).min(axis=1)
        for marker in kept[(own > rule.jump_mm) & (other < own / rule.handoff_ratio)]:
            stop = t + int(np.argmin(np.r_[seen[t:, marker], False]))  # to the end of its run
            handed[t:stop, marker] = True
    return handed


def _run_shape(positions: Array, marker: int) -> tuple[Array, Array]:
    """``(markers,)`` median and s.d. of the marker's distance to each other marker over a
    run; NaN for partners seen in fewer than 3 of its frames (and for itself)."""
    distance = np.linalg.norm(positions - positions[:, marker : marker + 1], axis=2)
    distance[:, marker] = np.nan
    enough = np.isfinite(distance).sum(axis=0) >= 3
    median, sd = np.full(len(enough), np.nan), np.full(len(enough), np.nan)
    median[enough] = np.nanmedian(distance[:, enough], axis=0)
    sd[enough] = np.nanstd(distance[:, enough], axis=0)
    return median, sd


def _moved(reference: tuple[Array, Array], shape: tuple[Array, Array], rule: LabelJumpRule) -> bool:
    with np.errstate(invalid="ignore"):
        rigid = (reference[1] <= rule.rigid_mm) & (shape[1] <= rule.rigid_mm)
    if rigid.sum() < rule.min_partners:
        return False
    return bool(np.median(np.abs(shape[0][rigid] - reference[0][rigid])) > rule.jump_mm)
