"""Scores of a camera-mode labeling against the simulator's truth."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from formulations.cross_camera import CrossCameraPoints
from service.recording import LabeledTrajectories


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
