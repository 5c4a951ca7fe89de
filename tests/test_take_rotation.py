"""Three markers whose labels went round for the rest of a take, given back on the say of the
labeled first frame (``formulations.markers.take_rotation``): the traced CMU 135_02 left foot
(heel, ankle and fifth metatarsal each on the next one's point for the last 700 frames), which
no pair exchange undoes."""

import numpy as np
import pytest
from rigid_scenes import SwingingSegment

from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import take_exchanges
from formulations.markers.take_rotation import take_rotations
from service.io.recording import LabeledTrajectories
from service.labeling.exchanged import exchange_summary, exchanged_back

# A foot: heel (0), ankle (1), fifth metatarsal (2), toe (3), 60-150 mm apart; a shank marker
# swings about the ankle (4), a far one stays (5).
FOOT = np.array([[0, 0, 0], [40, 10, 70], [150, -40, 5], [190, 0, 0]], float)
HEEL, ANKLE, MT5 = 0, 1, 2
WALK = SwingingSegment(turn=(0.5, 0.3, 0.9), periods=(11, 13, 7), speed=6.0, sway=40.0, hinge=1, swing=0.7, swing_period=9)
FRAMES, ROUND_AT = 500, 300


def _take(seed: int, noise: float = 1.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.stack([WALK.frame(t, FOOT) for t in range(FRAMES)]) + rng.normal(0, noise, (FRAMES, 6, 3))


def _round(take: np.ndarray) -> np.ndarray:
    """The heel on the ankle's point, the ankle on the metatarsal's, the metatarsal on the heel's."""
    labeled = take.copy()
    labeled[ROUND_AT:, [HEEL, ANKLE, MT5]] = take[ROUND_AT:, [ANKLE, MT5, HEEL]]
    return labeled


def _neighbours(labeled: np.ndarray) -> np.ndarray:
    return MarkerState.from_first_frame(labeled[0], n_neighbours=4).neighbours


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_labels_gone_round_come_back_from_where_they_went(seed: int) -> None:
    labeled = _round(_take(seed))
    (found,) = take_rotations(labeled, labeled[0], _neighbours(labeled))
    assert abs(found.start - ROUND_AT) <= 2 and found.stop == FRAMES
    given = labeled.copy()
    markers = list(found.markers)
    given[found.start :, markers] = labeled[found.start :, markers[1:] + markers[:1]]
    right = np.linalg.norm(given - _take(seed), axis=2)[ROUND_AT + 2 :] < 1e-9
    assert right.all()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_pair_exchange_undoes_a_rotation(seed: int) -> None:
    """The setup the rotation is for: the pair exchanges leave at least two of the three wrong."""
    take = _take(seed)
    labeled = _round(take)
    for e in take_exchanges(labeled, labeled[0], _neighbours(labeled)):
        labeled[e.start : e.stop, [e.a, e.b]] = labeled[e.start : e.stop, [e.b, e.a]]
    wrong = np.linalg.norm(labeled - take, axis=2)[-1, [HEEL, ANKLE, MT5]] > 1e-9
    assert wrong.sum() >= 2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_right_labels_and_a_pair_exchange_are_no_rotation(seed: int) -> None:
    take = _take(seed, noise=2.0)
    assert take_rotations(take, take[0], _neighbours(take)) == []
    exchanged = take.copy()
    exchanged[ROUND_AT:, [HEEL, ANKLE]] = take[ROUND_AT:, [ANKLE, HEEL]]
    assert take_rotations(exchanged, exchanged[0], _neighbours(exchanged)) == []


def test_the_labeling_gives_a_rotation_back_and_says_so() -> None:
    take = _take(0)
    labeled = _round(take)
    labels = LabeledTrajectories([f"m{k}" for k in range(6)], labeled, np.zeros((FRAMES, 6), bool), 100.0,
                                 confidence=np.ones((FRAMES, 6)))
    given, exchanges = exchanged_back(labels, MarkerState.from_first_frame(labeled[0], n_neighbours=4))
    assert np.allclose(given.positions[ROUND_AT + 2 :], take[ROUND_AT + 2 :])
    (summary,) = exchange_summary(exchanges, labels.names)
    assert sorted(summary["markers"]) == ["m0", "m1", "m2"] and summary["frames"][1] == FRAMES
    assert (given.confidence[ROUND_AT + 2 :, :3] <= 0.5).all() and (given.confidence[:, 3:] == 1).all()
