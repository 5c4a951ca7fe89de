"""A marker seen again after a gap moves as its neighbours do, not by its prediction's jump.

An occluded marker's prediction can jump between frames (a neighbour it followed is lost,
the model re-anchors it). Taking that jump as the marker's velocity when it is seen again
puts the next gate off it; it is lost, found again from its neighbours with the jump
reversed, and so on every other frame (CMU 135_02's right forearm, 40 frames).
"""

from dataclasses import replace

import numpy as np

from formulations.markers.guide import guide_track
from formulations.markers.rigid import RIGID_SD_MM
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


def _back_from_a_gap(frames: list[np.ndarray], nudge: np.ndarray, loose: bool = False) -> MarkerState:
    """Every marker seen in ``frames[:3]``, marker 0 unseen at ``frames[3]`` with its prediction
    ``nudge`` off its track, seen again at ``frames[4]``; ``loose``: its neighbours' learned
    distances vary too much for one segment."""
    state = MarkerState.from_first_frame(frames[0], n_neighbours=4)
    for frame in frames[1:3]:
        state = state.advance(frame, np.ones(len(PLATE), bool))
    lost = np.array([True, False, False, False, False])
    state = state.advance(frames[3], ~lost)
    state = replace(state, position=np.where(lost[:, None], state.position + nudge, state.position))
    if loose:
        state = replace(state, distance_var=np.full_like(state.distance_var, 4 * RIGID_SD_MM**2))
    return state.advance(frames[4], np.ones(len(PLATE), bool))


NUDGE = np.array([0.0, 0.0, 6.0])  # within 5 sd of the marker's motion: no jump by that test


def test_a_plausible_velocity_is_kept_off_a_segment():
    """Neighbours not on the marker's segment may move otherwise (a limb turning at a joint):
    a displacement within the marker's motion spread is kept."""
    back = _back_from_a_gap(_frames(0, 5), NUDGE, loose=True)
    assert np.allclose(back.velocity[0], STEP - NUDGE, atol=1e-6)


def test_on_a_segment_a_small_jump_is_not_taken_as_velocity():
    """The same 6 mm was kept on a rigid plate too, and as a still-unseen marker's nearest
    neighbour it pulled that one off (Vicon's STERr and STER)."""
    back = _back_from_a_gap(_frames(0, 5), NUDGE)
    assert np.allclose(back.velocity[0], STEP, atol=1e-6)


def test_a_turning_segment_gives_the_marker_its_own_displacement():
    """The segment's rigid motion at the marker, not its neighbours' mean step: a plate
    turning 0.1 rad a frame."""
    def turned(k: int) -> np.ndarray:
        c, s = np.cos(0.1 * k), np.sin(0.1 * k)
        return (PLATE - PLATE.mean(axis=0)) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + k * STEP
    frames = [turned(k) for k in range(5)]
    back = _back_from_a_gap(frames, NUDGE)
    assert np.allclose(back.velocity[0], frames[4][0] - frames[3][0], atol=1e-6)
    assert not np.allclose(back.velocity[0], (frames[4] - frames[3])[1:].mean(axis=0), atol=1.0)
