"""The confidence of every label (issue 13, item 5) against every reading of tiny windows."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from windows import arc_table, contested, layout_term, random_window

from formulations.confidence import label_confidence
from formulations.confidence.layers import layers
from formulations.confidence.margins import reading_margins
from formulations.methods.registry import get_formulation


def every_reading(problem):
    """All feasible readings ``(J, N, M)`` and their objective, by enumeration (own arc lookup)."""
    first, sizes = (b[:, 1:-1] for b in problem.blocks())
    table, groups = arc_table(problem), contested(problem)
    sources, sinks = problem.source_nodes(), problem.sink_nodes()
    paths, costs, usage = [], [], []
    for n in range(problem.n_objects):
        own = np.array(list(itertools.product(*[range(first[n, m], first[n, m] + sizes[n, m])
                                                for m in range(problem.n_frames)])))
        paths.append(own)
        costs.append(np.array([sum(table[s] for s in zip([sources[n], *p], [*p, sinks[n]])) for p in own.tolist()]))
        usage.append(groups[own].sum(axis=1))
    choice = np.stack([g.ravel() for g in np.meshgrid(*[np.arange(len(p)) for p in paths], indexing="ij")], axis=1)
    feasible = (sum(usage[n][choice[:, n]] for n in range(problem.n_objects)) <= 1).all(axis=1)
    choice = choice[feasible]
    joint = np.stack([paths[n][choice[:, n]] for n in range(problem.n_objects)], axis=1)
    total = sum(costs[n][choice[:, n]] for n in range(problem.n_objects))
    total = total + np.array([layout_term(problem, q) for q in joint]) if len(problem.layout_pairs) else total
    return joint, np.asarray(total, dtype=float)


def exact_margins(problem, path, most_moved=None):
    """Delta(n, t, u) by enumeration, over readings moving at most ``most_moved`` objects off ``path``."""
    joint, total = every_reading(problem)
    chosen_cost = total[np.all(joint == path, axis=(1, 2))][0]
    if most_moved is not None:
        moved = (joint != path).any(axis=2).sum(axis=1)
        joint, total = joint[moved <= most_moved], total[moved <= most_moved]
    grid = layers(problem, path)
    margin = np.full((problem.n_objects, problem.n_frames, grid.width), np.inf)
    for q, cost in zip(joint, total):
        slots = q - grid.first[:, 1:-1]
        n, t = np.indices(slots.shape)
        margin[n, t, slots] = np.minimum(margin[n, t, slots], cost - chosen_cost)
    return margin


def margins_of(problem, path, horizon=np.inf):
    return reading_margins(problem, path, horizon)[0]


CASES = [dict(seed=s, n_objects=2, n_frames=3, n_points=3, per_object=2) for s in range(6)] + [
    dict(seed=s, n_objects=2, n_frames=3, n_points=3, per_object=2, mu=0.5) for s in range(3)
]


@pytest.mark.parametrize("case", CASES)
def test_two_objects_margins_equal_the_enumerated_ones(case):
    problem = random_window(**case)
    for name in ("ilp", "nn-hungarian"):  # an optimum and a heuristic answer (negative margins)
        path = get_formulation(name).solve(problem).path
        assert np.allclose(margins_of(problem, path), exact_margins(problem, path), atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_three_objects_margins_are_the_two_object_moves_and_bound_the_rest(seed, mu):
    problem = random_window(seed=seed, n_objects=3, n_frames=3, n_points=3, per_object=2, mu=mu)
    path = get_formulation("ilp").solve(problem).path
    ours = margins_of(problem, path)
    assert np.allclose(ours, exact_margins(problem, path, most_moved=2), atol=1e-9)
    exact = exact_margins(problem, path)
    assert (ours >= exact - 1e-9).all()


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_objects_of_different_widths_have_the_enumerated_margins(seed, mu):
    # 1, 2 and 4 candidates a frame: each object's steps in a batch of its own width (``layers``)
    problem = random_window(seed=seed, n_objects=3, n_frames=3, n_points=4, per_object=(1, 2, 4), mu=mu)
    path = get_formulation("ilp").solve(problem).path
    assert len(layers(problem, path).batches) == 3
    assert np.allclose(margins_of(problem, path), exact_margins(problem, path, most_moved=2), atol=1e-9)


def test_probability_is_the_max_marginal_formula_on_every_label():
    problem = random_window(seed=2, n_objects=2, n_frames=3, n_points=3, per_object=2)
    path = get_formulation("ilp").solve(problem).path
    exact = exact_margins(problem, path)
    confidence = label_confidence(problem, path, scale=2.0)
    chosen = layers(problem, path).chosen[:, 1:-1]
    for n, t in itertools.product(range(problem.n_objects), range(problem.n_frames)):
        others = [d for u, d in enumerate(exact[n, t]) if u != chosen[n, t] and np.isfinite(d)]
        assert confidence.probability[n, t] == pytest.approx(1 / (1 + sum(np.exp(-d / 2.0) for d in others)))
        assert confidence.margin[n, t] == pytest.approx(min(others, default=np.inf))


@pytest.mark.parametrize("seed", range(4))
def test_a_horizon_drops_only_alternatives_beyond_it(seed):
    problem = random_window(seed=seed, n_objects=3, n_frames=4, n_points=4, per_object=3)
    path = get_formulation("lp-l1").solve(problem).path
    every, near = margins_of(problem, path), margins_of(problem, path, horizon=2.0)
    within = every <= 2.0
    assert np.allclose(near[within], every[within])
    assert (near[~within] >= every[~within]).all()  # beyond it a margin may only come out larger
    assert (~within & np.isfinite(every)).any()  # something was beyond the horizon
