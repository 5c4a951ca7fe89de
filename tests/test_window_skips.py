"""Skip arcs (``formulations.window.skips``): the network they build, its costs, and every
formulation on it against brute force."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from windows import assert_feasible, brute_force, objective, random_window

from formulations import get_formulation
from formulations.relaxation.solve_lp import solve_window_lp
from formulations.window.build import build_window
from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights
from formulations.window.objective import arc_index, path_cost
from formulations.window.problem import OCCLUSION

WEIGHTS = ArcCostWeights(displacement=1.0, reappear=3.0, disappear=4.0)


def _one_object(returned_steps: bool = False) -> tuple[WindowCandidates, np.ndarray]:
    """One object, 3 frames, one candidate in frames 1 and 3 (0 and 1); s(0, 1) = 0.5, s(1, 1) unused."""
    skip_table = np.array([[0.0, 0.5], [0.0, 0.0]])
    candidates = WindowCandidates(
        template_location=np.zeros((1, 2)), template_occluded=np.zeros(1, bool), n_frames=3,
        object=np.array([0, 0]), frame=np.array([1, 3]), location=np.array([[1.0, 0.0], [3.0, 0.0]]),
        template_cost=np.array([0.2, 2.0]), resources=sp.csr_matrix(np.eye(2)),
        occlusion_location=np.zeros((1, 3, 2)), motion=np.zeros((1, 3, 2)),
        skip=lambda tail, head: skip_table[tail, head], returned_steps=returned_steps,
    )
    return candidates, skip_table


def test_a_skip_pays_its_misses_and_the_return_from_its_own_last_box():
    candidates, _ = _one_object()
    problem, candidate_of = build_window(candidates, WEIGHTS)
    first, third = (int(np.flatnonzero(candidate_of == c)[0]) for c in (0, 1))
    gap = int(problem.gap_successor[first])
    assert problem.node_kind[gap] == OCCLUSION and problem.node_frame[gap] == 2
    c_ab = WEIGHTS.reappear + WEIGHTS.disappear
    # source -> box 1 (template term + 1 of displacement) -> gap -> box 3 (c_a + s) -> sink
    expected = (0.2 + 1.0) + c_ab + (WEIGHTS.reappear + 0.5) + c_ab
    assert path_cost(problem, np.array([[first, gap, third]])) == pytest.approx(expected)
    # Unseen since the template, box 3 is judged by the template term (2.0), as in Jiang's network.
    plain = problem.frame_nodes()[0] + problem.blocks()[1][0, 1:-1] - 1
    assert path_cost(problem, np.array([[plain[0], plain[1], third]])) == pytest.approx(3 * c_ab + WEIGHTS.reappear + 2.0)
    # After box 1 the path cannot reach the template's occlusion nodes: no return priced by the template.
    with pytest.raises(ValueError, match="not an arc"):
        arc_index(problem, np.array([first]), np.array([plain[1]]))


def test_gap_nodes_hold_no_resource_so_no_conflict_set_binds_a_skipped_frame():
    problem = random_window(3, n_objects=3, n_frames=4, n_points=3, per_object=2, skip=True)
    gaps = (problem.node_kind == OCCLUSION) & (problem.gap_successor >= 0)
    assert gaps.any()
    assert problem.resources[np.flatnonzero(problem.node_kind == OCCLUSION)].nnz == 0
    assert problem.conflict_groups[:, np.flatnonzero(gaps)].nnz == 0


def test_returned_steps_price_the_box_after_a_return_from_the_box_before():
    candidates, _ = _one_object(returned_steps=True)
    candidates = WindowCandidates(**{**vars(candidates), "frame": np.array([1, 2])})  # boxes in frames 1 and 2
    occluded = WindowCandidates(**{**vars(candidates), "template_occluded": np.ones(1, bool)})
    # Seen at the template, the step pays t g(s_n, j) = 2.0; unseen there, the path re-entered
    # at box 1, and the step pays t s(i, j) = 0.5 instead. Both add lambda_2 d = 1.0 * |3 - 1|.
    for posed, step in ((candidates, 2.0), (occluded, 0.5)):
        problem, candidate_of = build_window(posed, WEIGHTS)
        heads = problem.arc_head[problem.arc_tail == problem.source_nodes()[0]]
        first = heads[candidate_of[heads] == 0]
        assert len(first) == 1  # one copy of box 1 after the source: the one its history enters
        second = (problem.arc_tail == first[0]) & (candidate_of[problem.arc_head] == 1)
        assert second.sum() == 1
        assert problem.arc_cost[second][0] == pytest.approx(step + 2.0)


def test_jiang_network_without_skip_pricing_is_fully_connected():
    problem = random_window(1, n_objects=2, n_frames=3, n_points=3, per_object=2)
    _, sizes = problem.blocks()
    assert problem.n_arcs == int((sizes[:, :-1] * sizes[:, 1:]).sum())
    assert (problem.node_kind == OCCLUSION).sum() == problem.n_objects * problem.n_frames  # no gap nodes


@pytest.mark.parametrize("returned_steps", [False, True])
@pytest.mark.parametrize("seed", range(6))
def test_exact_formulations_and_the_lp_honour_skip_windows(seed, returned_steps):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2, skip=True,
                            returned_steps=returned_steps)
    optimum, _ = brute_force(problem)
    ilp = get_formulation("ilp").solve(problem)
    assert_feasible(problem, ilp.path)
    assert objective(problem, ilp.path) == pytest.approx(optimum)
    relaxation = solve_window_lp(problem)
    assert relaxation.bound <= optimum + 1e-7
    for name in ("lp-l1", "nn-hungarian"):
        solution = get_formulation(name).solve(problem)
        assert_feasible(problem, solution.path)
        assert solution.cost == pytest.approx(objective(problem, solution.path))
        assert solution.cost >= optimum - 1e-7
        if solution.integral:
            assert solution.cost == pytest.approx(optimum)


@pytest.mark.parametrize("seed", range(40))
def test_greedy_rounding_of_a_fractional_skip_window_is_feasible(seed):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2, skip=True, returned_steps=True)
    solution = get_formulation("lp-l1", repair=0).solve(problem)
    assert_feasible(problem, solution.path)
