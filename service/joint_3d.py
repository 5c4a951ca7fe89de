"""``joint-3d`` association: label triangulated cross-camera points with the window LP.

Each frame's detections are matched across cameras (``formulations.cross_camera``); the
resulting 3D points become an unlabeled cloud whose resources are the (camera, detection)
pairs each point uses, so two candidates sharing a detection conflict in the window LP.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any
from dataclasses import dataclass

import numpy as np

from formulations.cameras import Camera
from formulations.cross_camera import CrossCameraPoints, match_across_cameras
from service.recording import LabeledTrajectories, UnlabeledCloud


@dataclass(frozen=True)
class CameraScores:
    """Scores of a camera-mode labeling against the simulator's truth.

    Attributes:
        label_accuracy: Over marker-frames seen by two or more cameras (frame 0 excluded):
            the marker took a point all of whose detections are that marker's.
        rmse_mm: 3D error of the correctly labeled points.
        filled_rmse_mm: 3D error of the predicted positions filled in where a marker was
            occluded (seen by fewer than two cameras, or not labeled).
        marker_frames: Marker-frames counted.
    """

    label_accuracy: float
    rmse_mm: float
    filled_rmse_mm: float
    marker_frames: int


class LazyFrames(Sequence):
    """A per-frame sequence whose items are computed when first asked for, then kept."""

    def __init__(self, n_frames: int, compute: Callable[[int], Any]) -> None:
        self._n, self._compute, self._done = n_frames, compute, {}

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, f):  # type: ignore[override]
        if isinstance(f, slice):
            return [self[k] for k in range(*f.indices(self._n))]
        if not -self._n <= f < self._n:
            raise IndexError(f)
        f %= self._n
        if f not in self._done:
            self._done[f] = self._compute(f)
        return self._done[f]


def cross_camera_cloud(
    cameras: list[Camera], detections: list[list[np.ndarray]], rate: float,
    epipolar_px: float = 3.0, max_reprojection_px: float = 2.0,
) -> tuple[UnlabeledCloud, Sequence[CrossCameraPoints]]:
    """The cross-camera points of every frame as a cloud with detection resources.

    Frames are matched on demand: a long job labels (and reports) its first window without
    matching every frame first, and a resumed job matches only the frames it still needs.
    """

    def match(f: int) -> CrossCameraPoints:
        return match_across_cameras(cameras, detections[f], epipolar_px, max_reprojection_px)

    def resources(f: int):
        offsets = np.cumsum([0] + [len(d) for d in detections[f]])
        return matched[f].resources(offsets[:-1], int(offsets[-1]))

    n = len(detections)
    matched = LazyFrames(n, match)
    points = LazyFrames(n, lambda f: matched[f].points)
    return UnlabeledCloud(points=points, rate=rate, resources=LazyFrames(n, resources)), matched


def camera_scores(
    marker_detection: np.ndarray, truth: np.ndarray, result: LabeledTrajectories, matched: Sequence[CrossCameraPoints]
) -> CameraScores:
    """Score labels whose ``point_index`` indexes each frame's cross-camera points.

    Args:
        marker_detection: ``(F, C, N)`` detection index each marker produced, -1 unseen.
        truth: ``(F, N, 3)`` true positions (mm).
        result: The labeling.
        matched: The cross-camera points of every frame.
    """
    seen_twice = (marker_detection >= 0).sum(axis=1) >= 2  # (F, N)
    seen_twice[0] = False
    correct = np.zeros_like(seen_twice)
    for f, points in enumerate(matched):
        took = np.flatnonzero(result.point_index[f] >= 0)
        views = points.views[result.point_index[f, took]]  # (k, C)
        expected = marker_detection[f][:, took].T  # (k, C)
        agree = ((views < 0) | (views == expected)).all(axis=1) & (views >= 0).any(axis=1)
        correct[f, took] = agree
    counted = correct & seen_twice
    error = np.linalg.norm(result.positions - truth, axis=2)[counted]
    filled_error = np.linalg.norm(result.filled - truth, axis=2)
    filled_error = filled_error[result.occluded & np.isfinite(filled_error)]
    return CameraScores(
        label_accuracy=float(counted.sum() / max(seen_twice.sum(), 1)),
        rmse_mm=_rms(error), filled_rmse_mm=_rms(filled_error), marker_frames=int(seen_twice.sum()),
    )


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if len(values) else float("nan")
