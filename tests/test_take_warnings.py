"""The fast-motion warning: markers that step further per frame than half their neighbour distance."""

import json

import numpy as np
import pytest

from service.labeling.take_warnings import FAST_RATIO, fast_markers, fast_motion_warning


def cluster(step_mm: float, spacing_mm: float, frames: int = 60, seed: int = 0) -> np.ndarray:
    """A rigid 3-marker triangle of side ``spacing_mm`` translating ``step_mm`` per frame, plus
    a still marker far away (``(frames, 4, 3)``)."""
    rng = np.random.default_rng(seed)
    corners = spacing_mm * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    moving = corners[None] + (step_mm * np.arange(frames))[:, None, None] * direction
    still = np.full((frames, 1, 3), 5000.0)
    return np.concatenate([moving, still], axis=1)


NAMES = ["A", "B", "C", "far"]


@pytest.mark.parametrize("step,spacing", [(28.0, 30.0), (20.0, 30.0), (5.0, 30.0), (60.0, 100.0), (40.0, 100.0)])
def test_flagged_exactly_when_the_step_exceeds_half_the_spacing(step, spacing):
    fast = fast_markers(NAMES, cluster(step, spacing))
    expected = {"A", "B", "C"} if step > FAST_RATIO * spacing else set()
    assert {f.marker for f in fast} == expected
    for f in fast:
        assert f.step_mm == pytest.approx(step)
        assert f.neighbour_mm == pytest.approx(spacing)
        assert f.neighbour in {"A", "B", "C"} - {f.marker}


def test_unlabeled_frames_are_left_out_not_counted_as_motion():
    positions = cluster(5.0, 30.0)
    positions[::3, 0] = np.nan  # A occluded every third frame: its steps are only the labeled pairs
    positions[10:, 3] = np.nan  # the far marker leaves
    assert fast_markers(NAMES, positions) == []
    positions[:, 1:] = np.nan  # A alone: no neighbour, nothing to compare
    assert fast_markers(NAMES, positions) == []


def test_the_line_names_the_markers_and_the_figures_serialise():
    fast = fast_markers(NAMES, cluster(28.0, 30.0))
    line = fast_motion_warning(fast)
    assert line is not None and line.startswith("warning: 3 markers") and "28 mm/frame, 30 mm from" in line
    assert fast_motion_warning([]) is None
    one = fast_motion_warning(fast[:1])
    assert one is not None and one.startswith("warning: 1 marker moves") and "its label may swap" in one
    json.dumps([vars(f) for f in fast], allow_nan=False)


def test_a_copied_column_is_reported_and_not_read_as_fast_motion():
    """HDM05 repeats three markers in columns of their own: two points on one position."""
    from service.labeling.coincident import coincident_pairs, coincident_warning

    positions = cluster(5.0, 30.0)
    copied = np.concatenate([positions, positions[:, :1] + 1e-4], axis=1)  # A again, to the 0.1 micrometre
    names = [*NAMES, "A copy"]
    assert coincident_pairs(names, copied) == [("A", "A copy")]
    assert fast_markers(names, copied) == []  # 5 mm a frame against the 30 mm to B and C, not 0 mm to the copy
    assert coincident_pairs(NAMES, cluster(28.0, 30.0)) == []
    line = coincident_warning([("A", "A copy")])
    assert line is not None and line.startswith("warning: 1 pair of markers on one position (A and A copy)")
    assert coincident_warning([]) is None
    two = coincident_warning([("A", "A copy"), ("B", "B copy")])
    assert two is not None and two.startswith("warning: 2 pairs of markers on one position")
