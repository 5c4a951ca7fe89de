"""Mirror-image markers exchanged over a take, given back by handedness
(``formulations.markers.take_mirror``): distances cannot see the exchange, the signed volume can."""

from __future__ import annotations

import numpy as np

from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import take_exchanges
from formulations.markers.take_mirror import take_mirrors

FRAMES = 200
TOE, FIFTH = 2, 3  # mirror images across the plane of heel and ankle


def _foot(ankle_height: np.ndarray) -> np.ndarray:
    """``(F, 4, 3)`` heel, ankle, toe and fifth metatarsal turning and walking, the ankle at
    ``ankle_height`` (mm per frame) over the heel; 0.5 mm noise."""
    frames = []
    for f in range(FRAMES):
        body = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, ankle_height[f]], [140.0, 30.0, 0.0], [140.0, -30.0, 0.0]])
        angle = 0.01 * f
        turn = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]])
        frames.append(body @ turn.T + [5.0 * f, 0.0, 100.0])
    return np.stack(frames) + np.random.default_rng(0).normal(0.0, 0.5, (FRAMES, 4, 3))


def _neighbours(truth: np.ndarray) -> np.ndarray:
    return MarkerState.from_first_frame(truth[0], n_neighbours=3).neighbours


def test_an_exchange_distances_cannot_see_is_given_back_by_handedness() -> None:
    truth = _foot(np.full(FRAMES, 60.0))
    labels = truth.copy()
    labels[80:150, [TOE, FIFTH]] = truth[80:150][:, [FIFTH, TOE]]
    assert take_exchanges(labels, truth[0], _neighbours(truth)) == []  # the setup: every distance fits
    mirrors = take_mirrors(labels, truth[0], _neighbours(truth))
    assert [(sorted(m.markers), m.start, m.stop) for m in mirrors] == [([TOE, FIFTH], 80, 150)]


def test_a_right_labeling_is_left_alone() -> None:
    truth = _foot(np.full(FRAMES, 60.0))
    assert take_mirrors(truth, truth[0], _neighbours(truth)) == []


def test_a_quadruple_the_pose_turns_through_flat_does_not_judge() -> None:
    """The ankle swinging through the plane of the foot (a joint, not a segment), toe and fifth
    both lost where it crosses (where an exchange may start or stop): right labels whose
    quadruple's sign turns over half the take are no exchange."""
    truth = _foot(60.0 * np.cos(2 * np.pi * np.arange(FRAMES) / 120))
    labels = truth.copy()
    for crossing in (30, 90, 150):
        labels[crossing - 2:crossing + 3, [TOE, FIFTH]] = np.nan
    assert take_mirrors(labels, truth[0], _neighbours(truth)) == []


def test_one_markers_quadruple_turned_by_a_loose_mate_is_no_exchange() -> None:
    """a's quadruple has a loose mate d swinging through its plane (turned over frames 30-90);
    b's quadruple is not labeled whole there (its mate f lost); both a and b lost where d
    crosses, where an exchange may start. a's flips alone are no exchange of a and b."""
    c, a, b, f, d = range(5)
    t = np.arange(FRAMES)
    swing = 30.0 * np.clip(3 * np.cos(2 * np.pi * t / 120), -1.0, 1.0)
    body = np.array([[20.0, 0, 0], [60, 0, 0], [60, 40, 0], [20, 40, 20], [70, -20, 0]])
    truth = np.repeat(body[None], FRAMES, axis=0) + np.random.default_rng(1).normal(0.0, 0.3, (FRAMES, 5, 3))
    truth[:, d, 2] += swing
    labels = truth.copy()
    labels[31:90, f] = np.nan
    for crossing in (30, 90, 150):
        labels[crossing - 2:crossing + 3, [a, b]] = np.nan
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=3).neighbours
    assert take_mirrors(labels, truth[0], neighbours) == []
