"""A rigid equilateral plate whose labels turn round it: no distance tells, its smooth turn does."""

from itertools import permutations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.markers.state import MarkerState
from formulations.markers.turns import PERMUTATIONS, _turns, repair_turns, rigid_triples

# A glove plate (0, 1, 2: equilateral, 43 mm sides, as the wheelchair-racing take's) turning
# 25 degrees a frame as it sweeps 60 mm a frame; a forearm marker (3) that slides, and a far one (4).
PLATE = 43.0 / np.sqrt(3.0) * np.array([[1.0, 0, 0], [-0.5, np.sqrt(3) / 2, 0], [-0.5, -np.sqrt(3) / 2, 0]])


def _frame(t: int, plate: np.ndarray = PLATE) -> np.ndarray:
    turn = Rotation.from_rotvec(np.radians(25.0) * t * np.array([0.2, 0.3, 0.93]) / np.linalg.norm([0.2, 0.3, 0.93]))
    centre = np.array([60.0 * t, 30.0 * np.sin(t / 5), 900.0])
    forearm = centre + [-120.0 + 8 * np.sin(t / 3), 20.0, 0.0]
    return np.vstack([turn.apply(plate) + centre, forearm, [2000.0, 0.0, 1000.0]])


def _state(frames: int, noise: float, plate: np.ndarray = PLATE) -> MarkerState:
    rng = np.random.default_rng(3)
    state = MarkerState.from_first_frame(_frame(0, plate), n_neighbours=4)
    for t in range(1, frames):
        state = state.advance(_frame(t, plate) + rng.normal(0, noise, (5, 3)), np.ones(5, bool))
    return state


def _window(start: int, length: int, noise: float, seed: int = 0) -> tuple[list[np.ndarray], np.ndarray]:
    """The window's points (shuffled) and the point each marker truly took."""
    rng = np.random.default_rng(seed)
    frames, taken = [], np.zeros((5, length), int)
    for m in range(length):
        order = rng.permutation(5)
        points = _frame(start + 1 + m) + rng.normal(0, noise, (5, 3))
        frames.append(points[order])
        taken[order, m] = np.arange(5)
    return frames, taken


def test_the_turn_of_each_reading_is_its_rotation_off_the_expected_one():
    rng = np.random.default_rng(0)
    before = PLATE + rng.normal(0, 0.1, (3, 3))
    turn = Rotation.from_rotvec([0.1, -0.2, 0.3])
    now = turn.apply(before) + [5.0, 1.0, 2.0]
    angle, fit, rotation = (x[0] for x in _turns(before[None], now[None], np.eye(3)[None], PERMUTATIONS))
    assert np.allclose(rotation[0], turn.as_matrix(), atol=1e-6)
    assert angle[0] == pytest.approx(turn.magnitude(), abs=1e-6)
    assert fit[0] < 1e-6
    # every permutation of an equilateral plate fits, but turns by a symmetry: 120 or 180 degrees off
    assert (fit < 0.5).all()
    assert (np.degrees(angle[1:]) > 100.0).all()
    angle = _turns(before[None], now[None], turn.as_matrix()[None], PERMUTATIONS)[0][0]  # off the expected turn itself: none
    assert angle[0] == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("order", [p for p in permutations(range(3)) if p != (0, 1, 2)])
def test_a_plate_whose_labels_turned_round_it_is_given_back(order):
    state = _state(frames=30, noise=0.5)
    triples, symmetric = rigid_triples(state)
    assert triples.tolist() == [[0, 1, 2]]  # the forearm slides and the far marker is far: no plate of theirs
    assert symmetric.all()  # an equilateral plate: every permutation keeps its sides
    frames, truth = _window(29, 10, noise=0.5)
    wrong = truth.copy()
    wrong[:3, 4:] = truth[list(order), 4:]  # from the window's fifth frame the plate's labels turn round
    repaired, repairs, _ = repair_turns(state, frames, wrong, triples, symmetric)
    assert repairs == 1
    assert (repaired == truth).all()


def test_labels_that_turn_smoothly_are_left_as_they_are():
    state = _state(frames=30, noise=1.0)
    frames, truth = _window(29, 19, noise=1.0, seed=5)
    repaired, repairs, _ = repair_turns(state, frames, truth, *rigid_triples(state))
    assert repairs == 0 and (repaired == truth).all()


def test_after_a_gap_the_plate_is_given_back_only_while_it_cannot_have_turned_by_a_symmetry_half():
    state = _state(frames=30, noise=0.5)
    triples, symmetric = rigid_triples(state)
    frames, truth = _window(29, 12, noise=0.5)
    wrong = truth.copy()
    wrong[:3, 2:7] = -1  # the plate unseen for five frames (six steps of 25 degrees since its last sighting)
    wrong[:3, 7:] = truth[[1, 2, 0], 7:]
    repaired, repairs, _ = repair_turns(state, frames, wrong, triples, symmetric)
    assert repairs == 0 and (repaired == wrong).all()  # it may have turned by a third of a turn: nothing to go on
    short = truth.copy()
    short[:3, 2:3] = -1  # unseen for one frame (two steps of 25 degrees since its last sighting), then turned round
    short[:3, 3:] = truth[[1, 2, 0], 3:]
    repaired, repairs, _ = repair_turns(state, frames, short, triples, symmetric)
    expected = truth.copy()
    expected[:3, 2:3] = -1
    assert repairs == 1 and (repaired == expected).all()


def test_only_the_symmetries_of_a_plate_are_tried():
    """A scalene plate's permutations change its sides, which the distances read: no cluster of
    this repair. An isosceles one keeps its sides under the exchange of its base only."""
    scalene = np.array([[0.0, 0, 0], [50, 0, 0], [10, 35, 0]])  # sides 50, 36.4, 53.2
    assert len(rigid_triples(_state(frames=30, noise=0.5, plate=scalene))[0]) == 0
    isosceles = np.array([[0.0, 0, 0], [40, 0, 0], [20, 45, 0]])  # legs 49.2, base 40
    triples, symmetric = rigid_triples(_state(frames=30, noise=0.5, plate=isosceles))
    assert triples.tolist() == [[0, 1, 2]]
    assert [tuple(p) for p in PERMUTATIONS[symmetric[0]]] == [(0, 1, 2), (1, 0, 2)]


def _carried(state: MarkerState, frames: list[np.ndarray], taken: np.ndarray) -> MarkerState:
    """The state advanced through a window's labels, as the cloud chain does."""
    for m, points in enumerate(frames):
        seen = taken[:, m] >= 0
        observed = np.zeros((len(seen), 3))
        observed[seen] = points[taken[seen, m]]
        state = state.advance(observed, seen)
    return state


def test_a_plate_lost_across_a_window_template_is_read_against_its_last_whole_sighting():
    state = _state(frames=30, noise=0.5)
    triples, symmetric = rigid_triples(state)
    frames, truth = _window(29, 10, noise=0.5)
    hidden = truth.copy()
    hidden[:3, 9] = -1  # lost in the window's last frame, the next window's template
    labels, _, plates = repair_turns(state, frames, hidden, triples, symmetric)
    after = _carried(state, frames, labels)
    later, truth_later = _window(39, 10, noise=0.5, seed=1)
    wrong = truth_later.copy()
    wrong[:3] = truth_later[[1, 2, 0]]  # back in the next window's first frame, turned round
    forgotten, repairs, _ = repair_turns(after, later, wrong, triples, symmetric)
    assert repairs == 0 and (forgotten == wrong).all()  # without the last sighting nothing tells
    remembered = plates.remembered(after, triples, len(frames))
    assert (remembered.plate_age[:3] == 1).all() and (remembered.plate_age[3:] == -1).all()
    repaired, repairs, _ = repair_turns(remembered, later, wrong, triples, symmetric)
    assert repairs == 1 and (repaired == truth_later).all()
