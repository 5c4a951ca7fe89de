"""The shape check of the labels' confidence: a re-acquired marker on another marker's point
is doubtful even when the window's margin is sure, and a clean shape flags nothing."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.confidence.shape import shape_identity, shape_log_density
from formulations.markers.state import MarkerState
from service.labeling.confidence import carried, shape_checked
from service.labeling.stats import DOUBTFUL_BELOW

FRAMES = 5  # new frames of the window
BODY = np.array([[0, 0, 0], [60, 0, 0], [0, 80, 0], [0, 0, 90], [70, 70, 0], [50, 0, 100]], dtype=float)


def _template() -> MarkerState:
    """Six markers of one rigid body, their distances learned tight (s.d. 2 mm)."""
    state = MarkerState.from_first_frame(BODY, n_neighbours=5)
    return replace(state, distance_var=np.full(state.distance_var.shape, 4.0), streak=np.full(len(BODY), 30))


def _end(position: np.ndarray, seen: np.ndarray, streak: np.ndarray) -> MarkerState:
    """The state at the window's last frame, the body moved by 5 mm."""
    state = _template()
    moved = position + np.array([5.0, 0.0, 0.0])
    return replace(state, position=moved, unseen=np.where(seen, 0, 3), streak=np.where(seen, streak, 0))


def _brute_identity(template: MarkerState, end: MarkerState, judged: np.ndarray) -> np.ndarray:
    """p(m) of ``shape.py``'s doc for the ``judged`` markers, hypothesis by hypothesis."""
    n = len(end.position)
    f = np.exp(shape_log_density(template, end, np.arange(n), np.arange(n)))  # f[j, p]: marker j at marker p's position
    partners = set(judged) | {k for m in judged for k in end.neighbours[m] if end.visible[k]}
    p = np.ones(len(judged))
    for r, m in enumerate(judged):
        alternatives = sum(f[j, m] for j in range(n) if not end.visible[j])
        alternatives += sum(f[j, m] * f[m, j] / f[j, j] for j in partners if j != m)
        p[r] = f[m, m] / (f[m, m] + alternatives)
    return p


def test_shape_identity_equals_the_hypotheses_one_by_one() -> None:
    rng = np.random.default_rng(3)
    for _ in range(8):
        seen = rng.random(len(BODY)) < 0.7
        seen[:2] = True
        position = BODY + rng.normal(0, 15, BODY.shape)
        end = _end(position, seen, np.full(len(BODY), 3))
        judged = np.flatnonzero(seen & (rng.random(len(BODY)) < 0.8))
        expected = _brute_identity(_template(), end, judged)
        assert np.allclose(shape_identity(_template(), end, judged), expected, rtol=1e-9, atol=1e-12)


def test_a_marker_reacquired_on_a_lost_neighbours_point_is_doubtful() -> None:
    # Marker 0 comes back (seen for 3 frames) on marker 1's point; marker 1 stays lost,
    # carried to where its neighbours put it. The window's margin is sure of both.
    position = BODY.copy()
    position[0] = BODY[1] + 1.0
    end = _end(position, np.array([True, False, True, True, True, True]), np.array([3, 0, 30, 30, 30, 30]))
    sure = np.ones((FRAMES, len(BODY)))
    occluded = np.zeros_like(sure, dtype=bool)
    occluded[:, 1] = True
    occluded[:2, 0] = True
    checked, carry = shape_checked(carried(sure, np.ones(len(BODY))), occluded, np.ones(len(BODY)), _template(), end)
    assert (carried(sure, np.ones(len(BODY)))[~occluded] >= DOUBTFUL_BELOW).all()  # the margin alone flags nothing
    assert (checked[2:, 0] < DOUBTFUL_BELOW).all() and carry[0] < DOUBTFUL_BELOW
    assert (checked[:, 2:] == 1.0).all()  # the others fit: nothing else flagged


def test_two_reacquired_neighbours_exchanged_are_doubtful() -> None:
    position = BODY.copy()
    position[[2, 4]] = BODY[[4, 2]]
    streak = np.array([30, 30, 4, 30, 4, 30])
    end = _end(position, np.ones(len(BODY), bool), streak)
    sure = np.ones((FRAMES, len(BODY)))
    checked, carry = shape_checked(sure, np.zeros(sure.shape, bool), np.ones(len(BODY)), _template(), end)
    assert (checked[1:, [2, 4]] < DOUBTFUL_BELOW).all() and (carry[[2, 4]] < DOUBTFUL_BELOW).all()
    assert (checked[0, [2, 4]] == 1.0).all()  # before the re-acquisition: not this identity's labels
    assert (checked[:, [0, 1, 3, 5]] >= DOUBTFUL_BELOW).all()


def test_a_clean_shape_flags_nothing() -> None:
    rng = np.random.default_rng(0)
    end = _end(BODY + rng.normal(0, 1.0, BODY.shape), np.ones(len(BODY), bool), np.array([3, 30, 3, 30, 30, 30]))
    assert (shape_identity(_template(), end, np.arange(len(BODY))) > 0.99).all()
    window = np.full((FRAMES, len(BODY)), 0.97)
    before = np.array([1.0, 0.5, 1.0, 1.0, 1.0, 1.0])  # marker 1 was doubtful, and stays so
    checked, carry = shape_checked(carried(window, before), np.zeros(window.shape, bool), before, _template(), end)
    assert np.array_equal(checked, carried(window, before))
    assert np.array_equal(carry, window[-1] * before)
