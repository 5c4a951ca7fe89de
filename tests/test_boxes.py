"""Box tracking: MOT files, box geometry against pixel counts, conflict sets, births and deaths, look-ahead."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.boxes import kalman
from formulations.boxes.candidates import box_window
from formulations.boxes.conflicts import ConflictRule
from formulations.boxes.costs import BoxCostModel
from formulations.boxes.geometry import corner_distance, corners, overlap_ratio
from formulations.boxes.lifecycle import Lifecycle
from formulations.boxes.objects import BoxObjects
from formulations.window.build import build_window
from service.boxes.detections import BoxDetections, BoxTracks
from service.boxes.mot_files import read_detections, read_rows, write_tracks
from service.boxes.track import track_boxes
from service.errors import InputError


def test_mot_result_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    tracks = BoxTracks(frame=rng.integers(1, 20, 30), track_id=rng.integers(1, 5, 30),
                       box=rng.uniform(1, 300, (30, 4)).round(2), confidence=np.ones(30), n_frames=20,
                       occluded=np.zeros(30, bool))
    path = tmp_path / "result.txt"
    write_tracks(path, tracks)
    rows = read_rows(path)
    order = np.lexsort((tracks.track_id, tracks.frame))
    assert rows.shape == (30, 10)
    np.testing.assert_array_equal(rows[:, 0], tracks.frame[order])
    np.testing.assert_array_equal(rows[:, 1], tracks.track_id[order])
    np.testing.assert_allclose(rows[:, 2:6], tracks.box[order], atol=0.006)
    again = read_detections(path)
    assert again.n_frames == tracks.frame.max() and len(again.frame) == 30


def _pixels(box):
    grid = np.zeros((60, 60), bool)
    x, y, w, h = box
    grid[y:y + h, x:x + w] = True
    return grid


def test_overlap_ratio_and_corner_distance_against_brute_force():
    rng = np.random.default_rng(1)
    for _ in range(50):
        a, b = rng.integers(0, 25, 2), rng.integers(0, 25, 2)
        sa, sb = rng.integers(1, 30, 2), rng.integers(1, 30, 2)
        box_a, box_b = (*a, *sa), (*b, *sb)
        pa, pb = _pixels(box_a), _pixels(box_b)
        expected = (pa & pb).sum() / (0.5 * (pa.sum() + pb.sum()))
        ca, cb = corners(np.array([box_a], float)), corners(np.array([box_b], float))
        assert overlap_ratio(ca, cb)[0, 0] == pytest.approx(expected)
        four = [(0, 1), (2, 1), (0, 3), (2, 3)]  # (x, y) index of each corner
        cityblock = sum(abs(ca[0, i] - cb[0, i]) + abs(ca[0, j] - cb[0, j]) for i, j in four)
        assert corner_distance(ca, cb)[0, 0] == pytest.approx(cityblock)


def test_conflict_sets_on_overlapping_boxes():
    # A, A shifted by 3 px (the same person twice), B beside A, C holding A at twice its area.
    ltwh = np.array([[100, 100, 40, 100], [103, 101, 40, 100], [150, 100, 40, 100], [90, 80, 60, 140]], float)
    boxes = corners(ltwh)
    rule = ConflictRule(corner_distance_max=0.5, overlap_ratio_min=0.85)
    expected = np.array([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], bool)
    np.testing.assert_array_equal(rule.conflicts(boxes), expected)
    assert not ConflictRule(corner_distance_max=0, overlap_ratio_min=2).conflicts(boxes)[0, 1]
    # In a window, object 0 at A and object 1 at A' share a conflict group; at B they do not.
    objects = BoxObjects(np.array([1, 2]), *kalman.start(kalman.measurement(boxes[[0, 2]])), np.array([0, 0]), None)
    window = box_window(objects, 0, 1, np.ones(4, int), boxes, None, BoxCostModel(), rule)
    problem, node_candidate = build_window(window.candidates, window.weights)
    det_of_node = np.where(node_candidate >= 0, np.append(window.detection, -1)[node_candidate], -1)
    groups = problem.conflict_groups.toarray().astype(bool)
    def shared(det_a, obj_a, det_b, obj_b):
        a = np.flatnonzero((det_of_node == det_a) & (problem.node_object == obj_a))
        b = np.flatnonzero((det_of_node == det_b) & (problem.node_object == obj_b))
        return bool(len(a) and len(b) and (groups[:, a[0]] & groups[:, b[0]]).any())
    assert shared(0, 0, 1, 1)
    assert not shared(0, 0, 2, 1)


def _one_person(frames, present, rng):
    rows = [(f, 100 + 3 * f + rng.normal(0, 1), 100.0, 40.0, 100.0) for f in frames if f in present]
    return rows


def test_birth_needs_min_hits_and_death_after_occlusion():
    rng = np.random.default_rng(2)
    frames = range(1, 61)
    rows = _one_person(frames, set(range(5, 20)), rng)  # a person seen in frames 5..19
    rows += [(30, 500.0, 300.0, 40.0, 100.0), (31, 501.0, 300.0, 40.0, 100.0)]  # a 2-frame blip
    rows += [(f, 100 + 3 * f, 100.0, 40.0, 100.0) for f in range(54, 61)]  # back after 34 frames unseen
    r = np.array(rows)
    detections = BoxDetections(r[:, 0].astype(int), r[:, 1:], np.ones(len(r)), 60, (640.0, 480.0))
    tracks = track_boxes(detections, "lp-l1", window=5, lifecycle=Lifecycle(min_hits=3, max_occluded=30)).tracks
    first = tracks.track_id[tracks.frame < 20]
    assert len(first) == 15 and len(set(first)) == 1  # born from its first box on, one identity
    assert not ((tracks.frame == 30) | (tracks.frame == 31)).any()  # the blip makes no object
    later = tracks.track_id[tracks.frame >= 54]
    assert len(later) == 7 and len(set(later)) == 1 and later[0] != first[0]  # died, a new object
    # A longer allowance is not enough: 34 frames unseen spread the prediction so wide that the
    # person is cheaper left to a new object; with a dearer occlusion the first object takes them
    # back. The window's costs decide here, not the return-against-newcomer test.
    alive = Lifecycle(max_occluded=40, returns_compete=False)
    assert len(set(track_boxes(detections, "lp-l1", window=5, lifecycle=alive).tracks.track_id)) == 2
    kept = track_boxes(detections, "lp-l1", window=5, lifecycle=alive, model=BoxCostModel(disappear=14.0)).tracks
    assert set(kept.track_id[kept.frame >= 54]) == {kept.track_id[0]}


def test_border_death_is_sooner():
    # Both last seen at 10; at the frame asked about, one is predicted across the right border.
    at = corners(np.array([[630, 100, 40, 100], [300, 100, 40, 100]], float))
    objects = BoxObjects(np.array([1, 2]), *kalman.start(kalman.measurement(at)), np.array([10, 10]), None)
    rule = Lifecycle(max_occluded=30, border_occluded=5)
    image = np.array([0, 0, 640.0, 480.0])
    np.testing.assert_array_equal(rule.leaving(objects, 16, image), [True, False])
    np.testing.assert_array_equal(rule.leaving(objects, 15, image), [False, False])
    np.testing.assert_array_equal(rule.leaving(objects, 41, image), [True, True])


def _crossing_scene(seed, frames=60, n=4, noise=3.0):
    """People walking left and right at different depths; one behind another is not detected."""
    rng = np.random.default_rng(seed)
    rows, who = [], []
    x0, y = rng.uniform(100, 500, n), rng.uniform(100, 140, n)
    v = rng.choice([-1, 1], n) * rng.uniform(2, 5, n)
    for f in range(1, frames + 1):
        xs = x0 + v * f
        for p in range(n):
            hidden = any(q != p and y[q] > y[p] and abs(xs[q] - xs[p]) < 25 for q in range(n))
            if hidden or rng.random() < 0.05:
                continue
            rows.append((f, *(np.array([xs[p], y[p], 40, 100]) + rng.normal(0, noise, 4))))
            who.append(p)
    r = np.array(rows)
    return BoxDetections(r[:, 0].astype(int), r[:, 1:], np.ones(len(r)), frames, (640.0, 480.0)), np.array(who)


def _identity_changes(detections, who, formulation, lifecycle=Lifecycle()):
    tracks = track_boxes(detections, formulation, window=10, lifecycle=lifecycle).tracks
    person = {(int(f), float(b[0])): w for f, b, w in zip(detections.frame, detections.box, who)}
    per_person: dict[int, list[int]] = {}
    for f, ident, box in sorted(zip(tracks.frame, tracks.track_id, tracks.box.tolist()), key=lambda t: t[0]):
        per_person.setdefault(person[(int(f), box[0])], []).append(int(ident))
    return sum(int((np.diff(ids) != 0).sum()) for ids in per_person.values())


def test_window_keeps_identities_where_frame_by_frame_swaps():
    # A seeded scene (found by search, not designed) where people cross and are hidden behind
    # one another: the window LP over 10 frames keeps every identity, frame-by-frame
    # assignment on the same costs changes some.
    detections, who = _crossing_scene(31)
    assert _identity_changes(detections, who, "nn-hungarian") > 0
    assert _identity_changes(detections, who, "lp-l1") == 0
    # Without weighing each return against a newcomer (the window's costs alone) the same.
    assert _identity_changes(detections, who, "lp-l1", Lifecycle(returns_compete=False)) == 0


def test_bad_detection_files_are_one_line_errors(tmp_path):
    bad = tmp_path / "det.txt"
    bad.write_text("1,-1,10,10,5,5,0.9\n2,-1,10,10,5\n")
    with pytest.raises(InputError, match="line 2 has 5 columns"):
        read_detections(bad)
    with pytest.raises(InputError, match="cannot read"):
        read_detections(tmp_path / "missing.txt")
    bad.write_text("1,-1,10,10,0,5,0.9\n")
    with pytest.raises(InputError, match="width and height"):
        read_detections(bad)
