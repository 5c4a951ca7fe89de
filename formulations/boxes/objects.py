"""The tracked boxes between windows: Jiang's object list with its templates (Sec. II-E).

Each object keeps its last seen box (corners), a velocity per frame, the frame it was last
seen, and, when frames are given, its template histogram. Its prediction for frame f is
constant-velocity extrapolation from the last seen box,

    p_n(f) = box_n + (f - last_seen_n) v_n,

(no Kalman filter: the window LP, not a filter, decides which detections are an object's).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


@dataclass(frozen=True)
class BoxObjects:
    """The objects alive at a window's template frame.

    Attributes:
        ident: ``(N,)`` identity of each object (1, 2, ... in order of birth).
        box: ``(N, 4)`` corners where each was last seen.
        velocity: ``(N, 4)`` corner displacement per frame.
        last_seen: ``(N,)`` frame of ``box``.
        histogram: ``(N, H)`` template histograms, or None without frames.
    """

    ident: Ints
    box: Array
    velocity: Array
    last_seen: Ints
    histogram: Array | None

    @property
    def n_objects(self) -> int:
        return len(self.ident)

    def predict(self, frames: Ints) -> Array:
        """``(N, F, 4)`` predicted corners in each of ``frames``."""
        gap = (np.asarray(frames)[None, :] - self.last_seen[:, None]).astype(float)
        result: Array = self.box[:, None, :] + gap[:, :, None] * self.velocity[:, None, :]
        return result

    def subset(self, keep: NDArray[np.bool_]) -> BoxObjects:
        hist = None if self.histogram is None else self.histogram[keep]
        return BoxObjects(self.ident[keep], self.box[keep], self.velocity[keep], self.last_seen[keep], hist)

    @staticmethod
    def empty(bins: int | None) -> BoxObjects:
        hist = None if bins is None else np.zeros((0, bins))
        return BoxObjects(np.zeros(0, int), np.zeros((0, 4)), np.zeros((0, 4)), np.zeros(0, int), hist)

    def joined(self, other: BoxObjects) -> BoxObjects:
        hist = None if self.histogram is None or other.histogram is None else np.vstack([self.histogram, other.histogram])
        return BoxObjects(
            np.r_[self.ident, other.ident], np.vstack([self.box, other.box]), np.vstack([self.velocity, other.velocity]),
            np.r_[self.last_seen, other.last_seen], hist,
        )


def fitted_velocity(frames: Ints, boxes: Array) -> Array:
    """Least-squares corner velocity of one object's seen boxes (0 with fewer than 2 frames)."""
    if len(frames) < 2:
        return np.zeros(4)
    t = frames - frames.mean()
    result: Array = (t[:, None] * (boxes - boxes.mean(axis=0))).sum(axis=0) / (t * t).sum()
    return result


def advance(
    objects: BoxObjects, seen_frames: list[Ints], seen_boxes: list[Array], seen_histograms: list[Array] | None,
    smoothing: float, histogram_rate: float,
) -> BoxObjects:
    """The objects after a window: last seen box, velocity and template updated from the boxes each took.

    The new velocity is ``smoothing`` times the old plus the rest times the least-squares
    fit over the window's seen boxes and the previous last seen box; the template
    histogram moves towards the mean of the taken ones at ``histogram_rate``.
    """
    box, velocity, last = objects.box.copy(), objects.velocity.copy(), objects.last_seen.copy()
    hist = None if objects.histogram is None else objects.histogram.copy()
    for n in range(objects.n_objects):
        if len(seen_frames[n]) == 0:
            continue
        frames = np.r_[objects.last_seen[n], seen_frames[n]]
        boxes = np.vstack([objects.box[n], seen_boxes[n]])
        velocity[n] = smoothing * velocity[n] + (1.0 - smoothing) * fitted_velocity(frames, boxes)
        box[n], last[n] = seen_boxes[n][-1], seen_frames[n][-1]
        if hist is not None and seen_histograms is not None:
            hist[n] = (1.0 - histogram_rate) * hist[n] + histogram_rate * seen_histograms[n].mean(axis=0)
    return BoxObjects(objects.ident, box, velocity, last, hist)
