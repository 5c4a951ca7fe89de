"""A point copied to the last bit (HDM05's ``*0``-``*2`` columns) is no alternative to the label
it copies: both readings put the marker at the same place (``formulations.confidence.same_place``)."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from test_confidence import exact_margins
from windows import random_window

from formulations.confidence import label_confidence
from formulations.confidence.layers import layers
from formulations.methods.registry import get_formulation
from formulations.window.problem import OBSERVATION
from service.capture.capture import Capture, LabelingOptions
from service.evaluation.scene import generate_scene
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.leftover_points import copied_markers, leftover_note, leftover_summary
from service.labeling.stats import reported_doubtful

COPIED = 2  # the marker whose point the scene's file carries twice


def _copied_slot(seed: int):
    """A tiny window where the first label on a point has its other candidate point moved onto it."""
    problem = random_window(seed=seed, n_objects=2, n_frames=3, n_points=3, per_object=2)
    path = get_formulation("ilp").solve(problem).path
    grid = layers(problem, path)
    n, t = next((n, t) for t, n in itertools.product(range(problem.n_frames), range(problem.n_objects))
                if problem.node_kind[path[n, t]] == OBSERVATION)
    other = grid.first[n, t + 1] + 1 - grid.chosen[n, t + 1]  # the other candidate (the occlusion is last)
    location = problem.node_location.copy()
    location[other] = location[path[n, t]]
    return replace(problem, node_location=location), path, grid


@pytest.mark.parametrize("seed", range(4))
def test_a_slot_at_the_chosen_place_counts_for_the_label(seed: int) -> None:
    problem, path, grid = _copied_slot(seed)
    exact = exact_margins(problem, path)  # the costs do not read locations (no layout term)
    chosen = grid.chosen[:, 1:-1]
    place = problem.node_location[grid.nodes(problem)[:, 1:-1]]
    confidence = label_confidence(problem, path)
    grouped = 0
    for n, t in itertools.product(range(problem.n_objects), range(problem.n_frames)):
        at = place[n, t, chosen[n, t]]
        same = [u != chosen[n, t] and (place[n, t, u] == at).all() and grid.valid[n, t + 1, u]
                for u in range(grid.width)]
        weight = np.exp(-np.where(np.isfinite(exact[n, t]), exact[n, t], np.inf))
        weight[chosen[n, t]] = 1.0
        support = weight[chosen[n, t]] + weight[same].sum()
        assert confidence.probability[n, t] == pytest.approx(support / weight.sum())
        others = [d for u, d in enumerate(exact[n, t]) if u != chosen[n, t] and not same[u] and np.isfinite(d)]
        assert confidence.margin[n, t] == pytest.approx(min(others, default=np.inf))
        grouped += any(same)
    assert grouped == 1  # that label, and no other


def _copied_scene() -> tuple[Capture, np.ndarray]:
    """A walking figure whose marker ``COPIED`` has its point twice in every frame."""
    truth = generate_scene(n_frames=60, seed=2)
    rng = np.random.default_rng(2)
    points = []
    for frame in truth.positions:
        noisy = frame + rng.normal(0.0, 0.5, frame.shape)
        points.append(rng.permutation(np.concatenate([noisy, noisy[[COPIED]]])))
    return Capture(list(truth.names), truth.positions[0], truth.rate, points=points), truth.positions


def test_a_copied_point_leaves_its_marker_sure() -> None:
    capture, truth = _copied_scene()
    result, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    assert (np.linalg.norm(result.positions - truth, axis=2) < 5.0).all()  # every label on its own point
    doubtful = reported_doubtful(result.confidence, result.occluded)
    assert not doubtful.any()  # before: the copied marker at p = 1/2 in every frame but the first


def test_the_copy_is_kept_as_an_unlabeled_trajectory_named_as_a_repeat() -> None:
    capture, truth = _copied_scene()
    result, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    summary = leftover_summary(result)
    assert summary["unlabeled_points"] == len(truth)  # the copy, in every frame
    assert copied_markers(result) == [capture.names[COPIED]]
    note = leftover_note(summary)
    assert note.endswith(f"*N (1 repeating a marker's point: {capture.names[COPIED]})")
    result.unlabeled = result.unlabeled + 0.001  # a thousandth of a millimetre off: another point, no copy
    assert copied_markers(result) == []
