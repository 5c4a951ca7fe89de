"""An object's boxes while it is held occluded: on the line between its sightings."""

from __future__ import annotations

import numpy as np

from formulations.boxes.occluded import occluded_boxes
from service.boxes.detections import BoxDetections
from service.boxes.mot_files import read_rows, write_tracks
from service.boxes.track import track_boxes


def _by_loop(frame, ident, box):
    rows = []
    for i in set(ident.tolist()):
        seen = sorted((int(f), box[k]) for k, f in enumerate(frame) if ident[k] == i)
        for (fa, ba), (fb, bb) in zip(seen, seen[1:]):
            for f in range(fa + 1, fb):
                rows.append((f, i, *(ba + (f - fa) / (fb - fa) * (bb - ba))))
    return sorted(rows)


def test_occluded_boxes_against_a_loop():
    rng = np.random.default_rng(5)
    for _ in range(20):
        ident = rng.integers(1, 5, 40)
        frame = np.concatenate([rng.choice(np.arange(1, 60), (ident == i).sum(), replace=False) for i in range(1, 5)])
        frame = frame[np.argsort(np.argsort(ident, kind="stable"), kind="stable")]  # frames grouped back per ident
        box = rng.uniform(0, 500, (40, 4))
        f, i, b = occluded_boxes(frame, ident, box)
        got = sorted((int(a), int(c), *d) for a, c, d in zip(f, i, b))
        want = _by_loop(frame, ident, box)
        assert len(got) == len(want) and len(got) > 0
        np.testing.assert_allclose(np.array(got, float), np.array(want, float))


def _walker_hidden(frames, hidden):
    """One person walking right at 4 px/frame, undetected in ``hidden`` frames."""
    rows = np.array([(f, 50.0 + 4 * f, 80.0, 40.0, 100.0) for f in frames if f not in hidden])
    return BoxDetections(rows[:, 0].astype(int), rows[:, 1:], np.ones(len(rows)), max(frames), (640.0, 480.0))


def test_a_hidden_person_gets_boxes_where_it_walked(tmp_path):
    hidden = set(range(21, 27))
    tracks = track_boxes(_walker_hidden(range(1, 41), hidden), "lp-l1", window=5).tracks
    assert len(set(tracks.track_id)) == 1 and not set(tracks.frame) & hidden  # taken boxes alone leave the gap
    full = tracks.with_occluded()
    gap = full.occluded
    assert sorted(full.frame[gap]) == sorted(hidden) and (full.confidence[gap] == 0).all()
    truth = np.array([50.0 + 4 * f for f in full.frame[gap]])
    np.testing.assert_allclose(full.box[gap, 0], truth, atol=1e-9)
    assert len(full.with_occluded().frame) == len(full.frame)  # adding them twice adds nothing
    write_tracks(tmp_path / "r.txt", full)
    rows = read_rows(tmp_path / "r.txt")
    assert len(rows) == 40 and (rows[np.isin(rows[:, 0], list(hidden)), 6] == 0).all()
