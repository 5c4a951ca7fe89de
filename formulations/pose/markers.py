"""Markers as weighting functions: the model's markers against unlabeled 3D points or 2D detections.

Nobody says which point is which marker, so the distance is a chamfer both ways: each model
marker to its nearest observation and each observation to its nearest marker, robustly,

    E = mean_k rho(min_j |m_k - z_j|) + mean_j rho(min_k |m_k - z_j|),   rho(d) = log(1 + d^2 / sigma^2),

the first term pulling the body onto the data, the second keeping it from leaving data
unexplained; rho (Cauchy) keeps ghosts and markers lost by every camera from dominating. With
2D detections the same is done per camera in pixels on the projected markers and summed over
cameras (eq. 5). A fitted pose then places every marker, also those no camera saw
(``kinematics.marker_positions``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.cameras.rig import Rig
from formulations.pose.body import BodyModel
from formulations.pose.kinematics import Posed, marker_positions
from formulations.pose.rotation import Array


def chamfer(predicted: Array, observed: Array, sigma: float) -> Array:
    """``(N,)`` the module doc's E for ``(N, K, d)`` predicted markers and ``(J, d)`` observations."""
    squared = ((predicted[:, :, None, :] - observed[None, None]) ** 2).sum(axis=3)  # (N, K, J)
    nearest_marker = np.log1p(squared.min(axis=2) / sigma ** 2).mean(axis=1)
    nearest_point = np.log1p(squared.min(axis=1) / sigma ** 2).mean(axis=1)
    total: Array = nearest_marker + nearest_point
    return total


@dataclass(frozen=True)
class MarkerCloudMeasurement:
    """One frame's unlabeled 3D points ``(J, 3)`` (model unit) against ``model``'s markers; sigma in that unit."""

    model: BodyModel
    points: Array
    sigma: float

    @property
    def empty(self) -> bool:
        return len(self.points) == 0

    def energy(self, posed: Posed) -> Array:
        return chamfer(marker_positions(self.model, posed), self.points, self.sigma)


@dataclass(frozen=True)
class MarkerDetectionMeasurement:
    """One frame's 2D marker centroids per camera (a ``(J_c, 2)`` array each, pixels); sigma in pixels."""

    rig: Rig
    model: BodyModel
    detections: tuple[Array, ...]
    sigma: float = 3.0

    @property
    def empty(self) -> bool:
        return all(len(d) == 0 for d in self.detections)

    def energy(self, posed: Posed) -> Array:
        markers = marker_positions(self.model, posed)
        count = len(markers)
        total = np.zeros(count)
        for camera, detections in zip(self.rig.cameras, self.detections):
            if len(detections):
                pixels = camera.project(markers.reshape(-1, 3)).reshape(count, -1, 2)
                total += chamfer(pixels, detections, self.sigma)
        return total
