"""Segments whose labeled markers no longer fit their constellation.

With three or more labeled markers a segment is posed by Kabsch (``segment_poses``) and each
labeled marker p has a residual |R u_p + d - x_p|. A correct labeling leaves every residual
within the marker's tolerance tau_p = sigmas s_p + r (``ModelGeometry``); two markers of the
segment exchanged, or a ghost taken for one, leave residuals of the order of the distances
between markers. A segment contradicts the model when some residual exceeds ``factor`` tau_p:
its labels are then to be read again from the model, not carried on. In a frame the user
labeled, such a segment says the opposite: the model is what is off (``labeled_misfits``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.subject.geometry import ModelGeometry, SegmentGeometry
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses

Array = NDArray[np.float64]


def contradicting(geometry: ModelGeometry, positions: Array, factor: float = RIGID_WITHIN) -> NDArray[np.bool_]:
    """``(S,)`` segments of ``positions`` ``(N, 3)`` (NaN: not labeled) that contradict the model."""
    _, ratio = _residual_ratio(geometry, positions)
    return np.array([_judged(s, ratio) and bool((ratio[s.markers] > factor).any()) for s in geometry.segments],
                    dtype=bool).reshape(len(geometry.segments))


@dataclass(frozen=True)
class SegmentMisfit:
    """A segment whose labeled markers sit off its constellation: the worst marker's residual
    and that marker's tolerance tau_p (mm)."""

    segment: str
    off_mm: float
    tolerance_mm: float


def labeled_misfits(geometry: ModelGeometry, positions: Array) -> list[SegmentMisfit]:
    """The segments of a labeled frame ``positions`` ``(N, 3)`` (NaN: not labeled) that
    contradict the model at ``factor`` 1, worst (in units of tau_p) first.

    A frame the user labeled is right, so such a segment says the model does not describe the
    take: a marker placed otherwise, or markers grouped from a trial with too little motion to
    separate them (03_rolling's first 562 frames gave 10-marker segments: its head 45 mm off at
    frame 562, tolerance 33; no segment is off at the other starts measured, docs/subject-model.md).
    """
    placed, ratio = _residual_ratio(geometry, positions)
    misfits = []
    for segment in geometry.segments:
        if not _judged(segment, ratio):
            continue
        worst = segment.markers[np.nanargmax(ratio[segment.markers])]
        if ratio[worst] > 1.0:
            off = float(np.linalg.norm(placed[worst] - positions[worst]))
            misfits.append(SegmentMisfit(segment.name, off, float(geometry.tolerance[worst])))
    return sorted(misfits, key=lambda m: -m.off_mm / m.tolerance_mm)


def _residual_ratio(geometry: ModelGeometry, positions: Array) -> tuple[Array, Array]:
    """Where each marker's segment puts it (Kabsch on its labels, ``segment_poses``) and ``(N,)``
    its residual in units of its tau_p; NaN where unlabeled or unposed."""
    placed = segment_poses(geometry, positions[None]).place(geometry)[0]
    ratio: Array = np.linalg.norm(placed - positions, axis=1) / geometry.tolerance
    return placed, ratio


def _judged(segment: SegmentGeometry, ratio: Array) -> bool:
    """A segment of three or more markers, three of them labeled (and so posed): its labels can
    contradict its constellation."""
    return len(segment.markers) >= 3 and int(np.isfinite(ratio[segment.markers]).sum()) >= 3
