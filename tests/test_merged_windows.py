"""Windows merged label by label: the labels taken from the other reading bring their points,
fills and confidences; a marker's state rows at a window's end follow its last frame there."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from service_fixtures import generated_capture

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.merged_windows import merged_windows


def test_labels_taken_in_part_of_a_window() -> None:
    labeling = CaptureLabeling(generated_capture(frames=40, seed=3), LabelingOptions(window=10))
    mine = list(labeling.windows())
    theirs = [replace(o, point_index=o.point_index + 1000, state=replace(o.state, position=o.state.position + 1.0))
              for o in mine]
    n = mine[0].point_index.shape[1]
    taken = np.zeros((40, n), dtype=bool)
    window = mine[1]
    rows = np.arange(window.stats.template + 1, window.stats.last + 1)
    taken[rows[3:], 0] = True  # marker 0 from the window's fourth frame to its end
    taken[rows[:2], 1] = True  # marker 1 in its first two frames only
    merged = merged_windows(mine, theirs, taken)
    assert all(m is o for k, (m, o) in enumerate(zip(merged, mine, strict=True)) if k != 1)  # nothing taken there
    got, own, other = merged[1], mine[1], theirs[1]
    assert np.array_equal(got.point_index[3:, 0], other.point_index[3:, 0])
    assert np.array_equal(got.point_index[:3, 0], own.point_index[:3, 0])
    assert np.array_equal(got.point_index[:2, 1], other.point_index[:2, 1])
    assert np.array_equal(got.point_index[2:, 1], own.point_index[2:, 1])
    assert np.array_equal(got.point_index[:, 2:], own.point_index[:, 2:])
    assert np.array_equal(got.state.position[0], other.state.position[0])  # taken in the window's last frame
    assert np.array_equal(got.state.position[1:], own.state.position[1:])
