"""Mirrored neighbours exchanged where no distance tells: the segment's handedness does."""

from dataclasses import replace
from itertools import permutations

import numpy as np
from rigid_scenes import SwingingSegment
from scipy.spatial.transform import Rotation

from formulations.markers.exchange import repair_exchanges
from formulations.markers.mirror import _flipped, _sine, repair_mirrors
from formulations.markers.state import MarkerState

# A foot whose toe (2) and fifth metatarsal (3) mirror each other across the plane of its
# heel (0) and ankle (1): every distance to the heel and the ankle is the same for both.
# A shank marker (4) swings about the ankle, a trunk marker (5) stays far off.
FOOT = np.array([[0, 0, 0], [30, 0, 80], [200, 30, 10], [200, -30, 10]], float)
TOE, MT5 = 2, 3


WALK = SwingingSegment(turn=(0.3, 0.2, 0.5), periods=(9, 13, 17), speed=3.0, sway=40.0, hinge=1, swing=0.6, swing_period=7)


def _frame(t: int, foot: np.ndarray = FOOT) -> np.ndarray:
    """The foot turned and moved rigidly, the shank swung about the ankle."""
    return WALK.frame(t, foot)


def _learned(noise: float, frames: int = 200, foot: np.ndarray = FOOT) -> MarkerState:
    rng = np.random.default_rng(1)
    state = MarkerState.from_first_frame(_frame(0, foot), n_neighbours=5)
    for t in range(1, frames):
        state = state.advance(_frame(t, foot) + rng.normal(0, noise, (6, 3)), np.ones(6, bool))
    return state


def _exchanged(state: MarkerState) -> MarkerState:
    order = np.arange(6)
    order[[TOE, MT5]] = MT5, TOE
    return replace(state, position=state.position[order], velocity=state.velocity[order])


def test_the_sine_is_kept_by_rigid_motion_and_its_sign_flipped_by_any_exchange():
    rng = np.random.default_rng(0)
    for _ in range(20):
        points = rng.normal(0, 100, (4, 3))
        moved = Rotation.random(random_state=rng).apply(points) + rng.normal(0, 500, 3)
        assert np.isclose(_sine(moved), _sine(points))
        for order in permutations(range(4)):
            parity = np.linalg.det(np.eye(4)[list(order)])
            assert np.sign(_sine(points[list(order)])) == parity * np.sign(_sine(points))


def test_mirrored_markers_exchanged_are_given_back_where_distances_cannot_tell():
    state = _learned(noise=1.0)
    swapped = _exchanged(state)
    unchanged, moved = repair_exchanges(swapped, np.zeros((0, 3)))  # the setup fails without it
    assert moved == 0 and np.allclose(unchanged.position, swapped.position)
    repaired, pairs = repair_mirrors(swapped, _frame(0))
    assert pairs == 1
    assert np.allclose(repaired.position, state.position)


def test_right_labels_under_noise_are_left_alone():
    for noise in (0.5, 2.0, 4.0):
        state = _learned(noise)
        kept, pairs = repair_mirrors(state, _frame(0))
        assert pairs == 0 and np.allclose(kept.position, state.position)


def test_no_first_frame_position_no_judgement():
    swapped = _exchanged(_learned(noise=1.0))
    reference = _frame(0)
    reference[TOE] = np.nan
    kept, pairs = repair_mirrors(swapped, reference)
    assert pairs == 0 and np.allclose(kept.position, swapped.position)


def test_a_flip_that_distances_can_see_is_left_to_the_exchange_repair():
    """Toe and fifth metatarsal not mirrored (the fifth 30 mm nearer the heel): the flip is
    seen, but the mirror repair names no partner; the exchange is for the distance-based
    repair to judge by its own bar."""
    foot = FOOT.copy()
    foot[MT5, 0] -= 30.0
    state = _learned(noise=1.0, foot=foot)
    swapped = _exchanged(state)
    kept, pairs = repair_mirrors(swapped, _frame(0, foot))
    assert pairs == 0 and np.allclose(kept.position, swapped.position)
    assert _flipped(swapped.position[[TOE, MT5, 0, 1]], _frame(0, foot)[[TOE, MT5, 0, 1]], 1.0)


def _shrugging(t: int) -> np.ndarray:
    """Clavicle and C7 mirrored across the acromia, the shoulders shrugged up and down by
    12 mm about the clavicle-C7 line (which moves no distance to first order)."""
    lift = 12.0 * np.sin(t / 5)
    return np.array([[0, 50, 0], [0, -50, 0], [150, 0, lift], [-150, 0, lift], [0, 0, -400], [0, 0, 400]], float)


def test_a_near_flat_quadruple_flipping_through_flat_is_no_exchange():
    rng = np.random.default_rng(2)
    state = MarkerState.from_first_frame(_shrugging(8), n_neighbours=5)  # shoulders up
    for t in range(9, 213):  # to shoulders down
        state = state.advance(_shrugging(t) + rng.normal(0, 0.2, (6, 3)), np.ones(6, bool))
    assert np.sign(_sine(state.position[:4])) != np.sign(_sine(_shrugging(8)[:4]))  # flipped, no exchange
    kept, pairs = repair_mirrors(state, _shrugging(8))
    assert pairs == 0 and np.allclose(kept.position, state.position)
