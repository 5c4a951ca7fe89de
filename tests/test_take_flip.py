"""A wrist plate of four read turned half round for the rest of a take (radial on ulnar styloid,
second on fifth metacarpal), given back on the say of the labeled first frame
(``formulations.markers.take_flip``): numediart 03_rolling's left hand, which no pair exchange
and no rotation undoes."""

import numpy as np
import pytest
from rigid_scenes import SwingingSegment

from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import take_exchanges
from formulations.markers.take_flip import take_flips
from formulations.markers.take_rotation import take_rotations
from service.io.recording import LabeledTrajectories
from service.labeling.exchanged import exchange_summary, exchanged_back

# A forearm and hand: lateral and medial epicondyle (0, 1), radial and ulnar styloid (2, 3),
# second and fifth metacarpal head (4, 5). The wrist plate is symmetric about the forearm's
# axis, so a half turn about it keeps all six of its distances; the epicondyles are not.
ARM = np.array([[0, 45, 0], [0, -30, 0], [250, 25, 0], [250, -25, 0], [330, 30, 0], [330, -30, 0]], float)
RSP, USP, HM2, HM5 = 2, 3, 4, 5
SWING = SwingingSegment(turn=(0.5, 0.3, 0.9), periods=(11, 13, 7), speed=6.0, sway=40.0, hinge=0, swing=0.7, swing_period=9)
FRAMES, FLIP_AT, MARKERS = 500, 300, 8


def _take(seed: int, noise: float = 1.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.stack([SWING.frame(t, ARM) for t in range(FRAMES)]) + rng.normal(0, noise, (FRAMES, MARKERS, 3))


def _flipped(take: np.ndarray) -> np.ndarray:
    labeled = take.copy()
    labeled[FLIP_AT:, [RSP, USP, HM2, HM5]] = take[FLIP_AT:, [USP, RSP, HM5, HM2]]
    return labeled


def _neighbours(labeled: np.ndarray) -> np.ndarray:
    return MarkerState.from_first_frame(labeled[0], n_neighbours=5).neighbours


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_plate_turned_half_round_comes_back_from_where_it_turned(seed: int) -> None:
    take = _take(seed)
    labeled = _flipped(take)
    found = take_flips(labeled, labeled[0], _neighbours(labeled))
    assert sorted(tuple(sorted(e.markers)) for e in found) == [(RSP, USP), (HM2, HM5)]
    assert all(abs(e.start - FLIP_AT) <= 2 and e.stop == FRAMES for e in found)
    for e in found:
        labeled[e.start : e.stop, [e.a, e.b]] = labeled[e.start : e.stop, [e.b, e.a]]
    assert (np.linalg.norm(labeled - take, axis=2)[FLIP_AT + 2 :] < 1e-9).all()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_pair_exchange_nor_rotation_undoes_a_half_turn(seed: int) -> None:
    """The setup the half turn is for: each styloid's witnesses are split, the elbow's two against
    the labels and the turned metacarpals for them."""
    take = _take(seed)
    labeled = _flipped(take)
    for e in take_exchanges(labeled, labeled[0], _neighbours(labeled)):
        labeled[e.start : e.stop, [e.a, e.b]] = labeled[e.start : e.stop, [e.b, e.a]]
    for r in take_rotations(labeled, labeled[0], _neighbours(labeled)):
        moved = list(r.markers)
        labeled[r.start : r.stop, moved] = labeled[r.start : r.stop, moved[1:] + moved[:1]]
    wrong = np.linalg.norm(labeled - take, axis=2)[-1, [RSP, USP, HM2, HM5]] > 1e-9
    assert wrong.sum() >= 2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_right_labels_and_one_pair_exchanged_are_no_half_turn(seed: int) -> None:
    take = _take(seed, noise=2.0)
    assert take_flips(take, take[0], _neighbours(take)) == []
    exchanged = take.copy()
    exchanged[FLIP_AT:, [RSP, USP]] = take[FLIP_AT:, [USP, RSP]]
    assert take_flips(exchanged, exchanged[0], _neighbours(exchanged)) == []


def test_the_labeling_gives_a_half_turn_back_and_says_so() -> None:
    take = _take(0)
    labeled = _flipped(take)
    labels = LabeledTrajectories([f"m{k}" for k in range(MARKERS)], labeled, np.zeros((FRAMES, MARKERS), bool), 100.0,
                                 confidence=np.ones((FRAMES, MARKERS)))
    given, exchanges = exchanged_back(labels, MarkerState.from_first_frame(labeled[0], n_neighbours=5))
    assert np.allclose(given.positions[FLIP_AT + 2 :], take[FLIP_AT + 2 :])
    summary = exchange_summary(exchanges, labels.names)
    assert sorted(sorted(s["markers"]) for s in summary) == [["m2", "m3"], ["m4", "m5"]]
    assert all(s["frames"][1] == FRAMES for s in summary)
    assert (given.confidence[FLIP_AT + 2 :, 2:6] <= 0.5).all() and (given.confidence[:, :2] == 1).all()
