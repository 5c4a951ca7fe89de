"""A marker seen again after a gap moves as its neighbours do, not by its prediction's jump.

An occluded marker's prediction can jump between frames (a neighbour it followed is lost,
the model re-anchors it). Taking that jump as the marker's velocity when it is seen again
puts the next gate off it; it is lost, found again from its neighbours with the jump
reversed, and so on every other frame (CMU 135_02's right forearm, 40 frames).
"""

from dataclasses import replace

import numpy as np

from formulations.markers.guide import guide_track
from formulations.markers.state import MarkerState

PLATE = np.array([[0, 0, 0], [80, 0, 0], [0, 90, 0], [70, 60, 30], [40, 10, 90]], float)
STEP = np.array([12.0, 8.0, -10.0])  # mm per frame, every marker
JUMP = np.array([0.0, 90.0, 120.0])  # where the gap's last prediction left marker 0, off its track


def _frames(start: int, count: int) -> list[np.ndarray]:
    return [PLATE + (start + k) * STEP for k in range(count)]


def _rejoined_state() -> MarkerState:
    """Every marker seen in frames 0-1 with its velocity measured; marker 0 unseen in frame
    2 at a prediction ``JUMP`` off its track, and seen again at its point in frame 3."""
    state = MarkerState.from_first_frame(PLATE, n_neighbours=4)
    for frame in _frames(1, 2):
        state = state.advance(frame, np.ones(len(PLATE), bool))
    lost = np.array([True, False, False, False, False])
    state = state.advance(_frames(3, 1)[0], ~lost)
    state = replace(state, position=np.where(lost[:, None], state.position + JUMP, state.position))
    return state.advance(_frames(4, 1)[0], np.ones(len(PLATE), bool))


def test_rejoined_marker_takes_its_neighbours_velocity():
    state = _rejoined_state()
    assert np.allclose(state.velocity[0], STEP, atol=1e-6)
    assert np.allclose(state.velocity[1:], STEP, atol=1e-6)


def test_guide_keeps_a_rejoined_marker_every_frame():
    """The failure this guards against: without the neighbours' velocity the guide loses
    marker 0 every other frame although its point is there in every one."""
    guide = guide_track(_rejoined_state(), _frames(5, 12))
    assert (guide.unseen[1:, 0] == 0).all()


def test_a_plausible_velocity_is_kept():
    """A marker back from a gap whose implied displacement is within its motion's spread
    keeps it (a limb turning moves its markers apart from the mean of its neighbours)."""
    state = MarkerState.from_first_frame(PLATE, n_neighbours=4)
    for frame in _frames(1, 2):
        state = state.advance(frame, np.ones(len(PLATE), bool))
    lost = np.array([True, False, False, False, False])
    state = state.advance(_frames(3, 1)[0], ~lost)
    nudge = np.array([0.0, 0.0, 6.0])
    state = replace(state, position=np.where(lost[:, None], state.position + nudge, state.position))
    back = state.advance(_frames(4, 1)[0], np.ones(len(PLATE), bool))
    assert np.allclose(back.velocity[0], STEP - nudge, atol=1e-6)
