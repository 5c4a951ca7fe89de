"""Plates with equal sides read exchanged, given back by how far they turned
(``formulations.markers.plate_turns``)."""

from __future__ import annotations

from itertools import permutations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.markers.plate_turns import (
    equal_plates,
    plate_readings,
    plate_turns,
    turn_angles,
)
from formulations.markers.state import MarkerState
from service.io.recording import LabeledTrajectories
from service.labeling.exchanged import EXCHANGED_CONFIDENCE, exchange_summary, exchanged_back

EQUILATERAL = 43.0 * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
SCALENE = np.array([[0.0, 0, 0], [30, 0, 0], [0, 40, 0]])  # sides 30, 40, 50 mm
ALONE = np.array([[1, 2], [0, 2], [0, 1]])  # a plate and nothing else: each corner's neighbours are the other two


def _turning_plate(frames: int, degrees_per_frame: float, seed: int = 0) -> np.ndarray:
    """``(frames, 3, 3)``: the equilateral plate turning steadily about a tilted axis while it
    travels, with 0.5 mm noise."""
    rng = np.random.default_rng(seed)
    axis = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    turns = Rotation.from_rotvec(np.radians(degrees_per_frame) * np.arange(frames)[:, None] * axis)
    centred = EQUILATERAL - EQUILATERAL.mean(axis=0)
    travel = np.arange(frames)[:, None, None] * np.array([12.0, 4.0, 0.0])
    plate = np.stack([turns[f].apply(centred) for f in range(frames)]) + travel
    return plate + rng.normal(0.0, 0.5, plate.shape)


def test_turn_angles_equal_scipys_rotation_magnitude_on_random_turns() -> None:
    rng = np.random.default_rng(1)
    turns = Rotation.random(50, random_state=2)
    before = rng.normal(0.0, 40.0, (50, 3, 3))
    after = np.stack([turns[k].apply(before[k]) for k in range(50)]) + rng.normal(0.0, 100.0, (50, 1, 3))
    assert np.allclose(turn_angles(before, after), np.degrees(turns.magnitude()), atol=1e-6)


def test_only_a_rigid_plate_with_equal_sides_is_found() -> None:
    frame = np.vstack([EQUILATERAL, SCALENE + [500.0, 0, 0], [[0.0, 900, 0], [900.0, 900, 0]]])
    take = np.repeat(frame[None], 40, axis=0) + np.random.default_rng(0).normal(0.0, 0.5, (40, 8, 3))
    assert equal_plates(take, frame) == [(0, 1, 2)]
    loose = take.copy()
    loose[:, 2] += np.random.default_rng(1).normal(0.0, 20.0, (40, 3))  # a corner that is no plate's
    assert equal_plates(loose, frame) == []


def _exchanged(plate: np.ndarray, reading: tuple[int, ...], start: int, stop: int, lost: int) -> np.ndarray:
    """``plate``'s labels read by ``reading`` over [start, stop), the plate lost whole for ``lost``
    frames before ``start`` (where the windows take it back exchanged)."""
    labels = plate.copy()
    labels[start:stop] = labels[start:stop][:, list(reading)]
    labels[start - lost:start] = np.nan
    return labels


@pytest.mark.parametrize("reading", [r for r in permutations(range(3)) if r != (0, 1, 2)])
def test_a_slow_plate_lost_whole_and_read_exchanged_is_given_back_exactly(reading: tuple[int, ...]) -> None:
    """Each exchange and rotation, over a run that starts after the plate was lost 12 frames
    and ends where the labels turn right again; the frames around it untouched."""
    plate = _turning_plate(200, 1.5)
    labels = _exchanged(plate, reading, 80, 150, 12)
    turns = plate_turns(labels, labels[0], ALONE)
    assert [(t.start, t.stop) for t in turns] == [(80, 150)]
    given = labels.copy()
    markers = list(turns[0].markers)
    given[80:150, markers] = given[80:150, markers[1:] + markers[:1]]
    seen = np.isfinite(labels).all(axis=2)
    assert np.allclose(given[seen], plate[seen])


def test_the_change_goes_where_a_labels_track_jumps_not_where_the_plate_was_lost() -> None:
    """Lost whole over 68-79, the first marker back alone and right at 80-81, the labels
    exchanged from 82 (its label jumping to the second's point): given back from 82, and 80-81
    kept (the racing take, right scapula plate: the change put at the first frame back cost a label)."""
    plate = _turning_plate(200, 1.5)
    labels = _exchanged(plate, (1, 0, 2), 80, 150, 12)
    labels[80:82] = np.nan
    labels[80:82, 0] = plate[80:82, 0]
    assert [(t.start, t.stop) for t in plate_turns(labels, labels[0], ALONE)] == [(82, 150)]


def test_the_labeled_first_frame_is_never_read_otherwise() -> None:
    """The first frame's third marker 15 mm off (no full frame there), the plate lost whole over
    frames 1-3, the third marker unlabeled to frame 99, the first two exchanged over 10-139: the
    full frames from 100 are read by the turn (the exchange ends in view at 140), and the change
    goes back to where the labels jumped, frame 10, not to the labeled first frame."""
    plate = _turning_plate(300, 1.5)
    labels = plate.copy()
    labels[10:140] = labels[10:140][:, [1, 0, 2]]
    labels[1:4] = np.nan
    labels[1:100, 2] = np.nan
    labels[0, 2] += [15.0, 0.0, 0.0]
    assert [(t.start, t.stop) for t in plate_turns(labels, labels[0], ALONE)] == [(10, 140)]


def test_a_right_labeling_is_left_alone_however_fast_the_plate_turns() -> None:
    for degrees in (0.5, 5.0, 40.0, 75.0):
        plate = _turning_plate(300, degrees, seed=3)
        plate[100:110] = np.nan
        plate[200:215, 1] = np.nan
        assert plate_turns(plate, plate[0], ALONE) == [], degrees


def test_a_plate_turning_faster_than_its_gap_can_tell_is_read_as_most_of_it_is_labeled() -> None:
    """40 degrees a frame: a 12-frame loss cannot tell an exchange from the turn. Exchanged from
    after the loss to the end, nothing says which side is right and nothing changes; exchanged
    over 40 frames of the 120 after it, ending in view, those 40 are given back."""
    plate = _turning_plate(200, 40.0)
    assert np.all(plate_readings(_exchanged(plate, (1, 0, 2), 80, 200, 12)) == 0)
    labels = _exchanged(plate, (1, 0, 2), 80, 120, 12)
    assert [(t.start, t.stop) for t in plate_turns(labels, labels[0], ALONE)] == [(80, 120)]


def test_a_ghost_in_place_of_one_marker_does_not_count_as_a_turn() -> None:
    """A triangle with a ghost for a corner is not the plate: it neither starts nor ends a run."""
    plate = _turning_plate(200, 1.5)
    labels = plate.copy()
    labels[100, 2] += [60.0, -40.0, 30.0]
    assert plate_turns(labels, labels[0], ALONE) == []


def test_the_labeling_gives_an_exchanged_plate_back_and_says_so() -> None:
    """Through ``exchanged_back``, after the distance-judged repairs that see nothing: the plate
    and a marker far from it (no witness rigid with the plate), the exchange given back,
    doubtful, and in the summary."""
    plate = _turning_plate(200, 1.5)
    labeled = np.concatenate([_exchanged(plate, (1, 0, 2), 80, 150, 12), plate[:, :1] + [0.0, 0.0, 900.0]], axis=1)
    labels = LabeledTrajectories(["p1", "p2", "p3", "far"], labeled, np.zeros((200, 4), bool), 100.0,
                                 confidence=np.ones((200, 4)))
    given, exchanges = exchanged_back(labels, MarkerState.from_first_frame(labeled[0], n_neighbours=3))
    seen = np.isfinite(labeled).all(axis=2)
    assert np.allclose(given.positions[:, :3][seen[:, :3]], plate[seen[:, :3]])
    assert exchange_summary(exchanges, labels.names) == [{"markers": ["p1", "p2"], "frames": [80, 150]}]
    assert (given.confidence[80:150, :2] <= EXCHANGED_CONFIDENCE).all() and (given.confidence[:80] == 1).all()
