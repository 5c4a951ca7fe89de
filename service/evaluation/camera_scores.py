"""Scores of a camera-mode labeling against the simulator's truth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from service.evaluation.scores import run_onsets
from service.io.recording import LabeledTrajectories


@dataclass(frozen=True)
class CameraScores:
    """Scores of a camera-mode labeling against the simulator's truth.

    Both ``label_accuracy`` and ``swaps`` count the scored marker-frames (frame 0 excluded):
    those of a marker seen by two or more cameras (a 3D point exists: left unlabeled, it is a
    miss), and any other the labeling labeled (a label it wrote, from one view or from another
    marker's detections, right or wrong). Over the first set alone, an exchange of two markers
    each seen by one camera counted 2 swaps beside an accuracy of 100 %.

    Attributes:
        label_accuracy: Over the scored marker-frames: the marker used one detection or
            more, all of them that marker's.
        rmse_mm: 3D error of the correctly labeled, triangulated markers (two views or more).
        filled_rmse_mm: 3D error of the predicted positions filled in where a marker was
            occluded (seen by fewer than two cameras, or not labeled).
        marker_frames: Marker-frames scored.
        swaps: Runs of consecutive scored frames in which a marker used only detections of
            one other marker (none of its own), counted once per run and per marker, as in
            cloud mode (a two-marker exchange counts 2).
        single_view_rmse_mm: 3D error of the correctly labeled markers located from one
            view (per-camera only: the point of its ray nearest the prediction); NaN when
            there are none, as always with joint-3d, whose points have two views or more.
    """

    label_accuracy: float
    rmse_mm: float
    filled_rmse_mm: float
    marker_frames: int
    swaps: int
    single_view_rmse_mm: float = float("nan")


def camera_scores(
    marker_detection: np.ndarray, truth: np.ndarray, result: LabeledTrajectories, views: np.ndarray
) -> CameraScores:
    """Score a labeling by the detections each marker used, whatever the association.

    Args:
        marker_detection: ``(F, C, N)`` detection index each marker produced, -1 unseen.
        truth: ``(F, N, 3)`` true positions (mm).
        result: The labeling.
        views: ``(F, N, C)`` detection each labeled marker used in each camera, -1 none
            (``CaptureLabeling.views``, either association).
    """
    seen_twice = (marker_detection >= 0).sum(axis=1) >= 2  # (F, N)
    expected = marker_detection.transpose(0, 2, 1)  # (F, N, C)
    used = views >= 0
    scored = seen_twice | used.any(axis=2)  # see CameraScores
    scored[0] = False  # frame 0 is the user's
    correct = ((~used) | (views == expected)).all(axis=2) & used.any(axis=2)
    # the RMSEs keep to markers seen twice, as measured in docs/cameras.md
    located = correct & seen_twice & scored
    error = np.linalg.norm(result.positions - truth, axis=2)
    n_views = used.sum(axis=2)
    filled_error = np.linalg.norm(result.filled - truth, axis=2)
    filled_error = filled_error[result.occluded & np.isfinite(filled_error)]
    return CameraScores(
        label_accuracy=float((correct & scored).sum() / max(scored.sum(), 1)),
        rmse_mm=_rms(error[located & (n_views >= 2)]), filled_rmse_mm=_rms(filled_error),
        marker_frames=int(scored.sum()), swaps=_swaps(expected, views, scored),
        single_view_rmse_mm=_rms(error[located & (n_views == 1)]),
    )


def _swaps(expected: np.ndarray, views: np.ndarray, scored: np.ndarray) -> int:
    """Swap runs (see ``CameraScores.swaps``) from ``(F, N, C)`` true and used detections,
    over the ``(F, N)`` marker-frames ``scored`` (those ``label_accuracy`` counts).

    ``holds[f, n, m]``: every view marker n used in frame f is marker m's detection there.
    """
    used = views >= 0
    holds = ((views[:, :, None, :] == expected[:, None, :, :]) | ~used[:, :, None, :]).all(axis=3)
    holds &= used.any(axis=2, keepdims=True)
    any_own = ((views == expected) & used).any(axis=2)  # a merged blob can be its own and another's
    other = holds.any(axis=2) & ~any_own & scored
    return run_onsets(other)


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if len(values) else float("nan")
