"""A returning point goes to the lost marker whose return the window prices cheaper, not to the
one predicted nearer in mm (``formulations.markers.guide_returns``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.markers.guide import assign_nearest
from formulations.markers.guide_returns import MARGIN_NATS, return_costs, returns_judged
from formulations.markers.state import MarkerState

BODY = np.array([[0, 0, 0], [60, 0, 0], [0, 80, 0], [0, 0, 90], [300, 0, 0]], dtype=float)
RADIUS = np.full(len(BODY), 200.0)
MISS = 60.0  # the guide's miss cost for a marker unseen last frame (``Gate.radius_mm``)


def _lost(unseen: np.ndarray) -> MarkerState:
    """Markers 0 and 1 lost for ``unseen`` frames, predicted at their first-frame places; the
    others seen. Drift 5 mm^2 a frame, motion residual 9 mm^2 per axis (03_rolling's)."""
    state = MarkerState.from_first_frame(BODY, n_neighbours=3)
    n = len(BODY)
    return replace(state, unseen=unseen, streak=np.where(unseen > 0, 0, 30), motion_var=np.full(n, 9.0),
                   burst_var=np.zeros(n), drift_var=np.full(n, 5.0))


def test_a_point_nearer_a_freshly_lost_marker_goes_to_the_long_lost_one() -> None:
    # 57 mm from marker 0's prediction (lost 17 frames), 73 mm from marker 1's (lost 131): 03_rolling's
    # wrist pair under the scenario, seed 1, frame 315.
    state = _lost(np.array([17, 131, 0, 0, 0]))
    x = (60.0**2 + 57.0**2 - 73.0**2) / 120.0
    point = np.array([[x, -np.sqrt(57.0**2 - x**2), 0.0]])
    assert np.allclose(np.linalg.norm(point - BODY[:2], axis=1), [57.0, 73.0])
    nearest = assign_nearest(BODY, point, RADIUS, MISS)
    assert nearest[0] == 0 and nearest[1] == -1  # the guide alone: the nearer prediction
    cost = return_costs(state, BODY, point)
    assert cost[1, 0] + MARGIN_NATS <= cost[0, 0]  # the window prices marker 1's return lower
    judged = returns_judged(state, BODY, point, nearest, RADIUS)
    assert judged[1] == 0 and judged[0] == -1


def test_equal_spreads_keep_the_nearest_pick() -> None:
    state = _lost(np.array([20, 20, 0, 0, 0]))
    point = BODY[[0]] + np.array([[10.0, 5.0, 0.0]])
    nearest = assign_nearest(BODY, point, RADIUS, MISS)
    assert np.array_equal(returns_judged(state, BODY, point, nearest, RADIUS), nearest)


def test_a_marker_seen_last_frame_keeps_its_point() -> None:
    # Marker 0 was seen the frame before: its point is a step, not a return.
    state = _lost(np.array([0, 131, 0, 0, 0]))
    point = BODY[[0]] + np.array([[0.0, -20.0, 0.0]])
    nearest = assign_nearest(BODY, point, RADIUS, MISS)
    assert nearest[0] == 0
    assert np.array_equal(returns_judged(state, BODY, point, nearest, RADIUS), nearest)


def test_a_point_outside_the_other_gate_stays() -> None:
    state = _lost(np.array([17, 131, 0, 0, 0]))
    point = BODY[[0]] + np.array([[0.0, -57.0, 0.0]])
    nearest = assign_nearest(BODY, point, RADIUS, MISS)
    narrow = RADIUS.copy()
    narrow[1] = 50.0
    assert np.array_equal(returns_judged(state, BODY, point, nearest, narrow), nearest)
