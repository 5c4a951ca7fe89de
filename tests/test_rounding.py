"""Jiang's greedy rounding: the nodes it skips without visiting could never have been taken."""

from __future__ import annotations

import numpy as np
import pytest

import formulations.relaxation.rounding as rounding
from formulations.window.problem import OCCLUSION
from tests.windows import random_window


@pytest.mark.parametrize("seed", range(40))
def test_skipping_nodes_below_their_occlusion_node_changes_no_path(seed, monkeypatch):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2)
    rng = np.random.default_rng(seed)
    # Node values as an LP returns them: mostly 0 or 1, some fractional, ties, and the
    # solver's tiny negatives (rounded away at 9 decimals, or not).
    y = rng.choice([0.0, 0.0, 1.0, 0.5, 0.25, -1e-12, -2e-9, 1e-10], size=problem.n_nodes)
    skipped = ~rounding._takeable(problem, np.round(y, 9), np.arange(problem.n_nodes))
    pruned = rounding.round_greedy(problem, y)
    monkeypatch.setattr(rounding, "_takeable", lambda problem, value, inner: np.ones(len(inner), bool))
    assert np.array_equal(pruned, rounding.round_greedy(problem, y))
    inner = (problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames) & (problem.node_kind != OCCLUSION)
    if seed == 0:
        assert (skipped & inner).any()  # the setup skips some nodes at all
