"""Identification of one unlabeled frame from a subject model (no labeled frame)."""

from __future__ import annotations

import numpy as np
import pytest
from test_subject_model import chain

from formulations.subject.fit import fit_subject
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify

FIT_FRAMES = 250  # the model learns on these; identification is tried on the frames after


def _subject(seed: int):
    names, positions, _ = chain(seed)
    model = fit_subject(names, positions[:FIT_FRAMES]).model
    geometry = ModelGeometry.of(model)
    columns = [names.index(n) for n in geometry.names]
    return geometry, positions[:, columns]


def _cloud(rng, truth: np.ndarray, missing: list[int], ghosts: int):
    """Shuffled points of the visible markers plus ghosts near the body; each point's marker (-1 ghost)."""
    keep = np.setdiff1d(np.arange(len(truth)), missing)
    spurious = truth[rng.integers(0, len(truth), ghosts)] + rng.normal(0, 200, (ghosts, 3))
    points = np.concatenate([truth[keep], spurious])
    marker = np.concatenate([keep, np.full(ghosts, -1)])
    order = rng.permutation(len(points))
    return points[order], marker[order]


@pytest.mark.parametrize("seed", range(3))
def test_held_out_frames_are_named_right_with_ghosts_and_missing_markers(seed: int) -> None:
    geometry, truth = _subject(seed)
    rng = np.random.default_rng(seed)
    named = right = visible = 0
    for frame in range(FIT_FRAMES, 300, 5):
        missing = list(rng.choice(len(truth[frame]), 2, replace=False))
        points, marker = _cloud(rng, truth[frame], missing, ghosts=5)
        found = identify(geometry, points)
        took = found.point >= 0
        named += took.sum()
        right += (marker[found.point[took]] == np.flatnonzero(took)).sum()
        visible += len(truth[frame]) - 2
        assert np.all(found.residual[took] <= geometry.tolerance[took])
    assert right == named, "a named point belongs to another marker"
    assert named >= 0.95 * visible


def test_noise_free_frame_names_every_marker_and_its_residual_is_small() -> None:
    names, positions, _ = chain(5, frames=300)
    model = fit_subject(names, positions).model
    geometry = ModelGeometry.of(model)
    truth = positions[280, [names.index(n) for n in geometry.names]]
    points, marker = _cloud(np.random.default_rng(0), truth, [], ghosts=0)
    found = identify(geometry, points)
    assert np.array_equal(marker[found.point], np.arange(len(truth)))
    assert np.nanmax(found.residual) < 10.0


def test_a_point_far_from_where_the_model_puts_its_marker_stays_unnamed() -> None:
    geometry, truth = _subject(1)
    frame = truth[260].copy()
    moved = int(geometry.segments[0].markers[0])
    frame[moved] += 3 * geometry.tolerance[moved]
    found = identify(geometry, frame)
    assert found.point[moved] == -1
    others = np.setdiff1d(np.arange(len(frame)), [moved])
    assert np.array_equal(found.point[others][found.point[others] >= 0], others[found.point[others] >= 0])


def test_a_segment_with_two_visible_markers_is_placed_about_its_joint() -> None:
    geometry, truth = _subject(2)
    end = geometry.segments[-1]  # the last segment of the chain: one joint only
    hidden = [int(end.markers[0]), int(end.markers[1])]
    frame = np.delete(truth[270], hidden, axis=0)
    kept = np.delete(np.arange(len(truth[270])), hidden)
    found = identify(geometry, frame)
    for m in end.markers[2:]:
        assert kept[found.point[m]] == m


def test_empty_and_tiny_frames_name_nothing() -> None:
    geometry, truth = _subject(0)
    assert not identify(geometry, np.zeros((0, 3))).named.any()
    assert not identify(geometry, truth[260, :2]).named.any()
