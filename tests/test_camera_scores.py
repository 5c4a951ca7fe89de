"""Camera-mode scores on hand-made detections: accuracy and swap runs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_cli import CMU, DATA, run_cli

from service.evaluation.camera_scores import camera_scores
from service.io.recording import LabeledTrajectories

F, N, C = 5, 3, 2
CALISCOPE = DATA / "multicam2d_caliscope_charuco" / "4_cam_recording" / "camera_array.toml"


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


def _seen_once(marker_detection: np.ndarray, frames: slice, markers: list[int]) -> None:
    """``markers`` seen by camera 1 only in ``frames`` (camera 0 misses them)."""
    for n in markers:
        marker_detection[frames, 0, n] = -1


def test_an_exchange_of_markers_seen_by_one_camera_is_wrong_labels_as_well_as_swaps():
    """Accuracy counted only markers seen twice, swaps every labeled one: per-camera's exchange
    of two one-view markers read 100 % with 2 swaps (85_02 through caliscope's rig)."""
    marker_detection, truth, result = _labeling(_own_views())
    _seen_once(marker_detection, slice(2, 4), [0, 1])
    views = _own_views()
    views[2:4, :2, 0] = -1  # frames 2-3: markers 0 and 1 seen in camera 1 only ...
    views[2:4, 0, 1], views[2:4, 1, 1] = 1, 0  # ... and labeled from each other's detection
    scores = camera_scores(marker_detection, truth, result, views)
    assert scores.swaps == 2
    assert scores.marker_frames == (F - 1) * N  # the four one-view labels are scored
    assert scores.label_accuracy == pytest.approx(1 - 4 / ((F - 1) * N))


def test_a_marker_seen_by_one_camera_is_scored_when_labeled_and_not_missed_when_not():
    marker_detection, truth, result = _labeling(_own_views())
    _seen_once(marker_detection, slice(2, 4), [0])
    views = _own_views()
    views[2:4, 0, 0] = -1  # labeled rightly from the one view that sees it
    scores = camera_scores(marker_detection, truth, result, views)
    assert scores.label_accuracy == 1.0 and scores.marker_frames == (F - 1) * N and scores.swaps == 0
    views[2:4, 0, :] = -1  # left unlabeled (no 3D point: joint-3d cannot label it): no miss
    scores = camera_scores(marker_detection, truth, result, views)
    assert scores.label_accuracy == 1.0 and scores.marker_frames == (F - 1) * N - 2


@pytest.mark.skipif(not CMU.exists(), reason="needs ../shared/data (CMU 85_02)")
def test_eval_in_camera_mode_scores_its_swaps_in_its_accuracy(tmp_path):
    """The repro: per-camera through caliscope's 4 webcams; 2 swaps beside 100 % at 100 frames.
    200 frames: since a marker back from a gap takes its segment's motion (2026-12-03) the
    first 100 have no swap left (99.44 %), and the check needs one (3 at 200, 95.96 %)."""
    scenario = tmp_path / "cam2.toml"
    scenario.write_text(f'mode = "cameras"\ncalibration = "{CALISCOPE}"\nassociation = "per-camera"\nframes = 200\n')
    result = run_cli("-q", "eval", CMU, "--scenario", scenario, "--json")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["swaps"] > 0 and summary["label_accuracy"] < 1.0
