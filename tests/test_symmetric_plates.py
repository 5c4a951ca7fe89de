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


def _still(frame: np.ndarray, noise: float = 0.5) -> np.ndarray:
    """``frame`` held 30 frames with ``noise`` mm of noise."""
    return frame[None] + np.random.default_rng(0).normal(0.0, noise, (30, *frame.shape))


def test_only_the_plate_with_equal_sides_is_named() -> None:
    names, frame = _frame()
    assert symmetric_plates(names, _still(frame), frame) == [("g1", "g2", "g3")]


def test_a_plate_named_through_noise_that_moves_one_frames_sides_past_the_share() -> None:
    """1.5 mm of noise moves a 43 mm side by 2-3 mm, past 5 % in one frame: the take's median sides are judged."""
    names, frame = _frame()
    noisy = _still(frame, noise=1.5)
    assert symmetric_plates(names, noisy, noisy[0]) == [("g1", "g2", "g3")]


def test_a_plate_stretched_past_the_share_or_missing_a_marker_is_not_named() -> None:
    names, frame = _frame()
    stretched = frame.copy()
    stretched[1, 0] += 0.06 * 43.0  # one side 6 % longer
    assert symmetric_plates(names, _still(stretched), stretched) == []
    unlabeled = frame.copy()
    unlabeled[2] = np.nan
    assert symmetric_plates(names, _still(unlabeled), unlabeled) == []


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


def test_the_line_counts_its_plates_in_words_that_agree() -> None:
    one, two = ("g1", "g2", "g3"), ("h1", "h2", "h3")
    assert (symmetric_plate_warning([one]) or "").startswith("warning: 1 plate of three markers with equal sides (g1/g2/g3)")
    two_plates = "warning: 2 plates of three markers with equal sides (g1/g2/g3, h1/h2/h3)"
    assert (symmetric_plate_warning([one, two]) or "").startswith(two_plates)
