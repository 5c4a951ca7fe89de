"""Boxes per frame: what a detector hands in, and what the tracker hands back."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.boxes.occluded import occluded_boxes


@dataclass(frozen=True)
class BoxDetections:
    """Detections of one camera, frames numbered from 1 (MOTChallenge).

    Attributes:
        frame: ``(K,)`` frame number of each box, 1..n_frames.
        box: ``(K, 4)`` left, top, width, height in pixels.
        confidence: ``(K,)`` detector score (1 where unknown).
        n_frames: Length of the sequence (frames without any box count).
        image_size: ``(width, height)`` in pixels, or None when unknown.
    """

    frame: np.ndarray
    box: np.ndarray
    confidence: np.ndarray
    n_frames: int
    image_size: tuple[float, float] | None = None


@dataclass(frozen=True)
class BoxTracks:
    """Tracked boxes: ``BoxDetections`` plus an identity per box.

    Attributes:
        frame, box, confidence: As in ``BoxDetections`` (one row per tracked box).
        track_id: ``(K,)`` identity, 1, 2, ... in order of birth.
        n_frames: Length of the sequence.
        occluded: ``(K,)`` True where no detection was taken: the object was held occluded
            and its box is placed between its sightings (``with_occluded``; confidence 0).
    """

    frame: np.ndarray
    track_id: np.ndarray
    box: np.ndarray
    confidence: np.ndarray
    n_frames: int
    occluded: np.ndarray

    def with_occluded(self) -> BoxTracks:
        """These tracks plus each object's boxes in the frames it was held occluded between
        two sightings (``formulations.boxes.occluded``)."""
        seen = ~self.occluded
        frame, ident, box = occluded_boxes(self.frame[seen], self.track_id[seen], self.box[seen])
        return BoxTracks(
            frame=np.r_[self.frame[seen], frame], track_id=np.r_[self.track_id[seen], ident],
            box=np.vstack([self.box[seen], box]), confidence=np.r_[self.confidence[seen], np.zeros(len(frame))],
            n_frames=self.n_frames, occluded=np.r_[np.zeros(seen.sum(), bool), np.ones(len(frame), bool)],
        )
