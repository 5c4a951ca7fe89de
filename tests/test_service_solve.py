"""``POST /v1/solve`` over real HTTP: one window answered with its certificate, checked against
the window solved by the formulations themselves (exact DP, the ILP, the LP relaxation)."""

from __future__ import annotations

import numpy as np
import pytest
import test_service_api
from service_fixtures import document_json, generated_capture, nan_array
from test_service_api import JSON, _assert_consistent, _solve, _solved_directly

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling

# The same fixtures as the jobs' tests: a served app (one per module) and a fractional window.
client = test_service_api.client
cluttered = test_service_api.cluttered


def test_solve_answers_one_window_with_its_certificate(client):
    capture = generated_capture(frames=12, seed=4)
    options = LabelingOptions(formulation="ilp", window=12)
    answer = client.post("/v1/solve", content=document_json(capture, options), headers=JSON)
    assert answer.status_code == 200, answer.text
    body = answer.json()
    expected, stats = CaptureLabeling(capture, options).label()
    assert np.array_equal(nan_array(body["positions"]), expected.positions, equal_nan=True)
    certificate = body["certificate"]
    assert certificate["integral"] == stats[0].integral and certificate["cost"] == stats[0].cost
    assert certificate["lower_bound"] <= certificate["cost"] + 1e-9 and certificate["status"] == stats[0].status
    optimum = _solved_directly(capture, "dp-extended")  # exact by dynamic programming: no LP, no HiGHS
    assert certificate["integral"] and certificate["gap"] == pytest.approx(0.0, abs=1e-12)
    assert certificate["cost"] == pytest.approx(optimum.cost, rel=1e-12)
    assert certificate["lower_bound"] == pytest.approx(optimum.cost, rel=1e-9)
    _assert_consistent(certificate)
    longer = client.post("/v1/solve", content=document_json(capture, LabelingOptions(window=5)),
                         headers=JSON)
    assert longer.status_code == 422
    assert longer.json()["message"].startswith("frames: 12 frames is more than one window (window = 5)")


def test_solve_reports_the_gap_of_a_fractional_window(client, cluttered):
    certificate = _solve(client, cluttered, "lp-l1")["certificate"]
    relaxed, optimum = _solved_directly(cluttered, "lp-l1"), _solved_directly(cluttered, "ilp")
    assert not certificate["integral"] and certificate["gap"] > 1e-5 and certificate["status"] == relaxed.status
    assert certificate["cost"] == pytest.approx(relaxed.cost, rel=1e-12)
    assert certificate["lower_bound"] == pytest.approx(relaxed.lower_bound, rel=1e-12)
    # The LP bound is below the 0/1 optimum, and the rounded paths' cost above it.
    assert certificate["lower_bound"] <= optimum.cost <= certificate["cost"]
    _assert_consistent(certificate)


def test_solve_proves_nothing_for_a_heuristic(client, cluttered):
    """nn-hungarian has no bound: its gap is null, not 0, and its cost is above the optimum."""
    certificate = _solve(client, cluttered, "nn-hungarian")["certificate"]
    baseline, optimum = _solved_directly(cluttered, "nn-hungarian"), _solved_directly(cluttered, "ilp")
    assert certificate["gap"] is None and certificate["lower_bound"] is None and not certificate["integral"]
    assert certificate["cost"] == pytest.approx(baseline.cost, rel=1e-12) and certificate["cost"] > optimum.cost
    _assert_consistent(certificate)
