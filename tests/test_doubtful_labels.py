"""Doubtful labels (issue 13, item 5): labels whose confidence is below the threshold, a
take's share of them, the warning, and how they are scored against the truth."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from formulations.confidence.calibration import LABEL_CALIBRATION
from service.cli.report import warn_doubtful
from service.evaluation.doubt_scores import doubt_counts, doubt_scores
from service.evaluation.scenario import Scenario
from service.evaluation.simulated import SimulatedCapture
from service.io.formats import read_labeled
from service.io.formats.c3d import write_c3d
from service.io.formats.csv import read_csv_labeled
from service.io.recording import LabeledTrajectories, Recording, UnlabeledCloud
from service.labeling.confidence import carried, last_labeled
from service.labeling.stats import (
    DOUBTFUL_BELOW,
    DOUBTFUL_WARNING,
    doubtful_fraction,
    doubtful_labels,
    reacquisitions,
    reported_doubtful,
)

REPO = Path(__file__).resolve().parents[1]
CMU = REPO.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def test_doubtful_labels_are_seen_samples_below_the_threshold() -> None:
    confidence = np.array([[1.0, 0.2], [DOUBTFUL_BELOW - 1e-6, DOUBTFUL_BELOW], [0.1, 0.95]])
    occluded = np.array([[False, True], [False, False], [True, False]])
    assert doubtful_labels(confidence, occluded).tolist() == [[False, False], [True, False], [False, False]]
    # a result's confidences are calibrated: its doubtful labels are those under the same map
    reported = LABEL_CALIBRATION(confidence)
    assert reported_doubtful(reported, occluded).tolist() == doubtful_labels(confidence, occluded).tolist()
    assert doubtful_fraction(reported, occluded) == 1 / 4
    assert doubtful_fraction(reported, np.ones((3, 2), bool)) == 0.0
    assert reacquisitions(["a", "b"], np.array([[True, False], [False, False], [True, False], [False, False]])) == {
        "a": [1, 3]}


def test_confidence_is_carried_from_the_last_label_before_the_window() -> None:
    window = np.array([[0.9, 1.0], [0.5, 1.0], [0.8, 0.7]])
    template = np.array([0.5, 1.0])
    # Within the window a label is no surer than the track's least sure label before it.
    assert np.allclose(carried(window, template), [[0.45, 1.0], [0.25, 1.0], [0.25, 0.7]])
    occluded = np.array([[False, True], [True, True], [True, True]])
    assert np.allclose(last_labeled(window, occluded, np.array([0.3, 0.6])), [0.9, 0.6])


def test_a_doubtful_jump_keeps_the_labels_after_it_doubtful_but_not_an_unseen_frame() -> None:
    # Marker 0 jumps at frame 1 (margin 0.6), then the window is sure of following that point.
    # Marker 1 is unseen at frame 1: the confidence of "unseen" says nothing of its identity.
    window = np.array([[0.99, 0.99], [0.6, 0.2], [0.999, 0.98]])
    occluded = np.array([[False, False], [False, True], [False, False]])
    assert np.allclose(carried(window, np.ones(2), occluded), [[0.99, 0.99], [0.6, 0.2], [0.6, 0.98]])
    assert (carried(window, np.ones(2), occluded)[2] < DOUBTFUL_BELOW).tolist() == [True, False]


def _capture(point_marker: list[np.ndarray]) -> SimulatedCapture:
    rec = Recording(["a", "b"], np.zeros((len(point_marker), 2, 3)), 100.0)
    points = [np.zeros((len(p), 3)) for p in point_marker]
    return SimulatedCapture(UnlabeledCloud(points, 100.0), point_marker, rec, Recording(["a", "b"], np.zeros((1, 2, 3)), 100.0),
                            Scenario())


def test_doubt_scores_count_wrong_labels_flagged_doubtful() -> None:
    # frame 0 given; frame 1: a right, b on a ghost (wrong); frame 2: a and b swapped (both wrong); frame 3: b occluded
    capture = _capture([np.array([0, 1]), np.array([1, 0, -1]), np.array([0, 1]), np.array([0])])
    taken = np.array([[0, 1], [1, 2], [1, 0], [0, -1]])
    confidence = np.array([[1.0, 1.0], [0.995, 0.3], [0.2, 0.997], [0.5, 0.1]])  # calibrated, as a result holds
    result = LabeledTrajectories(["a", "b"], np.zeros((4, 2, 3)), taken < 0, 100.0, point_index=taken,
                                 confidence=confidence)
    scores = doubt_scores(capture, result)
    # labels: 5 (frame 1: 2, frame 2: 2, frame 3: 1); doubtful: b@1, a@2, a@3 -> 3/5; wrong: b@1, a@2, b@2 -> 2/3 flagged
    assert scores == {"doubtful_share": pytest.approx(3 / 5), "doubtful_recall": pytest.approx(2 / 3)}
    right = LabeledTrajectories(["a", "b"], np.zeros((4, 2, 3)), taken < 0, 100.0,
                                point_index=np.array([[0, 1], [1, 0], [0, 1], [0, -1]]), confidence=confidence)
    assert doubt_scores(capture, right)["doubtful_recall"] is None  # nothing wrong to find


def test_labels_on_jumped_marker_frames_are_left_out_of_the_doubt_counts() -> None:
    capture = _capture([np.array([0, 1]), np.array([1, 0]), np.array([0, 1])])
    taken = np.array([[0, 1], [0, 1], [0, 1]])  # frame 1: both on the other's point
    result = LabeledTrajectories(["a", "b"], np.zeros((3, 2, 3)), taken < 0, 100.0, point_index=taken,
                                 confidence=np.array([[1.0, 1.0], [0.3, 0.995], [0.995, 0.2]]))
    assert doubt_counts(capture, result).scores() == {"doubtful_share": 2 / 4, "doubtful_recall": 1 / 2}
    unknown = np.zeros((3, 2), bool)
    unknown[1, 1] = True  # the file's b is not known to be b there
    counts = doubt_counts(capture, result, unknown)
    assert (counts.labels, counts.doubtful, counts.wrong, counts.flagged) == (3, 2, 1, 1)


def test_a_label_on_a_point_the_file_names_wrongly_is_left_out_unless_its_own_point_is_seen() -> None:
    # frame 1: the file sees only b, at point 0, and its b is not known to be b there (it
    # jumped); a, which the file does not see, takes that point: neither right nor wrong.
    # frame 2: the file sees a at point 1 too, and a takes point 0 again: wrong either way.
    capture = _capture([np.array([0, 1]), np.array([1]), np.array([1, 0])])
    taken = np.array([[0, 1], [0, -1], [0, -1]])
    result = LabeledTrajectories(["a", "b"], np.zeros((3, 2, 3)), taken < 0, 100.0, point_index=taken,
                                 confidence=np.array([[1.0, 1.0], [0.999, 1.0], [0.999, 1.0]]))
    assert dataclasses.astuple(doubt_counts(capture, result)) == (2, 0, 2, 0)
    unknown = np.zeros((3, 2), bool)
    unknown[1:, 1] = True
    assert dataclasses.astuple(doubt_counts(capture, result, unknown)) == (1, 0, 1, 0)


def test_the_warning_is_one_stderr_line_above_the_share(capsys: pytest.CaptureFixture[str]) -> None:
    warn_doubtful(DOUBTFUL_WARNING + 0.001)
    warn_doubtful(DOUBTFUL_WARNING)
    warn_doubtful(None)
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.splitlines()) == 1
    assert captured.err.startswith(f"warning: {DOUBTFUL_WARNING + 0.001:.1%} of the labels are doubtful")
    assert captured.err.strip().endswith("markerflow track writes them with each label's confidence")  # eval's: no labels


def test_track_reports_the_doubtful_share_of_the_confidences_it_writes(tmp_path: Path) -> None:
    rec = read_labeled(CMU)
    write_c3d(tmp_path / "short.c3d", LabeledTrajectories(rec.names, rec.positions[:100],
                                                            np.isnan(rec.positions[:100]).any(axis=2), rec.rate))
    run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(tmp_path / "short.c3d"), "--out",
                          str(tmp_path / "x.csv"), "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    written = read_csv_labeled(tmp_path / "x.csv")
    assert written.confidence.shape == (100, rec.n_markers) and np.isfinite(written.confidence).all()
    assert summary["doubtful_fraction"] == pytest.approx(doubtful_fraction(written.confidence, written.occluded))
    assert ("warning" in run.stderr) == (summary["doubtful_fraction"] > DOUBTFUL_WARNING)
