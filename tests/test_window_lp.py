"""The window LP against exhaustive search and against a plain cvxpy model."""

import pytest
from windows import assert_feasible, brute_force, objective, random_window

from formulations.methods.lp_l1 import LpL1
from formulations.methods.lp_l1_cvxpy import LpL1Cvxpy
from formulations.relaxation.viterbi import shortest_paths
from formulations.window.objective import conflicts, path_cost

TINY = [(seed, n_obj, per_object) for seed in range(12) for n_obj, per_object in ((2, 2), (3, 2), (3, 3))]


@pytest.mark.parametrize("seed,n_objects,per_object", TINY)
@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_lp_bound_and_rounding_against_brute_force(seed, n_objects, per_object, mu):
    problem = random_window(seed, n_objects=n_objects, n_frames=3, n_points=3, per_object=per_object, mu=mu)
    optimum, _ = brute_force(problem)
    solution = LpL1(decompose=False).solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.lower_bound <= optimum + 1e-6
    assert solution.cost >= optimum - 1e-6
    assert solution.cost == pytest.approx(objective(problem, solution.path))
    if solution.integral:
        assert solution.cost == pytest.approx(optimum, abs=1e-6)
        assert solution.gap == pytest.approx(0.0, abs=1e-9)


def test_shared_candidates_make_independent_paths_infeasible():
    """The setup needs the conflict rows: alone, objects collide; the LP keeps them apart."""
    collided = [s for s in range(40) if len(conflicts(p := random_window(s, n_points=3), shortest_paths(p)[0]))]
    assert len(collided) >= 5
    for seed in collided[:5]:
        problem = random_window(seed, n_points=3)
        solution = LpL1().solve(problem)
        assert_feasible(problem, solution.path)
        assert solution.components.get("coupled", 0) >= 1


def test_fractional_windows_occur_with_layout_and_are_certified():
    """With the L1 layout term some LPs are fractional: the certificate must show a gap then."""
    fractional = 0
    for seed in range(15):
        problem = random_window(seed, n_frames=3, n_points=4, per_object=2, mu=0.3)
        solution = LpL1(decompose=False).solve(problem)
        assert_feasible(problem, solution.path)
        if not solution.integral:
            fractional += 1
            assert solution.n_fractional > 0
            assert solution.cost >= solution.lower_bound - 1e-9
    assert fractional >= 1


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("mu", [0.0, 0.25])
def test_sparse_build_equals_cvxpy_model(seed, mu):
    problem = random_window(seed, n_objects=3, n_frames=4, n_points=5, per_object=3, mu=mu)
    fast = LpL1(decompose=False).solve(problem)
    reference = LpL1Cvxpy().solve(problem)
    assert fast.lower_bound == pytest.approx(reference.lower_bound, abs=1e-6)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_column_generation_reaches_the_full_lp_optimum(seed, mu):
    problem = random_window(seed, n_objects=3, n_frames=6, n_points=8, per_object=6, mu=mu)
    full = LpL1(decompose=False, pricing_min_arcs=10**9).solve(problem)
    priced = LpL1(decompose=False, pricing_min_arcs=0, pricing_successors=1).solve(problem)
    assert priced.lower_bound == pytest.approx(full.lower_bound, abs=1e-7)


@pytest.mark.parametrize("seed", range(10))
def test_decomposition_keeps_bound_and_cost(seed):
    problem = random_window(seed, n_objects=4, n_frames=4, n_points=6, per_object=2)
    whole = LpL1(decompose=False).solve(problem)
    split = LpL1(decompose=True).solve(problem)
    assert split.lower_bound == pytest.approx(whole.lower_bound, abs=1e-6)
    if whole.integral and split.integral:
        assert split.cost == pytest.approx(whole.cost, abs=1e-6)


def test_viterbi_is_the_single_object_optimum():
    for seed in range(8):
        problem = random_window(seed, n_objects=1, n_frames=4, n_points=4, per_object=3)
        optimum, _ = brute_force(problem)
        path, cost = shortest_paths(problem)
        assert cost[0] == pytest.approx(optimum)
        assert path_cost(problem, path) == pytest.approx(optimum)
