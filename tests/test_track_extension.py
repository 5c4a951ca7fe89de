"""Tracks extended over unclaimed points (``markers.track_extension``, ``labeling.extension``)."""

from __future__ import annotations

import numpy as np

from formulations.markers.track_extension import MIN_TRIPLES, extend_tracks
from service.io.recording import LabeledTrajectories
from service.labeling.extension import extended

FRAMES = 40


def _walk(seed: int = 0) -> np.ndarray:
    """``(FRAMES, 2, 3)`` two markers 300 mm apart on smooth paths with 0.5 mm noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(FRAMES)[:, None]
    a = np.column_stack([10.0 * t[:, 0], 200 * np.sin(t[:, 0] / 15), np.zeros(FRAMES)])
    truth = np.stack([a, a + [0.0, 300.0, 0.0]], axis=1)
    return truth + rng.normal(0, 0.5, truth.shape)


def _frames(truth: np.ndarray, ghosts: list[np.ndarray] | None = None) -> list[np.ndarray]:
    """Per frame the markers' points (marker k at index k), then any ghosts."""
    return [np.vstack([truth[f]] + ([ghosts[f]] if ghosts is not None else [])) for f in range(FRAMES)]


def test_a_gap_with_its_points_in_view_is_labeled_from_both_ends() -> None:
    truth = _walk()
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[15:25, 0] = -1  # the windows left marker 0 occluded with its point in view
    index[:6, 1] = -1  # and marker 1 unnamed at the start
    out = extend_tracks(_frames(truth), index)
    assert (out == np.arange(2)).all()


def test_far_ghosts_are_left_and_a_missing_point_stops_the_walk() -> None:
    truth = _walk(1)
    rng = np.random.default_rng(2)
    ghosts = [truth[f, :1] + rng.uniform(60, 200, (1, 3)) for f in range(FRAMES)]
    points = _frames(truth, ghosts)
    points[20] = np.vstack([truth[20, 1:], ghosts[20]])  # marker 0's point is gone in frame 20
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[20] = [-1, 0]
    index[16:25, 0] = -1
    out = extend_tracks(points, index)
    assert (out[16:20, 0] == 0).all() and (out[21:25, 0] == 0).all()  # walked in from both sides
    assert out[20, 0] == -1  # nothing of it there: no ghost taken


def test_two_free_points_in_the_gate_are_left() -> None:
    truth = _walk(3)
    twin = [truth[f, :1] + [2.0, 0.0, 0.0] for f in range(FRAMES)]  # a second point 2 mm off
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[30:, 0] = -1
    out = extend_tracks(_frames(truth, twin), index)
    assert (out[30:, 0] == -1).all()


def test_a_point_two_ends_want_goes_to_neither() -> None:
    truth = _walk(4)
    truth[:, 1] = truth[:, 0] + [0.0, 0.0, 0.0]  # two markers on one path, one labeled each side
    points = [truth[f, :1] for f in range(FRAMES)]
    index = np.full((FRAMES, 2), -1)
    index[:20, 0] = 0
    index[21:, 1] = 0
    out = extend_tracks(points, index)
    assert out[20].tolist() == [-1, -1]


def test_a_marker_with_too_few_triples_is_not_extended() -> None:
    truth = _walk(5)
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[MIN_TRIPLES + 1 :, 0] = -1  # MIN_TRIPLES - 1 triples labeled
    out = extend_tracks(_frames(truth), index)
    assert (out[MIN_TRIPLES + 1 :, 0] == -1).all()
    assert (out[:, 1] == 1).all()


def test_extended_labels_carry_the_nearest_window_confidence() -> None:
    truth = _walk(6)
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[15:25, 0] = -1
    confidence = np.full((FRAMES, 2), 0.9)
    confidence[:15, 0], confidence[25:, 0] = 0.3, 0.8
    positions = np.where((index >= 0)[..., None], truth, np.nan)
    labels = LabeledTrajectories(["a", "b"], positions, index < 0, 100.0, point_index=index,
                                 filled=np.where((index < 0)[..., None], 0.0, np.nan), confidence=confidence)
    out = extended(labels, _frames(truth), FRAMES)
    assert not out.occluded.any() and np.allclose(out.positions, truth)
    assert np.isnan(out.filled).all()  # a labeled sample has no fill
    assert out.confidence[15:20, 0].tolist() == [0.3] * 5 and out.confidence[20:25, 0].tolist() == [0.8] * 5


def test_frames_no_window_labeled_stay_unlabeled() -> None:
    """A partial result (a job stopped after some windows) is not extended past them."""
    truth = _walk(7)
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[25:] = -1  # the windows labeled frames 0-24
    positions = np.where((index >= 0)[..., None], truth, np.nan)
    labels = LabeledTrajectories(["a", "b"], positions, index < 0, 100.0, point_index=index,
                                 confidence=np.ones((FRAMES, 2)))
    assert (extended(labels, _frames(truth), 25).point_index[25:] == -1).all()
    assert (extended(labels, _frames(truth), FRAMES).point_index[25:] >= 0).all()


def test_a_gap_where_the_limb_accelerates_is_walked_from_its_fast_end() -> None:
    """A serve's arm: slow for 30 frames (g_n from those residuals is ~6 mm), then 10 mm per
    frame^2. The windows lost it over the strike; the end labeled in the strike walks back."""
    truth = _walk(6)
    t = np.arange(FRAMES, dtype=float)
    truth[:, 0, 0] = 2.0 * t + 5.0 * np.maximum(t - 30, 0) ** 2 + np.random.default_rng(7).normal(0, 0.5, FRAMES)
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[31:35, 0] = -1
    ghosts = [truth[f, :1] + [0.0, 45.0, 0.0] for f in range(FRAMES)]  # beyond 3 residuals of the strike
    out = extend_tracks(_frames(truth, ghosts), index)
    assert (out[31:35, 0] == 0).all()


def test_one_wrong_label_at_an_end_does_not_open_its_gate() -> None:
    """Marker 0's last label before its gap is a ghost 30 mm off. That residual alone would open
    the gate to 90 mm and take a point 20 mm from where the jump heads; the least of the last
    three residuals is the calm motion's, and the point is left."""
    truth = _walk(8)
    jump = truth[29, 0] + [0.0, 30.0, 0.0]
    points = _frames(truth)
    points[29] = np.vstack([truth[29], jump])
    points[30:] = [truth[f, 1:] for f in range(30, FRAMES)]  # marker 0's own points gone from 30
    points[30] = np.vstack([truth[30, 1:], 2 * jump - truth[28, 0] + [20.0, 0.0, 0.0]])
    index = np.tile(np.arange(2), (FRAMES, 1))
    index[29, 0] = 2
    index[30:] = [-1, 0]
    out = extend_tracks(points, index)
    assert out[30, 0] == -1
