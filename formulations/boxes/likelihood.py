"""The window's likelihood terms for boxes (``window.likelihood``): negative log-likelihoods in pixels.

A box is a point of the 4-D corner space (x1, y1, x2, y2); the map from (cx, cy, w, h)
has determinant 1, so a Kalman density in either is the same density. Against the box
being a false alarm of density lambda_FA (per pixel^4), with detection probability P_D:

    step, box j after box i on the path:  rho(|d(i, j)| / s) + 4 log s + 2 log 2 pi - log P_D + log lambda_FA + K
    reappear, box j after a gap:          rho(m_j) + log det S / 2 + 2 log 2 pi - log P_D + log lambda_FA + K
    occlusion:                            -log(1 - P_D) + K

d is the corner step off the object's velocity (in its heights: the window's locations),
s its sd (``kalman.step_variance`` at the size of box j, in pixels; in heights for d),
m_j the Mahalanobis distance of box j to the object's Kalman forecast for its frame with
innovation covariance S (wide after a long gap, whichever window the object was last seen
in), rho the step loss (``window.likelihood.step_loss``: a contaminated Gaussian) and K one shift keeping every cost >= 0.

P_D and lambda_FA are learned from the windows solved so far (``DetectionRates``): P_D the
share of object-frames a path took a box (Beta(18, 2) prior, clipped to [0.5, 0.99]), and
lambda_FA the detections per frame no object explained (at least ``MIN_CLUTTER``) over the
image area times the spread of box widths and heights (``clutter_volume``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman
from formulations.boxes.objects import BoxObjects
from formulations.window.likelihood import CandidateLikelihood, step_loss

Array = NDArray[np.float64]
Ints = NDArray[np.int_]

LOG_2PI_4D = 2.0 * np.log(2 * np.pi)
PRIOR_HITS, PRIOR_MISSES = 18.0, 2.0  # Beta prior on P_D: 0.9 from 20 pseudo object-frames
MIN_CLUTTER = 0.5  # false alarms per frame assumed even when every detection was explained


@dataclass(frozen=True)
class DetectionRates:
    """Counts from the windows solved so far, for P_D and lambda_FA (module doc).

    Attributes:
        hits: Object-frames whose path took a box.
        misses: Object-frames whose path went through an occlusion node.
        spare: Detections no object explained.
        frames: Frames counted.
    """

    hits: float = 0.0
    misses: float = 0.0
    spare: float = 0.0
    frames: float = 0.0

    @property
    def detection_probability(self) -> float:
        p = (self.hits + PRIOR_HITS) / (self.hits + self.misses + PRIOR_HITS + PRIOR_MISSES)
        return float(np.clip(p, 0.5, 0.99))

    @property
    def false_alarms_per_frame(self) -> float:
        return max(self.spare / self.frames if self.frames else 0.0, MIN_CLUTTER)

    def counted(self, hits: int, misses: int, spare: int, frames: int) -> DetectionRates:
        return replace(self, hits=self.hits + hits, misses=self.misses + misses, spare=self.spare + spare,
                       frames=self.frames + frames)


def clutter_volume(image: Array, boxes: Array) -> float:
    """Pixel^4 where a false alarm may lie: image area times the range of widths and heights (+1 px each)."""
    area = float(np.prod(np.maximum(image[2:] - image[:2], 1.0)))
    if len(boxes) == 0:
        return area
    size = boxes[:, 2:] - boxes[:, :2]
    return area * float(np.prod(size.max(axis=0) - size.min(axis=0) + 1.0))


def box_likelihood(
    objects: BoxObjects, rates: DetectionRates, log_clutter: float, predicted: Array, spread: Array,
    obj: Ints, step: Ints, z: Array,
) -> CandidateLikelihood:
    """The likelihood terms of every candidate.

    Args:
        objects: The objects at the template frame.
        rates: P_D and the false alarms per frame.
        log_clutter: log lambda_FA (per pixel^4).
        predicted, spread: ``(N, M, 4)``, ``(N, M, 4, 4)`` the objects' Kalman forecasts.
        obj, step: ``(C,)`` object and window frame 1..M of each candidate.
        z: ``(C, 4)`` the candidates as (cx, cy, w, h).
    """
    n, m = predicted.shape[:2]
    detection = rates.detection_probability
    base = LOG_2PI_4D - np.log(detection) + log_clutter
    unit = np.maximum(objects.mean[:, 3], 1.0)  # the window's locations are in these heights
    sigma_px = np.sqrt(kalman.step_variance(z[:, 2:], objects.covariance[obj, 4:, 4:], step.astype(float)))
    offset = 4.0 * np.log(sigma_px) + base
    s = spread[obj, step - 1]
    difference = z - predicted[obj, step - 1]
    distance = np.sqrt(np.einsum("ci,ci->c", difference, np.linalg.solve(s, difference[..., None])[..., 0]))
    reach = 0.5 * np.linalg.slogdet(s)[1] + base
    # K: the lowest cost an observation can have (its residual 0) is lifted to 0.
    shift = -float(min(offset.min(initial=0.0), reach.min(initial=0.0)))
    miss = np.full((n, m), -np.log1p(-detection) + shift)
    return CandidateLikelihood(step_sigma=sigma_px / unit[obj], step_offset=offset + shift,
                               reappear_cost=step_loss(distance) + reach + shift, miss_cost=miss)
