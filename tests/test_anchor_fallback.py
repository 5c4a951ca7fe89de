"""A marker lost while its segment's other markers were hidden follows them once they are back."""

from dataclasses import replace

import numpy as np
from rigid_scenes import SwingingSegment

from formulations.markers.state import MarkerState

# A foot: ankle (0, the hinge of the shank marker), heel (1), toe (2), fifth metatarsal (3),
# first metatarsal (4), navicular (5); then the shank marker (6) and a far trunk marker (7).
FOOT = np.array([[0, 0, 0], [-60, -30, -60], [150, 20, -70], [110, -40, -60], [120, 50, -60], [40, 30, -40]], float)
SWING = SwingingSegment(turn=(0.3, 0.2, 0.4), periods=(15, 20, 12), speed=8.0, sway=40.0, hinge=0, swing=0.8,
                        swing_period=6)
HEEL, TOE, MT5 = 1, 2, 3
LEARN, ANCHOR, LOST = 200, 203, 25  # learned in full until LEARN; MT5 seen last at ANCHOR, then lost LOST frames


def _take(noise: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """``(F, 8, 3)`` true and noisy positions."""
    truth = np.stack([SWING.frame(t, FOOT) for t in range(ANCHOR + LOST + 1)])
    return truth, truth + np.random.default_rng(4).normal(0, noise, truth.shape)


def _seen(t: int) -> np.ndarray:
    """Heel and toe hidden for the three frames up to MT5's last sighting; after it MT5, MT1
    and the navicular hidden while heel and toe are back."""
    seen = np.ones(8, bool)
    if LEARN <= t <= ANCHOR:
        seen[[HEEL, TOE]] = False
    elif t > ANCHOR:
        seen[[MT5, 4, 5]] = False
    return seen


def _at_anchor() -> tuple[MarkerState, np.ndarray, np.ndarray]:
    """The state at MT5's last sighting, the true and the noisy take."""
    truth, noisy = _take()
    state = MarkerState.from_first_frame(noisy[0], n_neighbours=7)
    for t in range(1, ANCHOR + 1):
        state = state.advance(noisy[t], _seen(t))
    return state, truth, noisy


def _errors(state: MarkerState, truth: np.ndarray, noisy: np.ndarray) -> np.ndarray:
    """MT5's prediction error in every frame after its last sighting."""
    errors = []
    for t in range(ANCHOR + 1, ANCHOR + LOST + 1):
        state = state.advance(noisy[t], _seen(t))
        errors.append(np.linalg.norm(state.position[MT5] - truth[t, MT5]))
    return np.array(errors)


def test_a_marker_lost_after_its_mates_follows_them_once_they_are_back():
    """The heel and toe's first step back has a guessed velocity, which leaves MT5 an offset
    (about 16 mm here); after it MT5 moves with the foot, so the offset no longer grows."""
    anchor, truth, noisy = _at_anchor()
    assert anchor.anchor_carried[MT5, list(anchor.neighbours[MT5]).index(HEEL)]  # carried, not seen, at the anchor
    without = replace(anchor, anchor_carried=np.zeros_like(anchor.anchor_carried))
    # The setup fails without it: following the ankle and the swinging shank, across the joint.
    assert _errors(without, truth, noisy).max() > 50.0
    errors = _errors(anchor, truth, noisy)
    # No growth: the fitted trend over the gap, not the spread of 24 noisy errors (0.5 mm noise)
    growth_per_frame = np.polyfit(np.arange(len(errors) - 1), errors[1:], 1)[0]
    assert errors.max() < 20.0 and abs(growth_per_frame) < 0.1


def test_carried_neighbours_are_not_followed_where_three_rigid_ones_were_seen():
    anchor, _, noisy = _at_anchor()
    seen = np.ones(8, bool)
    seen[MT5] = False  # MT1 and the navicular, seen at the anchor, stay seen
    followable = anchor.advance(noisy[ANCHOR + 1], seen)._followable
    carried = anchor.anchor_carried[MT5]
    assert carried.any() and not followable[MT5][carried].any()
