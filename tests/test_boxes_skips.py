"""Boxes with skip arcs (``BoxCostModel(skip_arcs=True)``): a return priced from the object's own last box."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.boxes import kalman
from formulations.boxes.candidates import box_window
from formulations.boxes.conflicts import ConflictRule
from formulations.boxes.costs import BoxCostModel
from formulations.boxes.objects import BoxObjects
from formulations.boxes.reentry import reentry_pricing
from formulations.window.build import build_window
from formulations.window.problem import OBSERVATION, OCCLUSION

VELOCITY = np.array([5.0, 0.0, 0.0, 0.0])  # (cx, cy, w, h) per frame


def _walker() -> BoxObjects:
    """Seen at frame 0 at cx = 120 after 20 frames walking right at 5 px/frame: a settled filter."""
    mean, covariance = kalman.start(np.array([[20.0, 150.0, 40.0, 100.0]]), VELOCITY[None])
    for f in range(1, 21):
        mean, covariance = kalman.predict(mean, covariance)
        mean, covariance = kalman.update(mean, covariance, np.array([[20.0 + 5.0 * f, 150.0, 40.0, 100.0]]))
    return BoxObjects(np.array([1]), mean, covariance, np.array([0]), None)


def _corners(cx: float, cy: float = 150.0) -> np.ndarray:
    return kalman.box_corners(np.array([cx, cy, 40.0, 100.0]))


def test_a_box_where_its_own_forecast_puts_it_costs_the_spread_alone_and_more_the_longer_the_skip():
    objects, model = _walker(), BoxCostModel()
    boxes = np.array([_corners(200.0), _corners(210.0), _corners(215.0), _corners(260.0)])
    price = reentry_pricing(objects.mean, objects.covariance, np.zeros(4, int), np.array([1, 3, 4, 4]), boxes,
                            np.zeros(4), model)
    two, three, far = price(np.array([0, 0, 0]), np.array([1, 2, 3]))
    assert 0 < two < three  # exactly on 2 and 3 frames of own velocity: only the wider spread costs
    assert far == np.inf  # 45 px off in 3 frames: outside the gate, no skip arc


def test_a_return_inside_the_window_is_judged_from_the_path_s_own_last_box():
    # Seen at t0 walking right at 5 px/frame; at frame 1 it has stepped 25 px aside (up), missed in
    # frame 2, and in frame 3 goes on from there. From its own box the return is where expected;
    # the template's forecast would call it 25 px off.
    objects = _walker()
    boxes = np.array([_corners(125.0, 125.0), _corners(135.0, 125.0)])
    frame = np.array([1, 3])
    plain_costs, skip_costs = [], []
    for model, costs in ((BoxCostModel(), plain_costs), (BoxCostModel(skip_arcs=True), skip_costs)):
        posed = box_window(objects, 0, 3, frame, boxes, None, model, ConflictRule())
        problem, node_candidate = build_window(posed.candidates, posed.weights)
        back = (problem.node_kind[problem.arc_tail] == OCCLUSION) & (problem.node_kind[problem.arc_head] == OBSERVATION)
        back &= node_candidate[problem.arc_head] >= 0
        costs.extend(problem.arc_cost[back & (problem.node_frame[problem.arc_head] == 3)])
    assert len(plain_costs) == 1 and len(skip_costs) == 2  # the template's return, and with skips box 1's too
    from_box, from_template = sorted(skip_costs)
    assert from_template == pytest.approx(plain_costs[0])  # unseen since the template: as before
    assert from_box < from_template - 1.0  # 3.96 against 6.19 over c_a
