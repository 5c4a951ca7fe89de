"""The path LP (column generation over whole paths) against the arc LP it replaces on large windows."""

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp
from windows import brute_force, random_window

import formulations.relaxation.solve_lp as solve_lp_module
from formulations.relaxation.components import restrict
from formulations.relaxation.lp_model import window_lp
from formulations.relaxation.path_lp import PROVEN, STALLED, _columns, _GroupRows, solve_path_lp
from formulations.relaxation.viterbi import ArcLayers, shortest_path_arcs, shortest_paths
from formulations.solvers import create_backend
from formulations.window.objective import path_arcs

CASES = [(seed, n, per, likelihood) for seed in range(10) for n, per in ((3, 2), (4, 3), (6, 3)) for likelihood in (False, True)]


def arc_lp_value(problem):
    backend = create_backend("highs")
    backend.set_model(window_lp(problem))
    result = backend.solve()
    assert result.optimal
    return result.objective


@pytest.mark.parametrize("seed,n_objects,per_object,likelihood", CASES)
def test_same_optimum_as_the_arc_lp_and_a_flow_in_each_object(seed, n_objects, per_object, likelihood):
    problem = random_window(seed, n_objects=n_objects, n_frames=4, n_points=4, per_object=per_object, likelihood=likelihood)
    result, _ = solve_path_lp(problem)
    assert result.optimal
    value = arc_lp_value(problem)
    # proven to the path LP's relative tolerance (its duals come from an interior point)
    assert result.bound == pytest.approx(value, rel=PROVEN, abs=1e-7)
    assert problem.arc_cost @ result.x == pytest.approx(value, rel=PROVEN, abs=1e-7)
    # xi is a unit flow per object: out of each source 1, conserved at every inner node
    into = np.bincount(problem.arc_head, weights=result.x, minlength=problem.n_nodes)
    out = np.bincount(problem.arc_tail, weights=result.x, minlength=problem.n_nodes)
    assert np.allclose(out[problem.source_nodes()], 1.0)
    inner = (problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames)
    assert np.allclose(into[inner], out[inner])
    assert np.all(problem.conflict_groups @ into <= 1 + 1e-7)


@pytest.mark.parametrize("seed", range(6))
def test_bound_never_above_the_exhaustive_optimum(seed):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=3)
    optimum, _ = brute_force(problem)
    result, _ = solve_path_lp(problem)
    assert result.bound <= optimum + 1e-7


def test_refuses_a_layout_term():
    with pytest.raises(ValueError, match="layout"):
        solve_path_lp(random_window(0, mu=0.5))


@pytest.mark.parametrize("seed", range(8))
def test_viterbi_arcs_are_the_paths_and_their_costs(seed):
    problem = random_window(seed, n_objects=4, n_frames=4, n_points=4, per_object=3)
    cost = problem.arc_cost + np.random.default_rng(seed).uniform(0, 3, problem.n_arcs)
    arcs, distance = shortest_path_arcs(problem, cost, ArcLayers.of(problem))
    path, same = shortest_paths(problem, cost)
    assert np.array_equal(arcs, path_arcs(problem, path))
    assert np.allclose(cost[arcs].sum(axis=1), distance)
    assert np.array_equal(distance, same)


def _needs_rounds(seeds=range(30)):
    """A random window whose path pricing takes more than one round."""
    for seed in seeds:
        problem = random_window(seed, n_objects=6, n_frames=4, n_points=4, per_object=3)
        if not solve_path_lp(problem, max_rounds=1)[0].optimal:
            return problem
    raise AssertionError("no random window needed a second pricing round")


def test_pricing_cut_short_says_so_and_is_not_optimal():
    result, _ = solve_path_lp(_needs_rounds(), max_rounds=1)
    assert result.status == STALLED and not result.optimal


def test_a_stalled_path_lp_hands_the_window_to_the_arc_lp(monkeypatch: pytest.MonkeyPatch):
    problem = _needs_rounds()
    monkeypatch.setattr(solve_lp_module, "MIN_ROUNDS", 1)
    monkeypatch.setattr(solve_lp_module, "ARCS_PER_ROUND", 10**9)
    relaxed = solve_lp_module.solve_window_lp(problem, pricing_min_arcs=0)
    assert relaxed.optimal and relaxed.status != STALLED
    assert relaxed.bound == pytest.approx(arc_lp_value(problem), abs=1e-7)
    assert relaxed.n_variables == problem.n_arcs  # the arc LP's columns, not paths


@pytest.mark.parametrize("seed", range(6))
def test_a_sub_window_takes_its_arc_order_from_the_window_as_its_own_sort(seed):
    problem = random_window(seed, n_objects=6, n_frames=4, n_points=4, per_object=3)
    order = problem.arc_order  # sorted: restrict derives a large sub-window's from it
    for objects in (np.arange(6), np.arange(1, 6), np.array([0, 2, 3, 5])):
        sub, _ = restrict(problem, objects)
        derived = sub.__dict__.get("arc_order")
        assert derived is not None or 2 * sub.n_arcs <= problem.n_arcs
        del sub.__dict__["arc_order"]  # sorted afresh
        if derived is not None:
            assert np.array_equal(derived, sub.arc_order) and derived.dtype == sub.arc_order.dtype
    assert np.array_equal(order, ArcLayers.of(problem).order)


def test_path_columns_are_the_coo_built_matrix_duplicates_summed():
    rng = np.random.default_rng(1)
    for _ in range(100):  # groups spanning frames: a path may cross one twice (an entry of 2)
        n, g, k, m = (int(rng.integers(1, 8)) for _ in range(4))
        node_groups = sp.csc_matrix((rng.random((g, 20)) < 0.3).astype(float))
        problem = SimpleNamespace(n_objects=n, arc_head=rng.integers(0, 20, 60))
        paths, objects = rng.integers(0, 60, (k, m + 1)), rng.integers(0, n, k)
        built = _columns(problem, node_groups, objects, paths, _GroupRows(np.full(g, -1)))
        rows = _GroupRows(np.full(g, -1))
        nodes = problem.arc_head[paths[:, :-1]]
        groups = [node_groups.indices[node_groups.indptr[v]:node_groups.indptr[v + 1]] for v in nodes.ravel()]
        group_rows = n + rows.of(np.concatenate(groups).astype(int))
        column_of = np.repeat(np.repeat(np.arange(k), m), [len(each) for each in groups])
        entries, columns = np.r_[objects, group_rows], np.r_[np.arange(k), column_of]
        coo = sp.csc_matrix((np.ones(len(entries)), (entries, columns)), shape=(n + rows.count, k))
        assert built.shape == coo.shape
        for field in ("indptr", "indices", "data"):
            assert np.array_equal(getattr(built, field), getattr(coo, field))
            assert getattr(built, field).dtype == getattr(coo, field).dtype
