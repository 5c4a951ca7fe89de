"""The boxes' Kalman filter against the information form, and the prediction cost built on it."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.boxes import kalman
from formulations.boxes.costs import BoxCostModel
from formulations.boxes.objects import BoxObjects, advance


def _random_state(rng, n):
    z = np.column_stack([rng.uniform(50, 500, (n, 2)), rng.uniform(20, 80, n), rng.uniform(60, 200, n)])
    mean, covariance = kalman.start(z, rng.normal(0, 2, (n, 4)))
    for _ in range(3):  # correlate position and velocity
        mean, covariance = kalman.predict(mean, covariance)
    return mean, covariance


def test_update_equals_information_form():
    rng = np.random.default_rng(0)
    mean, covariance = _random_state(rng, 5)
    z = mean[:, :4] + rng.normal(0, 5, (5, 4))
    posterior, spread = kalman.update(mean, covariance, z)
    h = np.hstack([np.eye(4), np.zeros((4, 4))])
    for n in range(5):
        r = np.linalg.inv(kalman.innovation(mean[n:n + 1], covariance[n:n + 1])[1][0] - covariance[n, :4, :4])
        information = np.linalg.inv(covariance[n]) + h.T @ r @ h
        expected_cov = np.linalg.inv(information)
        expected = expected_cov @ (np.linalg.solve(covariance[n], mean[n]) + h.T @ r @ z[n])
        np.testing.assert_allclose(posterior[n], expected, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(spread[n], expected_cov, rtol=1e-8, atol=1e-9)


def test_mahalanobis_against_explicit_inverse():
    rng = np.random.default_rng(1)
    mean, covariance = _random_state(rng, 3)
    predicted, s = kalman.innovation(mean, covariance)
    z = rng.uniform(0, 500, (4, 4))
    got = kalman.mahalanobis(z, predicted, s)
    for n in range(3):
        for b in range(4):
            d = z[b] - predicted[n]
            assert got[n, b] == pytest.approx(d @ np.linalg.inv(s[n]) @ d)


def test_forecast_moves_at_the_velocity_and_spreads():
    z = np.array([[100.0, 200.0, 40.0, 100.0]])
    mean, covariance = kalman.start(z, np.array([[3.0, -1.0, 0.0, 0.5]]))
    objects = BoxObjects(np.array([1]), mean, covariance, np.array([0]), None)
    predicted, spread = objects.forecast(6)
    for k in range(6):
        np.testing.assert_allclose(predicted[0, k], z[0] + (k + 1) * np.array([3.0, -1.0, 0.0, 0.5]))
    assert (np.diff(np.linalg.det(spread[0])) > 0).all()


def test_prediction_cost_is_a_likelihood_ratio_that_grows_with_the_gap():
    z = np.array([[100.0, 200.0, 40.0, 100.0]])
    objects = BoxObjects(np.array([1]), *kalman.start(z), np.array([0]), None)
    predicted, spread = objects.forecast(10)
    model = BoxCostModel()
    box = kalman.box_corners(z)
    costs = [model.gate_and_cost(predicted[:, k], spread[:, k], box)[1][0, 0] for k in range(10)]
    # A box exactly where predicted: g = log(det S / det R) / 2, >= 0 and rising with the reach.
    noise = np.diag((kalman.MEASUREMENT_SD * np.array([40.0, 100.0, 40.0, 100.0])) ** 2)
    assert costs[0] == pytest.approx(0.5 * np.log(np.linalg.det(spread[0, 0]) / np.linalg.det(noise)))
    assert costs[0] > 0 and (np.diff(costs) > 0).all()
    # Off by 6 sd of the one-frame spread in x: outside the gate (m^2 = 36), dearer by m^2 / 2.
    off = kalman.box_corners(z + np.array([[6 * np.sqrt(spread[0, 0, 0, 0]), 0, 0, 0]]))
    inside, cost = model.gate_and_cost(predicted[:, 0], spread[:, 0], off)
    assert not inside[0, 0] and cost[0, 0] == pytest.approx(costs[0] + 18.0)


def test_advance_learns_the_velocity_and_keeps_the_last_sighting():
    truth = np.array([4.0, 1.0, 0.0, 0.0])
    start = np.array([[100.0, 200.0, 40.0, 100.0]])
    objects = BoxObjects(np.array([7]), *kalman.start(start), np.array([0]), None)
    frames = np.arange(1, 31)
    boxes = kalman.box_corners(start + frames[:, None] * truth)
    taken = np.where(frames % 5 == 0, -1, frames - 1)[None, :]  # every fifth frame occluded
    taken[0, -1] = -1
    after = advance(objects, 0, taken, boxes, None, 0.2)
    np.testing.assert_allclose(after.mean[0, 4:], truth, atol=0.05)
    np.testing.assert_allclose(after.mean[0, :4], start[0] + 30 * truth, atol=0.5)
    assert after.last_seen[0] == 29
