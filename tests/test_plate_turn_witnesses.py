"""A turn of a plate read from its own corners alone is denied by the markers rigid with it
(``formulations.markers.witness_costs.witnesses_deny`` in ``plate_turns``)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from formulations.markers.plate_turns import plate_turns
from formulations.markers.state import MarkerState

EQUILATERAL = 43.0 * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
WITNESS = np.array([[70.0, 20.0, 40.0]])  # rigid with the plate, off its axis: its distances tell the corners apart
PLATE_ONLY = np.array([[1, 2], [0, 2], [0, 1], [0, 1]])  # the witness is no corner's neighbour


def _spun_while_lost(frames: int = 260, lost: tuple[int, int] = (100, 130), extra: float = 100.0) -> np.ndarray:
    """``(frames, 4, 3)``: the plate spinning about its own normal 1.5 degrees a frame and
    ``extra`` more while lost whole over ``lost`` (a wrist turning under a full occlusion: 145
    degrees in 30 frames, 25 from a third of a turn), travelling, the witness turning with
    it and seen throughout; 0.5 mm noise."""
    body = np.vstack([EQUILATERAL - EQUILATERAL.mean(axis=0), WITNESS])
    f = np.arange(frames)
    angle = 1.5 * f + extra * np.clip((f - lost[0]) / (lost[1] - lost[0]), 0.0, 1.0)
    turns = Rotation.from_euler("z", angle[:, None], degrees=True)
    points = np.stack([turns[k].apply(body) for k in f]) + f[:, None, None] * np.array([8.0, 3.0, 0.0])
    points += np.random.default_rng(0).normal(0.0, 0.5, points.shape)
    points[lost[0]:lost[1], :3] = np.nan
    return points


def test_a_right_labeling_spun_across_a_loss_is_read_turned_by_the_plate_alone() -> None:
    """The setup: 145 degrees across the loss costs more than 25 and a change of reading, so the
    plate's corners alone read the labels after it as taken round."""
    labels = _spun_while_lost()
    turns = plate_turns(labels, labels[0], PLATE_ONLY)
    assert turns and turns[-1].stop == len(labels) and set(turns[-1].markers) == {0, 1, 2}


def test_the_witness_denies_that_turn() -> None:
    labels = _spun_while_lost()
    assert plate_turns(labels, labels[0], MarkerState.from_first_frame(labels[0], n_neighbours=3).neighbours) == []


def test_an_exchange_the_witness_agrees_with_is_still_given_back() -> None:
    """No extra spin; two corners exchanged over 110-170 after the loss: given back with the
    witness among the neighbours, the witness untouched."""
    truth = _spun_while_lost(extra=0.0)
    labels = truth.copy()
    labels[130:170, :2] = labels[130:170][:, [1, 0]]
    turns = plate_turns(labels, labels[0], MarkerState.from_first_frame(labels[0], n_neighbours=3).neighbours)
    assert [(sorted(t.markers), t.start, t.stop) for t in turns] == [([0, 1], 130, 170)]
