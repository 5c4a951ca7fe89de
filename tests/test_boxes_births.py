"""Births inside the window: a lost object's return is weighed against a newcomer (``lifecycle``, ``returns``)."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.boxes.conflicts import ConflictRule, conflict_resources, distinct_chains
from formulations.boxes.lifecycle import Lifecycle, reentries
from service.boxes.detections import BoxDetections
from service.boxes.track import track_boxes

COMPETE = Lifecycle(returns_compete=True)
WINDOW_ONLY = Lifecycle(returns_compete=False)  # the window's costs alone decide a return


def test_reentries_are_the_boxes_after_a_miss():
    taken = np.array([[4, 5, 6], [7, -1, 8], [9, 10, -1]])
    last_seen = np.array([10, 10, 8])  # objects 0 and 1 seen at the template frame 10, object 2 not
    assert sorted(reentries(last_seen, taken, 10).tolist()) == [8, 9, 10]


def _scene(rows, frames=40, seed=0):
    """``rows`` plus two people standing far off, a small and a large one, so that the boxes
    span the sizes a camera sees (a newcomer's first box is uniform over the image and those sizes)."""
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
    for lifecycle, apart in ((COMPETE, True), (WINDOW_ONLY, False)):
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
    # A walks on behind an occluder for ``gap`` frames: the window takes the return (the first
    # box's jump with the cheap steps after it) and the chain test keeps it with A; frame by
    # frame, the first box alone costs more than another miss, and the chain is born anew.
    rng = np.random.default_rng(1)
    rows = _walker([f for f in range(1, 41) if not 10 < f <= 10 + gap], 100.0, 3.0, 100.0, (40.0, 100.0), rng)
    ids = {f: set(t.track_id[t.box[:, 0] < 1000].tolist())
           for f in ("lp-l1", "nn-hungarian") for t in [track_boxes(_scene(rows), f, window=5, lifecycle=COMPETE).tracks]}
    assert len(ids["lp-l1"]) == 1
    assert len(ids["nn-hungarian"]) == 2


@pytest.mark.parametrize("seed", range(4))
def test_a_newcomer_a_lost_object_took_in_a_windows_last_frames_is_born_there(seed):
    # A walks right in frames 1..10 and is gone; B walks left from frame 16, 45 px ahead of
    # A's forecast. Windows start at 1, 5, 9, 13, 17: B's first two boxes are the last two
    # frames of window 13, too few for a chain there, and A takes them; from window 17 on A
    # is seen at the template and walks on with B. B's chain runs on past window 13 into
    # frames not solved yet: tested there, it is a newcomer from its first box.
    rng = np.random.default_rng(seed)
    rows = _walker(range(1, 11), 100.0, 3.0, 100.0, (40.0, 100.0), rng)
    rows += _walker(range(16, 41), 100.0 + 3 * 16 + 45 + 3 * 16, -3.0, 105.0, (44.0, 110.0), rng)
    for lifecycle, apart in ((COMPETE, True), (WINDOW_ONLY, False)):
        tracks = track_boxes(_scene(rows, seed=seed), "lp-l1", window=5, lifecycle=lifecycle).tracks
        near = tracks.box[:, 0] < 1000
        a = set(tracks.track_id[near & (tracks.frame <= 10)].tolist())
        b = tracks.track_id[near & (tracks.frame >= 16)]
        assert len(a) == 1 and len(set(b.tolist())) == 1 and (a != set(b.tolist())) == apart
        assert len(b) == 25  # every box of B tracked, from its first on


def test_of_two_parallel_chains_of_one_person_one_is_kept_and_a_crossing_chain_stays():
    boxes = np.array([[0, 0, 10, 20], [0, 0, 10, 20], [1, 0, 11, 20], [1, 0, 11, 20], [30, 0, 40, 20],
                      [2, 0, 12, 20]], dtype=float)
    frame = np.array([1, 1, 2, 2, 1, 2])
    conflicting = conflict_resources(ConflictRule(), frame, boxes)
    person, twin, crossing = np.array([0, 2]), np.array([1, 3]), np.array([4, 5])  # crossing meets the person at 2
    assert [c.tolist() for c in distinct_chains([twin, person, crossing], conflicting)] == [[1, 3], [4, 5]]
