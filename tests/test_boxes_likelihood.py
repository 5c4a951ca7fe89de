"""Box arcs priced as negative log-likelihoods: against sampled steps and explicit Gaussian densities."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from formulations.boxes import kalman
from formulations.boxes.candidates import box_window
from formulations.boxes.conflicts import ConflictRule
from formulations.boxes.costs import BoxCostModel
from formulations.boxes.likelihood import DetectionRates, clutter_volume
from formulations.boxes.objects import BoxObjects
from formulations.window.build import build_window
from formulations.window.problem import OBSERVATION, OCCLUSION
from service.boxes.detections import BoxDetections
from service.boxes.track import track_boxes

TO_CORNERS = np.array([[1.0, 0, -0.5, 0], [0, 1.0, 0, -0.5], [1.0, 0, 0.5, 0], [0, 1.0, 0, 0.5]])


def test_step_variance_matches_sampled_steps():
    # Sample the model: velocity off its estimate by P_vv, k frames of velocity noise, one of
    # position noise, two measurements; the corner step's variance is what step_variance says.
    rng = np.random.default_rng(0)
    size, k, samples = np.array([40.0, 100.0]), 3, 200_000
    wh = np.r_[size, size]
    p_vv = np.diag([1.5, 2.0, 0.3, 0.8]) ** 2
    velocity = rng.multivariate_normal(np.zeros(4), p_vv, samples)
    velocity += rng.normal(0, np.sqrt(k) * kalman.VELOCITY_SD * wh, (samples, 4))
    step = velocity + rng.normal(0, kalman.POSITION_SD * wh, (samples, 4))
    step += rng.normal(0, kalman.MEASUREMENT_SD * wh, (samples, 4)) - rng.normal(0, kalman.MEASUREMENT_SD * wh, (samples, 4))
    sampled = (step @ TO_CORNERS.T).var(axis=0).mean()
    expected = kalman.step_variance(size[None], p_vv[None], np.array([float(k)]))[0]
    assert sampled == pytest.approx(expected, rel=0.01)


def test_detection_rates_prior_and_counts():
    assert DetectionRates().detection_probability == pytest.approx(0.9)
    assert DetectionRates().false_alarms_per_frame == 0.5
    rates = DetectionRates().counted(hits=80, misses=20, spare=30, frames=10)
    assert rates.detection_probability == pytest.approx(98 / 120)
    assert rates.false_alarms_per_frame == pytest.approx(3.0)
    assert DetectionRates().counted(0, 1000, 0, 1).detection_probability == 0.5


def _arc(problem, tail, head):
    k = np.flatnonzero((problem.arc_tail == tail) & (problem.arc_head == head))
    return float(problem.arc_cost[k[0]])


def test_arcs_are_log_likelihood_ratios():
    # Object 0 seen at the template, object 1 not (last seen 3 frames before): one box each, in frame 1.
    z0 = np.array([[200.0, 300.0, 40.0, 100.0], [450.0, 300.0, 50.0, 120.0]])
    mean, covariance = kalman.start(z0, np.array([[2.0, 0.0, 0.0, 0.0], [-1.0, 0.5, 0.0, 0.0]]))
    objects = BoxObjects(np.array([1, 2]), mean, covariance, np.array([10, 7]), None)
    box = kalman.box_corners(z0 + np.array([[3.0, -1.0, 1.0, 2.0], [-4.0, 2.0, -1.0, 1.0]]))
    rates = DetectionRates(hits=50, misses=10, spare=20, frames=10)
    image = np.array([0.0, 0.0, 640.0, 480.0])
    posed = box_window(objects, 10, 1, np.array([11, 11]), box, None, BoxCostModel(), ConflictRule(), rates, image)
    problem, node_candidate = build_window(posed.candidates, posed.weights)
    p_d = rates.detection_probability
    log_fa = np.log(rates.false_alarms_per_frame / clutter_volume(image, box))
    predicted, spread = objects.forecast(1)
    nodes = {}
    for n in range(2):
        obs = np.flatnonzero((problem.node_object == n) & (problem.node_kind == OBSERVATION))
        mine = obs[np.append(posed.detection, -1)[node_candidate[obs]] == n]
        occlusion = np.flatnonzero((problem.node_object == n) & (problem.node_kind == OCCLUSION))[0]
        nodes[n] = (problem.source_nodes()[n], mine[0], occlusion)
    # Seen object, step sd at the size of the box stepped into:
    # box minus miss = -log N(step; 0, s^2 I) - log P_D + log lambda - (-log(1 - P_D)), up to
    # the step loss's burst share, which adds less than 1e-6 this near the Gaussian core.
    source, node, occlusion = nodes[0]
    s2 = kalman.step_variance(kalman.measurement(box[:1])[:, 2:], covariance[:1, 4:, 4:], np.array([1.0]))[0]
    step = box[0] - kalman.box_corners(z0[0]) - kalman.corner_rates(mean[0])
    expected = -multivariate_normal(np.zeros(4), s2 * np.eye(4)).logpdf(step) - np.log(p_d) + log_fa + np.log1p(-p_d)
    assert _arc(problem, source, node) - _arc(problem, source, occlusion) == pytest.approx(expected, abs=1e-6)
    # Unseen object: reappearing is priced by its forecast, widened by the 3 frames since it was seen.
    source, node, occlusion = nodes[1]
    forecast = multivariate_normal(predicted[1, 0], spread[1, 0]).logpdf(kalman.measurement(box[1]))
    expected = -forecast - np.log(p_d) + log_fa + np.log1p(-p_d)
    assert _arc(problem, source, node) - _arc(problem, source, occlusion) == pytest.approx(expected, abs=1e-6)
    assert problem.arc_cost.min() >= 0


def test_births_deaths_and_identities_with_likelihood_costs():
    # Two people walking towards each other and past; a third enters later; the first leaves.
    rng = np.random.default_rng(3)
    rows = []
    for f in range(1, 41):
        rows.append((f, 100 + 6 * f, 200, 40, 100))
        rows.append((f, 500 - 6 * f, 210, 42, 105))
        if f >= 20:
            rows.append((f, 300, 50 + 2 * f, 30, 80))
    r = np.array(rows, float)
    r[:, 1:3] += rng.normal(0, 1.5, (len(r), 2))
    detections = BoxDetections(r[:, 0].astype(int), r[:, 1:], np.ones(len(r)), 40, (640.0, 480.0))
    tracks = track_boxes(detections, "lp-l1", window=5, likelihood=True).tracks
    # Every box taken but the newcomer's first (frame 20): in the window 17..21 its chain is 2 < min_hits boxes.
    assert len(tracks.frame) == len(r) - 1 and not ((tracks.frame == 20) & (tracks.box[:, 2] == 30)).any()
    for width in (40, 42, 30):  # each person one identity throughout, the newcomer from its first box
        assert len(set(tracks.track_id[tracks.box[:, 2] == width])) == 1
    assert len(set(tracks.track_id)) == 3
