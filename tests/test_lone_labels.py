"""Lone labels (one frame seen amid an occlusion) are reported no surer than lone labels are
right: the window prices them by a drifted prediction alone and calls them sure."""

import json
from pathlib import Path

import numpy as np
import pytest
from test_cli import run_cli

from formulations.confidence.calibration import LABEL_CALIBRATION
from formulations.confidence.lone import lone_labels
from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.evaluation.scene import generate_scene
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.reported import LONE_CONFIDENCE, reported
from service.labeling.stats import reported_doubtful

MARKER, FLICKER, HIDDEN = 3, 35, slice(20, 51)


def _lone_by_loop(labeled: np.ndarray) -> np.ndarray:
    frames, markers = labeled.shape
    out = np.zeros_like(labeled)
    for f in range(1, frames):
        for n in range(markers):
            before = labeled[f - 1, n]
            after = f + 1 < frames and labeled[f + 1, n]
            out[f, n] = labeled[f, n] and not before and not after
    return out


@pytest.mark.parametrize("seed", range(5))
def test_lone_labels_are_those_with_no_label_the_frame_before_nor_after(seed: int) -> None:
    labeled = np.random.default_rng(seed).random((40, 6)) < 0.4
    np.testing.assert_array_equal(lone_labels(labeled), _lone_by_loop(labeled))


def test_a_lone_label_is_reported_doubtful_and_a_label_in_a_run_is_not() -> None:
    positions = np.zeros((6, 2, 3))
    positions[[0, 2, 4], 0] = np.nan  # marker 0 seen alone in frames 1, 3 and 5 (the last)
    positions[[2, 3], 1] = np.nan  # marker 1 seen in runs
    raw = np.full((6, 2), 0.97)  # sure by the window's margins
    labels = LabeledTrajectories(["a", "b"], positions, ~np.isfinite(positions).all(axis=2), 100.0, confidence=raw.copy())
    confidence = reported(labels).confidence
    assert (LABEL_CALIBRATION(raw) > LONE_CONFIDENCE).all()  # calibrated alone, every label looked sure
    np.testing.assert_allclose(confidence[[1, 3, 5], 0], LONE_CONFIDENCE)
    np.testing.assert_allclose(confidence[[1, 4, 5], 1], LABEL_CALIBRATION(raw[[1, 4, 5], 1]))
    assert (confidence[0] == 1.0).all()  # the user's frame
    expected = [[False, False]] + [[True, False], [False, False]] * 2 + [[True, False]]
    assert reported_doubtful(confidence, labels.occluded).tolist() == expected


def _flickering() -> tuple[Capture, np.ndarray]:
    """A walking figure whose marker ``MARKER`` is unseen over ``HIDDEN`` but for frame ``FLICKER``; the truth."""
    truth = generate_scene(n_frames=80, seed=1)
    rng = np.random.default_rng(1)
    points = []
    for f, frame in enumerate(truth.positions):
        seen = np.ones(len(frame), bool)
        seen[MARKER] = not (HIDDEN.start <= f < HIDDEN.stop) or f == FLICKER
        points.append(rng.permutation(frame[seen] + rng.normal(0.0, 0.5, (int(seen.sum()), 3))))
    return Capture(list(truth.names), truth.positions[0], truth.rate, points=points), truth.positions


def test_a_marker_seen_for_one_frame_amid_an_occlusion_is_labeled_and_reported_doubtful() -> None:
    capture, truth = _flickering()
    result, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    taken = result.positions[FLICKER, MARKER]
    assert np.linalg.norm(taken - truth[FLICKER, MARKER]) < 5.0  # its own point, taken
    assert result.confidence[FLICKER, MARKER] <= LONE_CONFIDENCE
    assert reported_doubtful(result.confidence, result.occluded)[FLICKER, MARKER]
    neighbours = [n for n in range(len(capture.names)) if n != MARKER]
    assert not reported_doubtful(result.confidence, result.occluded)[FLICKER, neighbours].any()


def test_track_json_lists_the_lone_labels(tmp_path: Path) -> None:
    capture, _ = _flickering()
    source = tmp_path / "capture.json"
    source.write_text(CaptureDocument.of(capture, LabelingOptions(window=10)).model_dump_json())
    done = run_cli("track", source, "--out", tmp_path / "labeled.csv", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["lone_labels"] == {capture.names[MARKER]: [FLICKER]}
