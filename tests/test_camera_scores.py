"""Camera-mode scores on hand-made detections: accuracy and swap runs."""

from __future__ import annotations

import numpy as np
import pytest

from service.evaluation.camera_scores import camera_scores
from service.io.recording import LabeledTrajectories

F, N, C = 5, 3, 2


def _labeling(views: np.ndarray) -> tuple[np.ndarray, np.ndarray, LabeledTrajectories]:
    """Marker n's detection is n in every camera, except a merged blob (markers 1 and 2) in camera 0."""
    marker_detection = np.tile(np.arange(N), (F, C, 1))
    marker_detection[:, 0, 2] = 1  # marker 2's projection merged into marker 1's blob in camera 0
    truth = np.zeros((F, N, 3))
    result = LabeledTrajectories(
        names=["a", "b", "c"], positions=np.zeros((F, N, 3)), occluded=(views < 0).all(axis=2), rate=100.0,
        filled=np.full((F, N, 3), np.nan),
    )
    return marker_detection, truth, result


def _own_views() -> np.ndarray:
    views = np.tile(np.arange(N)[:, None], (F, 1, C))
    views[:, 2, 0] = 1  # marker 2 rightly uses the merged blob in camera 0
    return views


def test_right_views_score_full_and_no_swaps():
    views = _own_views()
    scores = camera_scores(*_labeling(views), views)
    assert scores.label_accuracy == 1.0 and scores.swaps == 0


def test_an_exchange_held_over_frames_counts_two_swaps():
    views = _own_views()
    views[2:4, 0], views[2:4, 1] = 1, 0  # frames 2-3: markers 0 and 1 exchange all their views
    scores = camera_scores(*_labeling(views), views)
    assert scores.swaps == 2  # one run each, not one per frame
    assert scores.label_accuracy == pytest.approx(1 - 4 / ((F - 1) * N))


def test_sharing_a_merged_blob_is_not_a_swap_but_a_foreign_view_is_wrong():
    views = _own_views()
    views[3, 1, 1] = 2  # marker 1 keeps its blob in camera 0 but takes marker 2's detection in camera 1
    scores = camera_scores(*_labeling(views), views)
    assert scores.swaps == 0  # it still holds its own blob: not wholly another marker's
    assert scores.label_accuracy == pytest.approx(1 - 1 / ((F - 1) * N))
