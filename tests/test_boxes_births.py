"""Births inside the window: a lost object and a newcomer compete for a chain (``lifecycle``, ``costs.birth_cost``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from formulations.boxes import kalman
from formulations.boxes.candidates import box_window
from formulations.boxes.conflicts import ConflictRule
from formulations.boxes.costs import BoxCostModel, birth_cost
from formulations.boxes.geometry import corners
from formulations.boxes.lifecycle import Lifecycle, reentries
from formulations.boxes.objects import BoxObjects
from formulations.window.build import build_window
from formulations.window.problem import OBSERVATION, OCCLUSION, SOURCE
from service.boxes.detections import BoxDetections
from service.boxes.track import track_boxes

COMPETE = Lifecycle(returns_compete=True)


def test_birth_cost_is_the_uniform_density_against_a_box_seen_where_predicted():
    rng = np.random.default_rng(0)
    boxes = corners(np.column_stack([rng.uniform(0, 500, (5, 2)), rng.uniform(10, 80, 5), rng.uniform(30, 200, 5)]))
    volume = 1e9
    for box, cost in zip(boxes, birth_cost(boxes, volume)):
        z = kalman.measurement(box)
        r = np.diag((kalman.MEASUREMENT_SD * np.r_[z[2:], z[2:]]) ** 2)
        expected = -np.log(1.0 / volume) + multivariate_normal(np.zeros(4), r).logpdf(np.zeros(4))
        assert cost == pytest.approx(expected)


def test_reentries_are_the_boxes_after_a_miss():
    taken = np.array([[4, 5, 6], [7, -1, 8], [9, 10, -1]])
    last_seen = np.array([10, 10, 8])  # objects 0 and 1 seen at the template frame 10, object 2 not
    assert sorted(reentries(last_seen, taken, 10).tolist()) == [8, 9, 10]


def _two_frames(unborn):
    box = corners(np.array([[100.0, 100.0, 40.0, 100.0], [103.0, 100.0, 40.0, 100.0]]))
    objects = BoxObjects(np.array([1]), *kalman.start(kalman.measurement(box[:1])), np.array([0]), None)
    model = BoxCostModel()
    window = box_window(objects, 0, 2, np.array([1, 2]), box, None, model, ConflictRule(), unborn=unborn,
                        birth_volume=1e9)
    problem, _ = build_window(window.candidates, window.weights)
    kind = problem.node_kind
    def arc(tail_kind, tail_frame, head_kind, head_frame):
        tails = (kind[problem.arc_tail] == tail_kind) & (problem.node_frame[problem.arc_tail] == tail_frame)
        heads = (kind[problem.arc_head] == head_kind) & (problem.node_frame[problem.arc_head] == head_frame)
        return float(problem.arc_cost[tails & heads][0])
    return box, model, window, arc


def test_an_unborn_object_enters_by_the_birth_density_and_then_steps_as_usual():
    box, model, window, arc = _two_frames(np.array([True]))
    _, _, seen_window, seen_arc = _two_frames(None)
    entry = model.reappear + model.prediction * birth_cost(box, 1e9)
    assert arc(SOURCE, 0, OBSERVATION, 1) == pytest.approx(entry[0])  # its template is occluded: an entry
    assert arc(OCCLUSION, 1, OBSERVATION, 2) == pytest.approx(entry[1])
    assert seen_arc(SOURCE, 0, OBSERVATION, 1) < entry[0] - 5  # seen at the template, a step from there
    # Once on its path, a box is priced against its forecast as for any object.
    assert arc(OBSERVATION, 1, OBSERVATION, 2) == pytest.approx(seen_arc(OBSERVATION, 1, OBSERVATION, 2))
    np.testing.assert_array_equal(window.candidates.template_occluded, [True])


def _scene(rows, frames=40, seed=0):
    """``rows`` plus two people standing far off, a small and a large one, so that the boxes
    span the sizes a camera sees (the birth density is over the image and those sizes)."""
    rng = np.random.default_rng(seed)
    rows = rows + [(f, x + rng.normal(0, 1), y + rng.normal(0, 1), w, h) for f in range(1, frames + 1)
                   for x, y, w, h in ((1500.0, 100.0, 20.0, 50.0), (1600.0, 500.0, 120.0, 300.0))]
    r = np.array(rows)
    return BoxDetections(r[:, 0].astype(int), r[:, 1:], np.ones(len(r)), frames, (1920.0, 1080.0))


def _walker(frames, x0, speed, y, size, rng):
    return [(f, x0 + speed * f + rng.normal(0, 1), y + rng.normal(0, 1), *size) for f in frames]


@pytest.mark.parametrize("seed", range(4))
def test_a_newcomer_in_a_lost_objects_gate_is_a_new_object(seed):
    # A walks right in frames 1..10 and is gone; from frame 14 (mid-window: windows start at
    # 1, 5, 9, 13, ...) B walks left, first 58 px ahead of A's forecast. Without births inside
    # the window the window LP hands B to A on each of these seeds: one costly jump, then
    # cheap steps, and no newcomer on offer.
    rng = np.random.default_rng(seed)
    rows = _walker(range(1, 11), 100.0, 3.0, 100.0, (40.0, 100.0), rng)
    rows += _walker(range(14, 41), 200.0 + 3 * 14, -3.0, 110.0, (44.0, 110.0), rng)
    for lifecycle, apart in ((COMPETE, True), (Lifecycle(), False)):
        tracks = track_boxes(_scene(rows, seed=seed), "lp-l1", window=5, lifecycle=lifecycle).tracks
        near = tracks.box[:, 0] < 1000
        a = set(tracks.track_id[near & (tracks.frame <= 10)].tolist())
        b = set(tracks.track_id[near & (tracks.frame >= 14)].tolist())
        assert len(a) == 1 and len(b) == 1 and (a != b) == apart
    assert (near & (tracks.frame >= 14)).sum() < 27  # and A missed some of B's boxes
    tracks = track_boxes(_scene(rows, seed=seed), "lp-l1", window=5, lifecycle=COMPETE).tracks
    assert ((tracks.box[:, 0] < 1000) & (tracks.frame >= 14)).sum() == 27  # B from its first box on


@pytest.mark.parametrize("gap", [8, 12])
def test_the_window_keeps_a_return_that_frame_by_frame_loses(gap):
    # A walks on behind an occluder for ``gap`` frames: its forecast explains the return better
    # than a newcomer over the window's frames; frame by frame, the first box alone does not.
    rng = np.random.default_rng(1)
    rows = _walker([f for f in range(1, 41) if not 10 < f <= 10 + gap], 100.0, 3.0, 100.0, (40.0, 100.0), rng)
    ids = {f: set(t.track_id[t.box[:, 0] < 1000].tolist())
           for f in ("lp-l1", "nn-hungarian") for t in [track_boxes(_scene(rows), f, window=5, lifecycle=COMPETE).tracks]}
    assert len(ids["lp-l1"]) == 1
    assert len(ids["nn-hungarian"]) == 2
