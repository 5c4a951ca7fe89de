"""The tracked boxes between windows: Jiang's object list with its templates (Sec. II-E).

Each object carries a constant-velocity Kalman state (``kalman``) at the window's template
frame t0: after a window its state is filtered through the boxes its path took and
predicted through the frames it was occluded, so the prediction of the next window starts
from the object's own last box and its velocity over its whole track, with an uncertainty
that grows with every frame since the object was last seen, whichever window that was in.
It also keeps the frame it was last seen and, when frames are given, its template histogram.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


@dataclass(frozen=True)
class BoxObjects:
    """The objects alive at a window's template frame.

    Attributes:
        ident: ``(N,)`` identity of each object (1, 2, ... in order of birth).
        mean: ``(N, 8)`` Kalman state at the template frame (``kalman``).
        covariance: ``(N, 8, 8)`` its covariance.
        last_seen: ``(N,)`` frame each object last took a box (a newborn: the frame before its first).
        histogram: ``(N, H)`` template histograms, or None without frames.
    """

    ident: Ints
    mean: Array
    covariance: Array
    last_seen: Ints
    histogram: Array | None

    @property
    def n_objects(self) -> int:
        return len(self.ident)

    @property
    def box(self) -> Array:
        """``(N, 4)`` corners at the template frame (predicted where the object was not seen there)."""
        return kalman.box_corners(self.mean[:, :4])

    def forecast(self, steps: int) -> tuple[Array, Array]:
        """Predicted measurements ``(N, steps, 4)`` and their covariances ``(N, steps, 4, 4)``, 1..steps frames ahead."""
        mean, covariance = self.mean, self.covariance
        z, s = [], []
        for _ in range(steps):
            mean, covariance = kalman.predict(mean, covariance)
            predicted, spread = kalman.innovation(mean, covariance)
            z.append(predicted)
            s.append(spread)
        n = self.n_objects
        return np.stack(z, axis=1).reshape(n, steps, 4), np.stack(s, axis=1).reshape(n, steps, 4, 4)

    def subset(self, keep: NDArray[np.bool_]) -> BoxObjects:
        hist = None if self.histogram is None else self.histogram[keep]
        return BoxObjects(self.ident[keep], self.mean[keep], self.covariance[keep], self.last_seen[keep], hist)

    @staticmethod
    def empty(bins: int | None) -> BoxObjects:
        hist = None if bins is None else np.zeros((0, bins))
        return BoxObjects(np.zeros(0, int), np.zeros((0, 8)), np.zeros((0, 8, 8)), np.zeros(0, int), hist)

    def joined(self, other: BoxObjects) -> BoxObjects:
        hist = None if self.histogram is None or other.histogram is None else np.vstack([self.histogram, other.histogram])
        return BoxObjects(
            np.r_[self.ident, other.ident], np.vstack([self.mean, other.mean]),
            np.concatenate([self.covariance, other.covariance]), np.r_[self.last_seen, other.last_seen], hist,
        )


def fitted_velocity(frames: Ints, boxes: Array) -> Array:
    """Least-squares corner velocity of one object's seen boxes (0 with fewer than 2 frames)."""
    if len(frames) < 2:
        return np.zeros(4)
    t = frames - frames.mean()
    result: Array = (t[:, None] * (boxes - boxes.mean(axis=0))).sum(axis=0) / (t * t).sum()
    return result


def advance(objects: BoxObjects, template_frame: int, taken: Ints, boxes: Array, histograms: Array | None,
            histogram_rate: float) -> BoxObjects:
    """The objects at the window's last frame, filtered through the boxes their paths took.

    Args:
        objects: The objects at the template frame.
        template_frame: t0.
        taken: ``(N, M)`` row into ``boxes`` of the box each object took in frames t0+1..t0+M, -1 occluded.
        boxes: Corners of the detections ``taken`` points into.
        histograms: Their histograms (None without frames): a template histogram moves
            towards the mean of the taken ones at ``histogram_rate``.
        histogram_rate: See ``histograms``.
    """
    mean, covariance, last = objects.mean, objects.covariance, objects.last_seen.copy()
    for m in range(taken.shape[1]):
        mean, covariance = kalman.predict(mean, covariance)
        seen = taken[:, m] >= 0
        last[seen] = template_frame + m + 1
        if seen.any():
            mean, covariance = mean.copy(), covariance.copy()
            mean[seen], covariance[seen] = kalman.update(mean[seen], covariance[seen],
                                                         kalman.measurement(boxes[taken[seen, m]]))
    hist = None if objects.histogram is None else objects.histogram.copy()
    for n in range(objects.n_objects):
        rows = taken[n][taken[n] >= 0]
        if hist is not None and histograms is not None and len(rows):
            hist[n] = (1.0 - histogram_rate) * hist[n] + histogram_rate * histograms[rows].mean(axis=0)
    return BoxObjects(objects.ident, mean, covariance, last, hist)
