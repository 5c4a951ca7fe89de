"""A recording's own label jumps (``service.evaluation.label_jumps``): marker-frames where the
file's label went on along another marker after a gap (left out of the doubt scores:
``tests/test_doubtful_labels.py``)."""

from __future__ import annotations

import numpy as np

from service.evaluation.label_jumps import label_jumps
from service.io.recording import Recording

FRAMES = 100
# A forearm-like rigid body of five markers (mm) and a point 60 mm from marker 0 on it.
BODY = np.array([[0, 0, 0], [80, 0, 0], [0, 90, 0], [70, 60, 20], [20, 30, 100.0]])
OTHER_POINT = BODY[0] + [0, -60, 0]


def _rolling(points: np.ndarray) -> np.ndarray:
    """``(FRAMES, len(points), 3)`` the points turning and moving as one body."""
    angle = np.linspace(0, 3, FRAMES)
    c, s = np.cos(angle), np.sin(angle)
    turn = np.stack([np.stack([c, -s, 0 * c], 1), np.stack([s, c, 0 * c], 1), np.tile([0, 0, 1.0], (FRAMES, 1))], 1)
    return np.einsum("fij,nj->fni", turn, points) + np.linspace(0, 900, FRAMES)[:, None, None] * [1, 0.3, 0]


def _take(jump: bool) -> Recording:
    """Marker 0 unseen in 40-44 and 70-74; with ``jump`` its label sits on the other point in 45-69."""
    positions = _rolling(BODY)
    if jump:
        positions[45:70, 0] = _rolling(OTHER_POINT[None])[45:70, 0]
    positions[40:45, 0] = positions[70:75, 0] = np.nan
    return Recording([f"m{i}" for i in range(len(BODY))], positions, 100.0)


def test_a_label_that_goes_on_along_another_marker_after_a_gap_is_found_until_it_comes_back() -> None:
    assert not label_jumps(_take(jump=False)).any()
    jumped = label_jumps(_take(jump=True))
    assert np.flatnonzero(jumped[:, 0]).tolist() == list(range(45, 70))
    # the jumped marker is one partner of the others: the median over partners keeps them clear
    assert not jumped[:, 1:].any()


def test_a_marker_moving_on_its_own_is_no_partner_and_its_gaps_no_jumps() -> None:
    take = _take(jump=True)
    free = 300 * np.stack([np.sin(np.arange(FRAMES) / 7), np.cos(np.arange(FRAMES) / 11), np.zeros(FRAMES)], 1)
    free[30:35] = np.nan  # a gap across which its distances to the body change by far more than jump_mm
    with_free = Recording([*take.names, "free"], np.concatenate([take.positions, free[:, None]], axis=1), 100.0)
    jumped = label_jumps(with_free)
    assert np.flatnonzero(jumped[:, 0]).tolist() == list(range(45, 70))
    assert not jumped[:, 1:].any()


def _handed_over(hand_over: bool) -> Recording:
    """Marker 3's label ends at frame 59; with ``hand_over`` marker 0's label goes on along
    marker 3's track from frame 60, with no gap (marker 0's own point is left unlabeled)."""
    positions = _rolling(BODY)
    positions[60:, 3] = np.nan
    if hand_over:
        positions[60:, 0] = _rolling(BODY)[60:, 3]
    return Recording([f"m{i}" for i in range(len(BODY))], positions, 100.0)


def test_a_label_handed_over_to_a_track_whose_label_ends_is_found_to_the_end_of_its_run() -> None:
    assert not label_jumps(_handed_over(hand_over=False)).any()  # a label ending is no hand-over
    jumped = label_jumps(_handed_over(hand_over=True))
    assert np.flatnonzero(jumped[:, 0]).tolist() == list(range(60, FRAMES))
    assert not jumped[:, 1:].any()


def test_a_fast_step_onto_no_ending_track_is_no_hand_over() -> None:
    take = _handed_over(hand_over=False)
    take.positions[60:, 0] += [0.0, 0.0, 200.0]  # marker 0 jumps 200 mm, far from marker 3's heading
    assert not label_jumps(take)[:, 0].any()
