"""A labeling's tracks extended over the points no marker took (``markers.track_extension``).

Each extended label is as sure as the label it grew from: it carries the confidence of the
marker's nearest frame a window labeled.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from formulations.markers.track_extension import extend_tracks
from service.io.recording import LabeledTrajectories


def extended(labels: LabeledTrajectories, points: Sequence[np.ndarray], frames: int) -> LabeledTrajectories:
    """``labels`` with gaps entered over unclaimed ``points`` (one array per frame) within the
    first ``frames`` frames, those the windows labeled (a partial result stops there)."""
    index = labels.point_index.copy()
    index[:frames] = extend_tracks(points[:frames], labels.point_index[:frames])
    new = (index >= 0) & (labels.point_index < 0)
    if not new.any():
        return labels
    positions = labels.positions.copy()
    for f, n in zip(*np.nonzero(new)):
        positions[f, n] = points[f][index[f, n]]
    filled = labels.filled.copy() if labels.filled.size else labels.filled
    if filled.size:
        filled[new] = np.nan
    confidence = _carried(labels.confidence, labels.point_index >= 0, new) if labels.confidence.size else labels.confidence
    return replace(labels, point_index=index, positions=positions, occluded=index < 0, filled=filled, confidence=confidence)


def _carried(confidence: np.ndarray, labeled: np.ndarray, new: np.ndarray) -> np.ndarray:
    """``confidence`` with each ``new`` label given that of its marker's nearest ``labeled`` frame."""
    carried = confidence.copy()
    frames = np.arange(len(confidence))
    for n in np.flatnonzero(new.any(axis=0)):
        source = np.flatnonzero(labeled[:, n])
        at = frames[new[:, n]]
        right = np.clip(np.searchsorted(source, at), 0, len(source) - 1)
        left = np.clip(right - 1, 0, len(source) - 1)
        nearest = np.where(np.abs(source[left] - at) <= np.abs(source[right] - at), source[left], source[right])
        carried[at, n] = confidence[nearest, n]
    return carried
