"""Rest lengths of rigid pairs: the first frame refined by the labels two labelings agree on,
so a first frame in an unusual pose (a foot on its toes) does not decide which labeling of a
returning marker the merge keeps."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.markers import first_frame_shape
from formulations.markers.first_frame_shape import pair_offsets
from formulations.markers.pass_merge import labels_taken
from formulations.markers.rest_lengths import rest_lengths
from formulations.markers.state import MarkerState

FRAMES = 80
ANKLE, TOE, MT5, HEEL = range(4)
EVENT = slice(40, 60)


def _foot(seed: int = 0) -> np.ndarray:
    """``(F, 4, 3)`` an ankle marker and a rigid foot (toe, fifth metatarsal, heel); in frame 0
    the foot is pitched 25 degrees about a joint below the ankle marker, after it is flat."""
    rng = np.random.default_rng(seed)
    ankle, joint = np.zeros(3), np.array([0.0, -20.0, -50.0])
    foot = np.array([[164.0, 0.0, -40.0], [127.0, 58.0, -45.0], [-60.0, 10.0, -70.0]])
    pitch = np.radians(-25.0)
    turn = np.array([[np.cos(pitch), 0.0, -np.sin(pitch)], [0.0, 1.0, 0.0], [np.sin(pitch), 0.0, np.cos(pitch)]])
    frames = [np.vstack([ankle, joint + (foot - joint) @ turn.T])]
    frames += [np.vstack([ankle, foot]) + rng.normal(0.0, 0.5, (4, 3)) for _ in range(FRAMES - 1)]
    return np.stack(frames) + np.arange(FRAMES)[:, None, None] * [2.0, 0.0, 0.0]


def _passes(truth: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], list[np.ndarray]]:
    """Point indices and positions of two passes that agree but over ``EVENT``, where the heel
    and the fifth metatarsal are unseen and the toe is back: pass one labels the toe's point
    the toe, pass two the fifth metatarsal."""
    one = np.tile(np.arange(4), (FRAMES, 1))
    one[EVENT, MT5] = one[EVENT, HEEL] = -1
    two = one.copy()
    two[EVENT, MT5], two[EVENT, TOE] = TOE, -1
    positions = [np.where(p[..., None] >= 0, truth[np.arange(FRAMES)[:, None], p], np.nan) for p in (one, two)]
    return (one, two), positions


def _merged(truth: np.ndarray) -> np.ndarray:
    """``labels_taken``: True where the merge takes pass two's label."""
    points, positions = _passes(truth)
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=3).neighbours
    return labels_taken(points, *pair_offsets(positions, truth[0], neighbours))


def test_the_first_frame_alone_keeps_the_toe_given_away(monkeypatch: pytest.MonkeyPatch) -> None:
    """The setup: judged by the first frame's distances, the toe's point fits the fifth
    metatarsal's distance to the ankle better, and the merge takes pass two's labels."""
    truth = _foot()
    first = np.linalg.norm(truth[0] - truth[0, ANKLE], axis=1)
    later = np.linalg.norm(truth[EVENT.start, TOE] - truth[EVENT.start, ANKLE])
    assert abs(later - first[MT5]) < abs(later - first[TOE])  # the pitched first frame misleads
    monkeypatch.setattr(first_frame_shape, "rest_lengths",
                        lambda labelings, mates, distance, d0, spread, tolerance: d0)
    assert _merged(truth)[EVENT, [TOE, MT5]].all()


def test_rest_lengths_keep_the_toe() -> None:
    """With the distances the passes agree on outside the event, the merge keeps pass one."""
    assert not _merged(_foot()).any()


MATES = np.array([[TOE, MT5, HEEL], [ANKLE, MT5, HEEL], [ANKLE, TOE, HEEL], [ANKLE, TOE, MT5]])
SPREAD = np.ones((4, 3))  # mm^2: the foot's distances vary by about 1 mm over the take


def _rest(labelings: list[np.ndarray], first: np.ndarray, tolerance: float) -> np.ndarray:
    """``rest_lengths`` of ``MATES`` with the first labeling's distances and ``first``'s."""
    distance = np.linalg.norm(labelings[0][:, :, None] - labelings[0][:, MATES], axis=3)
    d0 = np.linalg.norm(first[:, None] - first[MATES], axis=2)
    return rest_lengths(labelings, MATES, distance, d0, SPREAD, np.full((4, 3), tolerance))


def test_an_outlying_first_frame_distance_gives_way_to_the_agreed_median() -> None:
    """The ankle's distances to the foot, pitched in the first frame, are the median over the
    frames both passes label alike; the foot's own distances, the same in every pose, keep the
    first frame's."""
    truth = _foot()
    (_, _), positions = _passes(truth)
    rest = _rest(positions, truth[0], 30.0)
    agreed = np.r_[0:EVENT.start, EVENT.stop:FRAMES]
    expected = np.median(np.linalg.norm(truth[agreed, ANKLE] - truth[agreed, TOE], axis=1))
    assert rest[ANKLE, 0] == pytest.approx(expected)
    assert rest[TOE, 0] == pytest.approx(expected)
    first = np.linalg.norm(truth[0, :, None] - truth[0, MATES], axis=2)
    assert rest[TOE, 1:] == pytest.approx(first[TOE, 1:])  # toe to fifth metatarsal and heel: one plate


def test_labels_both_labelings_get_wrong_do_not_move_the_rest_length() -> None:
    """Both labelings exchange the toe and the fifth metatarsal after frame 10: the median of
    their agreed distances lies a marker spacing off the first frame's, beyond the tolerance,
    so the first frame's distance stands; too few agreed frames keep it too."""
    truth = _foot()
    wrong = truth.copy()
    wrong[10:, [TOE, MT5]] = truth[10:, [MT5, TOE]]
    flat = truth[1]  # a first frame in the take's usual pose
    first = np.linalg.norm(flat[:, None] - flat[MATES], axis=2)
    rest = _rest([wrong, wrong.copy()], flat, 10.0)
    assert rest[ANKLE, :2] == pytest.approx(first[ANKLE, :2])
    few = _rest([truth[:15], truth[:15].copy()], truth[0], 30.0)
    assert few == pytest.approx(np.linalg.norm(truth[0, :, None] - truth[0, MATES], axis=2))
