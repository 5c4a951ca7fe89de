"""Label scores on a hand-built capture whose right answers are known by heart."""

import numpy as np
import pytest

from service.evaluation.scenario import Scenario
from service.evaluation.scores import counts_within, label_scores
from service.evaluation.simulated import SimulatedCapture
from service.io.recording import LabeledTrajectories, Recording, UnlabeledCloud

# Three markers, six frames; -1 is a ghost. Marker 2 is deleted in frame 5.
POINT_MARKER = [
    [2, 0, -1, 1],
    [1, -1, 2, 0],
    [0, 2, 1],
    [-1, 1, 0, 2],
    [2, 1, 0],
    [0, -1, 1],
]
# The perfect labeling: PERFECT[f, n] is the position of n in POINT_MARKER[f].
PERFECT = np.array([[1, 3, 0], [3, 0, 2], [0, 2, 1], [2, 1, 3], [2, 1, 0], [0, 2, -1]])
# Scored marker-frames (frames 1..5): 3 + 3 + 3 + 3 + 2.
MARKER_FRAMES = 14
# Scored ghosts, in frames 1, 3 and 5 (frame 0's ghost is given away by the labels).
GHOSTS = 3


def _capture() -> SimulatedCapture:
    n_frames, n_markers = len(POINT_MARKER), 3
    truth = np.arange(n_frames * n_markers * 3, dtype=float).reshape(n_frames, n_markers, 3)
    points = [
        np.array([truth[f, m] if m >= 0 else [1e3, 1e3, 1e3] for m in pm])
        for f, pm in enumerate(POINT_MARKER)
    ]
    names = ["A", "B", "C"]
    return SimulatedCapture(
        cloud=UnlabeledCloud(points=points, rate=100.0),
        point_marker=[np.array(pm) for pm in POINT_MARKER],
        truth=Recording(names=names, positions=truth, rate=100.0),
        first_frame=Recording(names=names, positions=truth[:1], rate=100.0),
        scenario=Scenario(),
    )


def _labeled(point_index: np.ndarray) -> LabeledTrajectories:
    n_frames, n_markers = point_index.shape
    return LabeledTrajectories(
        names=["A", "B", "C"],
        positions=np.zeros((n_frames, n_markers, 3)),
        occluded=point_index < 0,
        rate=100.0,
        point_index=point_index,
    )


def _score(edits: dict[tuple[int, int], int]):
    point_index = PERFECT.copy()
    for (f, n), p in edits.items():
        point_index[f, n] = p
    return label_scores(_capture(), _labeled(point_index))


def test_perfect_labeling_scores_one() -> None:
    s = _score({})
    assert (s.label_accuracy, s.swaps, s.ghost_precision, s.ghost_recall) == (1.0, 0, 1.0, 1.0)
    assert (s.marker_frames, s.correct, s.missed, s.took_ghost) == (MARKER_FRAMES, 14, 0, 0)
    assert (s.ghosts, s.declared_ghosts) == (GHOSTS, GHOSTS)


def test_swapping_two_markers_for_three_frames() -> None:
    swapped = {(f, n): PERFECT[f, 1 - n] for f in (2, 3, 4) for n in (0, 1)}
    s = _score(swapped)
    assert s.label_accuracy == pytest.approx((MARKER_FRAMES - 6) / MARKER_FRAMES)
    assert s.correct == 8
    assert s.swaps == 2
    assert (s.ghost_precision, s.ghost_recall) == (1.0, 1.0)


@pytest.mark.parametrize(
    ("edits", "swaps"),
    [
        # Marker 0 holds marker 1's point in frames 1 and 3, right in 2: two runs.
        ({(1, 0): 0, (3, 0): 1}, 2),
        # Marker 0 holds marker 1's point, then marker 2's: one unbroken run.
        ({(2, 0): 2, (3, 0): 3}, 1),
        # Frame 0 is given, so a run entering frame 1 starts there.
        ({(0, 0): 3, (1, 0): 0}, 1),
    ],
)
def test_each_wrong_run_counts_once(edits: dict, swaps: int) -> None:
    assert _score(edits).swaps == swaps


def test_taking_a_ghost_is_wrong_but_no_swap() -> None:
    s = _score({(3, 2): 0})
    assert s.label_accuracy == pytest.approx(13 / 14)
    assert (s.swaps, s.took_ghost) == (0, 1)
    # Declared: the ghosts of frames 1 and 5, and marker 2's own point in frame 3.
    assert s.declared_ghosts == 3
    assert s.ghost_precision == pytest.approx(2 / 3)
    assert s.ghost_recall == pytest.approx(2 / 3)


def test_deleted_marker_is_not_scored_but_its_ghost_theft_is_counted() -> None:
    s = _score({(5, 2): 1})
    assert (s.marker_frames, s.label_accuracy, s.took_ghost) == (MARKER_FRAMES, 1.0, 1)
    assert (s.ghost_precision, s.ghost_recall) == (1.0, pytest.approx(2 / 3))


def test_leaving_a_visible_marker_occluded() -> None:
    s = _score({(2, 1): -1})
    assert (s.missed, s.correct, s.swaps) == (1, 13, 0)
    assert s.ghost_precision == pytest.approx(3 / 4)
    assert s.ghost_recall == 1.0


def test_first_frame_is_not_scored() -> None:
    assert _score({(0, 0): 0, (0, 1): 1, (0, 2): 2}) == _score({})


def test_a_first_frame_named_by_a_model_is_scored() -> None:
    """``eval --model`` gives the labeler no frame: its frame 0 was left out of the scores."""
    point_index = PERFECT.copy()
    point_index[0, [0, 1]] = point_index[0, [1, 0]]  # the model swapped two markers in frame 0
    given = label_scores(_capture(), _labeled(point_index))
    named = label_scores(_capture(), _labeled(point_index), first_given=False)
    assert named.marker_frames == given.marker_frames + 3 and named.correct == given.correct + 1
    assert named.swaps == given.swaps + 2


def test_empty_labeling_has_zero_accuracy_and_declares_every_point() -> None:
    s = label_scores(_capture(), _labeled(np.full(PERFECT.shape, -1)))
    assert (s.label_accuracy, s.missed, s.ghost_recall) == (0.0, MARKER_FRAMES, 1.0)
    assert s.ghost_precision == pytest.approx(GHOSTS / (MARKER_FRAMES + GHOSTS))


@pytest.mark.parametrize(
    "point_index",
    [PERFECT[:, :2], np.where(PERFECT == 3, 4, PERFECT), np.where(PERFECT < 0, -2, PERFECT)],
)
def test_labeling_that_does_not_fit_the_capture_is_refused(point_index: np.ndarray) -> None:
    with pytest.raises(ValueError, match="point_index"):
        label_scores(_capture(), _labeled(point_index))


def test_counts_within_a_mask_are_those_of_the_scores_inside_it() -> None:
    point_index = PERFECT.copy()
    point_index[2, 0], point_index[4, 1] = -1, 0  # marker A occluded in frame 2, B on A's point in frame 4
    within = np.zeros(PERFECT.shape, bool)
    within[0, :] = within[2, 0] = within[4, :] = within[5, 2] = True  # frame 0 unscored; C deleted in frame 5
    # scored inside: (2, A) visible and wrong, frame 4's three visible, B's wrong
    assert counts_within(_capture(), _labeled(point_index), within) == (4, 2)
