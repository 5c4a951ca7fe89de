"""A lost marker seen in one frame only keeps its label, but the state carries it as unseen
(``service.labeling.cloud._advance``): one point gives no step, and taken by a lost marker it
is most often a ghost that would send the prediction astray."""

import numpy as np
import pytest

import service.labeling.cloud as cloud_module
from formulations.markers.state import MarkerState
from service.labeling.cloud import _advance, _lone_sightings

# Two rigid plates of four, 300 mm apart, walking along x at 5 mm a frame
PLATE = np.array([[0, 0, 0], [60, 5, 0], [10, 70, 5], [55, 60, 40]], float)
BODY = np.vstack([PLATE, PLATE + [300.0, 0.0, 0.0]])
STEP = np.array([5.0, 0.0, 0.0])


def _lost_state(lost_for: int) -> MarkerState:
    """Tracked 40 frames, then marker 0 unseen ``lost_for`` frames while the rest walk on."""
    state = MarkerState.from_first_frame(BODY, n_neighbours=7)
    for t in range(40):
        state = state.advance(BODY + t * STEP, np.ones(len(BODY), bool))
    seen = np.arange(len(BODY)) != 0
    for t in range(40, 40 + lost_for):
        state = state.advance(BODY + t * STEP, seen)
    return state


def test_lone_is_a_label_with_none_the_frame_before_nor_after_and_never_the_last_frame() -> None:
    taken = np.full((4, 5), -1)
    taken[0, [0, 1]] = 0  # seen at the template and on: not lone
    taken[1, 2] = 1  # unseen at the template, one frame only: lone
    taken[2, 0] = 2  # seen at the template, then gone: not lone (a frame before)
    taken[3, 4] = 3  # the window's last frame: the next window may go on from it
    visible = np.array([True, False, True, False])
    lone = _lone_sightings(taken, visible)
    assert lone.tolist() == [[False] * 5, [False, False, True, False, False], [False] * 5, [False] * 5]


def test_a_lone_ghost_does_not_move_the_lost_marker_s_state(monkeypatch: pytest.MonkeyPatch) -> None:
    state = _lost_state(10)  # frames 0-49 read
    # frames 50-54: markers 1-7 as points 0-6, and a ghost 250 mm from marker 0 as point 7
    walked = [BODY + t * STEP for t in range(50, 55)]
    frames = [np.vstack([body[1:], body[0] + [0.0, 250.0, 0.0]]) for body in walked]
    taken = np.vstack([np.full((1, 5), -1), np.tile(np.arange(7)[:, None], (1, 5))])
    taken[0, 2] = 7  # marker 0 takes the ghost in the window's third frame only
    lone = _lone_sightings(taken, state.visible)
    assert lone[0, 2] and lone.sum() == 1
    kept, _ = _advance(state, frames, taken)
    truth = walked[-1][0]
    assert kept.unseen[0] == 15 and np.linalg.norm(kept.position[0] - truth) < 20.0
    # the setup fails without the rule: the ghost becomes the marker's last sighting
    monkeypatch.setattr(cloud_module, "_lone_sightings", lambda taken, visible: np.zeros(taken.shape, bool))
    moved, _ = _advance(state, frames, taken)
    assert moved.unseen[0] == 2 and np.linalg.norm(moved.position[0] - truth) > 200.0
