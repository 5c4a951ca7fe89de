"""The subject model during labeling: segment fill, prediction, recovery and layout pairs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_model_start import FIT, _cloud, _take

from formulations.markers.state import MarkerState
from formulations.subject.contradiction import contradicting
from formulations.subject.follow import follow_segments
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify
from formulations.subject.recover import recover
from formulations.subject.segment_fill import segment_fill
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses
from formulations.subject.start_state import model_start_state
from service.capture.capture import Capture, LabelingOptions
from service.capture.model_input import model_names, with_model
from service.labeling import model_start
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.model_start import ModelChain, segment_layout


def _held_out():
    names, positions, model = _take()
    order = [names.index(n) for n in model_names(model)]
    return model, ModelGeometry.of(model), positions[FIT:, order]


def test_an_occluded_marker_is_filled_where_its_segment_mates_carry_it() -> None:
    model, geometry, held = _held_out()
    window = held[:20].copy()
    gone = geometry.segments[1].markers[0]
    window[5:15, gone] = np.nan
    state = MarkerState.from_first_frame(window[0])
    filled = segment_fill(geometry, state, window, RIGID_WITHIN)
    mates = geometry.segments[1].markers[1:]
    for f in range(5, 15):  # brute force: the mates' Kabsch motion from frame 4, where it was last seen
        before, now = window[4, mates].mean(0), window[f, mates].mean(0)
        rotation, _ = Rotation.align_vectors(window[f, mates] - now, window[4, mates] - before)
        expected = rotation.apply(window[4, gone] - before) + now
        assert np.allclose(filled[f, gone], expected, atol=1e-6)
    assert np.isnan(filled[~np.isnan(window).any(axis=2)]).all()  # seen markers are not filled


def test_a_segment_with_too_few_markers_is_posed_through_its_joint() -> None:
    model, geometry, held = _held_out()
    frame = held[40].copy()
    child = geometry.segments[-1]
    hidden = child.markers[2:]
    frame[hidden] = np.nan  # two markers left: with the joint centre, three correspondences
    poses = segment_poses(geometry, frame[None])
    assert poses.posed[0].all()
    placed = poses.place(geometry)[0]
    assert np.linalg.norm(placed[hidden] - held[40, hidden], axis=1).max() < 25.0


def test_prediction_follows_only_segment_mates() -> None:
    model, geometry, held = _held_out()
    found = identify(geometry, held[0])
    state = model_start_state(geometry, found, held[0], lost_after=3)
    marker = geometry.segments[0].markers[0]
    state = replace(state, unseen=np.where(np.arange(len(held[0])) == marker, 1, state.unseen))
    followed = follow_segments(geometry, state)
    mates = geometry.segment_of[state.neighbours[marker]] == geometry.segment_of[marker]
    assert (followed.anchor_valid[marker] <= mates).all() and followed.anchor_valid[marker].sum() >= 3


def test_an_exchange_of_two_markers_on_a_segment_is_found_and_repaired() -> None:
    model, geometry, held = _held_out()
    frame = held[60]
    state = MarkerState.from_first_frame(frame)
    a, b = geometry.segments[2].markers[:2]
    swapped = frame.copy()
    swapped[[a, b]] = swapped[[b, a]]
    broken = replace(state, position=swapped)
    assert contradicting(geometry, swapped).tolist() == [s == 2 for s in range(len(geometry.segments))]
    assert not contradicting(geometry, frame).any()
    repaired, segments = recover(geometry, broken, frame, lambda: identify(geometry, frame))
    assert segments == [2]
    assert np.allclose(repaired.position[[a, b]], frame[[a, b]])


def test_labeling_repairs_an_exchange_carried_into_a_window() -> None:
    model, geometry, held = _held_out()
    absent = np.zeros(held.shape[:2], bool)
    frames, owner = _cloud(held, absent)
    capture = Capture(model_names(model), np.full((len(held[0]), 3), np.nan), 100.0, points=frames, model=model)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10))
    outcomes = []
    for outcome in labeling.windows():
        outcomes.append(outcome)
        if len(outcomes) == 3:
            break
    a, b = geometry.segments[1].markers[:2]
    state = outcomes[-1].state
    swapped = state.position.copy()
    swapped[[a, b]] = swapped[[b, a]]
    broken = replace(outcomes[-1], state=replace(state, position=swapped))
    repaired = labeling.windows(after=broken)
    for outcome in (next(repaired), next(repaired)):  # within a window or two
        first = outcome.stats.template + 1
        took = outcome.point_index
        right = [owner[first + m][took[m, k]] == k for m in range(len(took)) for k in (a, b) if took[m, k] >= 0]
    assert len(right) == 2 * len(took) and all(right)  # the second window holds both, rightly


def test_layout_pairs_are_segment_mates() -> None:
    model, geometry, held = _held_out()
    frames, _ = _cloud(held[:12], np.zeros(held[:12].shape[:2], bool))
    capture = Capture(model_names(model), np.full((len(held[0]), 3), np.nan), 100.0, points=frames, model=model)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10, layout_weight=1.0))
    problems = []
    list(labeling.windows(observer=lambda t, problem, s: problems.append(problem)))
    pairs = np.concatenate([p.layout_pairs for p in problems])
    assert len(pairs) and (geometry.segment_of[pairs[:, 0]] == geometry.segment_of[pairs[:, 1]]).all()
    problem = replace(problems[0], layout_pairs=np.zeros((0, 2), int), layout_weight=np.zeros(0))
    assert (segment_layout(problem, geometry.segment_of, 1.0).layout_weight == 1.0).all()


def test_a_labeled_first_frame_is_kept_with_a_model() -> None:
    model, geometry, held = _held_out()
    names = model_names(model)
    frames, owner = _cloud(held[:30], np.zeros(held[:30].shape[:2], bool))
    labeled = Capture(names[::-1], held[0, ::-1], 100.0, points=frames)
    capture = with_model(labeled, model, keep_labels=True)
    assert np.allclose(capture.first_frame, held[0])
    result, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    assert all((owner[f][result.point_index[f]] == np.arange(len(names))).all() for f in range(len(frames)))


def test_a_marker_carried_by_its_segment_follows_its_rotation_with_two_mates_seen() -> None:
    """Two seen mates fix no rotation about the line through them: the carried marker must
    also follow the other seen neighbours (mates only gave 24-31 mm here, a translation)."""
    model, geometry, held = _held_out()
    segment = geometry.segments[1].markers
    hidden, late = segment[:2], segment[2]
    for template in (30, 60, 90, 120):
        state = model_start_state(geometry, identify(geometry, held[0]), held[0], lost_after=3)
        for f in range(1, template + 1):
            seen = np.ones(len(held[f]), bool)
            seen[hidden] = f <= template - 5
            seen[late] = not template - 8 < f <= template - 3  # the anchor frame saw one mate only
            state = state.advance(held[f], seen)
        predicted = follow_segments(geometry, state).predict()
        assert np.linalg.norm(predicted[hidden] - held[template + 1, hidden], axis=1).max() < 15.0


def test_no_marker_is_acquired_from_a_reading_that_moves_a_seen_mate() -> None:
    model, geometry, held = _held_out()
    frame = held[50]
    found = identify(geometry, frame)
    state = model_start_state(geometry, found, frame, lost_after=3)
    segment = geometry.segments[2].markers
    unseen = segment[0]
    state = replace(state, unseen=np.where(np.arange(len(frame)) == unseen, 5, state.unseen))
    chain = ModelChain(inner=None, model=model, points=[frame])
    assert chain._acquired(state, frame, found).visible[unseen]  # a reading that agrees is acquired from
    turned = replace(found, point=found.point.copy())
    turned.point[segment[[1, 2]]] = found.point[segment[[2, 1]]]  # the reading exchanges two seen mates
    kept = chain._acquired(state, frame, turned)
    assert not kept.visible[unseen] and np.array_equal(kept.position, state.position)



def test_acquisition_searches_the_cloud_only_when_a_point_is_free(monkeypatch: pytest.MonkeyPatch) -> None:
    """A marker is acquired only on a point no seen marker holds: with its own point missing
    and every other point held there is nothing to name, and the model's search (most of a
    dense take's time with a model) is not run; with its point back it is acquired there."""
    model, geometry, held = _held_out()
    frame = held[50]
    state = model_start_state(geometry, identify(geometry, frame), frame, lost_after=3)
    unseen = geometry.segments[2].markers[0]
    state = replace(state, unseen=np.where(np.arange(len(frame)) == unseen, 5, state.unseen))
    chain = ModelChain(inner=None, model=model, points=[frame])
    searched: list[int] = []
    monkeypatch.setattr(model_start, "identify", lambda *args: searched.append(1) or identify(*args))
    without = np.delete(frame, unseen, axis=0)
    assert chain._acquired(state, without) is state and not searched
    acquired = chain._acquired(state, frame)
    assert searched and acquired.visible[unseen] and np.allclose(acquired.position[unseen], frame[unseen])


def test_a_segment_the_labels_contradict_gives_its_markers_their_nearest_neighbours() -> None:
    model, geometry, held = _held_out()
    found = identify(geometry, held[0])
    segment = geometry.segments[1]
    trusted = model_start_state(geometry, found, held[0], lost_after=3)
    doubted = model_start_state(geometry, found, held[0], lost_after=3, misfit=frozenset({segment.name}))
    k = trusted.neighbours.shape[1]
    position = doubted.position
    for marker in segment.markers:
        mates = set(segment.markers) - {marker}
        assert set(trusted.neighbours[marker, : len(mates)]) == mates  # segment-mates first
        gap = np.linalg.norm(position - position[marker], axis=1)
        gap[marker] = np.inf
        assert list(doubted.neighbours[marker]) == list(np.argsort(gap)[:k])  # the nearest, brute force
    other = geometry.segments[0].markers[0]
    assert (doubted.neighbours[other] == trusted.neighbours[other]).all()  # other segments keep their mates
