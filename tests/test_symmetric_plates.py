"""Plates whose markers no distance tells apart, warned of (``service.labeling.symmetric_plates``)."""

from __future__ import annotations

import numpy as np

from service import Capture, CaptureLabeling
from service.labeling.result_warnings import result_warnings
from service.labeling.symmetric_plates import symmetric_plate_warning, symmetric_plates

EQUILATERAL = 43.0 * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
SCALENE = np.array([[0.0, 0, 0], [30, 0, 0], [0, 40, 0]])  # sides 30, 40, 50 mm


def _frame() -> tuple[list[str], np.ndarray]:
    """An equilateral plate, a scalene one 500 mm off, and two lone markers far from both."""
    frame = np.vstack([EQUILATERAL, SCALENE + [500.0, 0, 0], [[0.0, 900, 0], [900.0, 900, 0]]])
    return ["g1", "g2", "g3", "s1", "s2", "s3", "far1", "far2"], frame


def test_only_the_plate_with_equal_sides_is_named() -> None:
    names, frame = _frame()
    assert symmetric_plates(names, frame) == [("g1", "g2", "g3")]


def test_a_plate_stretched_past_the_share_or_missing_a_marker_is_not_named() -> None:
    names, frame = _frame()
    stretched = frame.copy()
    stretched[1, 0] += 0.06 * 43.0  # one side 6 % longer
    assert symmetric_plates(names, stretched) == []
    unlabeled = frame.copy()
    unlabeled[2] = np.nan
    assert symmetric_plates(names, unlabeled) == []


def test_a_labeled_take_with_such_a_plate_is_warned_of() -> None:
    """Through ``result_warnings``, as ``track`` and a job print them; none without the plate."""
    names, frame = _frame()
    travel = np.arange(30)[:, None, None] * np.array([5.0, 3.0, 0.0])
    for take, plated in ((frame, True), (np.vstack([SCALENE + [-300.0, 0, 0], frame[3:]]), False)):
        points = list(take[None] + travel)
        capture = Capture(names, take, 100.0, points=points)
        labels, _ = CaptureLabeling(capture).label()
        lines = [line for line in result_warnings(capture, labels, []) if "equal sides" in line]
        assert lines == ([symmetric_plate_warning([("g1", "g2", "g3")])] if plated else [])
