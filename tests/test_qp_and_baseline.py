"""``qp-l2`` (squared-L2 layout QP) and ``nn-hungarian`` (frame-by-frame baseline)."""

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
from windows import assert_feasible, brute_force, objective, random_window

from formulations.errors import FormulationError
from formulations.methods.lp_l1 import LpL1
from formulations.methods.nn_hungarian import NnHungarian
from formulations.methods.qp_l2 import QpL2, _layout_operator
from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE, WindowProblem


@pytest.mark.parametrize("seed", range(6))
def test_qp_without_layout_is_the_lp(seed):
    problem = random_window(seed, n_objects=3, n_frames=4, n_points=4, per_object=3, mu=0.0)
    _, qp = QpL2.relax(problem)
    assert qp.status == "optimal"
    assert qp.value == pytest.approx(LpL1(decompose=False).solve(problem).lower_bound, abs=1e-5)
    solution = QpL2(decompose=False).solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.cost == pytest.approx(objective(problem, solution.path))


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("mu", [0.3, 1.5])
def test_qp_bound_is_below_the_l1_optimum(seed, mu):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2, mu=mu)
    optimum, _ = brute_force(problem)
    arc = QpL2(decompose=False).solve(problem)
    tight = QpL2(bound="l1-lp").solve(problem)
    for solution in (arc, tight):
        assert_feasible(problem, solution.path)
        assert solution.lower_bound <= optimum + 1e-7
        assert solution.cost >= optimum - 1e-7
        if solution.integral:
            assert solution.cost == pytest.approx(optimum, abs=1e-7)
    assert tight.lower_bound >= arc.lower_bound - 1e-7


@pytest.mark.parametrize("seed", range(4))
def test_layout_operator_is_the_squared_l2_term_on_integral_paths(seed):
    problem = random_window(seed, n_objects=3, n_frames=4, mu=0.7, dim=3)
    path = NnHungarian().solve(problem).path
    y = np.zeros(problem.n_nodes)
    y[path.ravel()] = 1.0
    p = problem.node_location[path]  # (N, M, D)
    a, b = problem.layout_pairs.T
    direct = problem.layout_weight @ (np.diff(p[a] - p[b], axis=1) ** 2).sum(axis=(1, 2))
    assert np.sum((_layout_operator(problem) @ y) ** 2) == pytest.approx(direct)


def test_qp_value_is_no_bound_on_the_l1_objective():
    """Why the QP value is not reported as the bound: v^2 > |v| for |v| > 1."""
    above = []
    for seed in range(10):
        for mu in (0.5, 2.0):
            problem = random_window(seed, n_objects=2, n_frames=3, n_points=3, per_object=2, mu=mu)
            above.append(QpL2.relax(problem)[1].value > brute_force(problem)[0] + 1e-6)
    assert any(above)


@pytest.mark.parametrize("seed", range(4))
def test_qp_decomposition_keeps_the_bound(seed):
    problem = random_window(seed, n_objects=4, n_frames=4, n_points=6, per_object=2)
    whole, split = QpL2(decompose=False).solve(problem), QpL2().solve(problem)
    assert split.lower_bound == pytest.approx(whole.lower_bound, abs=1e-7)
    assert_feasible(problem, split.path)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_baseline_is_feasible_and_proves_nothing(seed, mu):
    problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2, mu=mu)
    solution = NnHungarian().solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.cost >= brute_force(problem)[0] - 1e-9
    assert solution.cost == pytest.approx(objective(problem, solution.path))
    assert solution.lower_bound == -np.inf and not solution.integral and solution.status == "baseline"


def test_look_ahead_matters():
    worse = 0
    for seed in range(10):
        problem = random_window(seed, n_objects=3, n_frames=3, n_points=3, per_object=2)
        worse += NnHungarian().solve(problem).cost > brute_force(problem)[0] + 1e-6
    assert worse >= 1


@pytest.mark.parametrize("seed", range(10))
def test_one_frame_assignment_is_exact(seed):
    """With one frame (and equal sink arcs) the joint assignment is the whole problem."""
    problem = random_window(seed, n_objects=3, n_frames=1, n_points=3, per_object=2)
    assert NnHungarian().solve(problem).cost == pytest.approx(brute_force(problem)[0], abs=1e-9)


def test_greedy_per_frame_on_a_hand_built_chain():
    """s -> {a1, a2, o1} -> {b1, o2} -> {c1, o3} -> t: cheapest step each frame is a1, o2, c1."""
    problem = _chain()
    solution = NnHungarian().solve(problem)
    assert solution.path.tolist() == [[1, 5, 6]]
    assert solution.cost == pytest.approx(1 + 8 + 3 + 0)
    assert brute_force(problem)[0] == pytest.approx(2 + 1 + 1 + 0)  # s -> a2 -> b1 -> c1 -> t


def test_candidates_with_several_resources_fall_back_to_greedy():
    base = random_window(3, n_objects=3, n_frames=3, n_points=3, per_object=2)
    # Object 0's observations also claim the point of object 1's first candidate in the frame.
    own = np.flatnonzero((base.node_object == 0) & (base.node_kind == OBSERVATION))
    first = base.frame_nodes()[1, base.node_frame[own] - 1]
    extra = sp.csr_matrix((np.ones(len(own)), (own, base.resources[first].indices)), shape=base.resources.shape)
    problem = dataclasses.replace(base, resources=((base.resources + extra) > 0).astype(float).tocsr())
    assert (np.diff(problem.conflict_groups.T.tocsr().indptr) > 1).any()
    solution = NnHungarian().solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.cost >= brute_force(problem)[0] - 1e-9


@pytest.mark.parametrize("parameters,named", [
    ({"integrality_tolerance": 0.0}, "integrality_tolerance"),
    ({"integrality_tolerance": 0.5}, "integrality_tolerance"),
    ({"integrality_tolerance": "1e-5"}, "integrality_tolerance"),
    ({"decompose": "yes"}, "decompose"),
    ({"bound": "qp"}, "bound"),
])
def test_bad_parameters_are_named(parameters, named):
    with pytest.raises(FormulationError, match=named):
        QpL2(**parameters)


def test_negative_layout_weight_is_refused():
    problem = random_window(0, n_objects=2, n_frames=2, mu=0.5)
    with pytest.raises(FormulationError, match="mu"):
        QpL2().solve(dataclasses.replace(problem, layout_weight=-problem.layout_weight))


def _chain() -> WindowProblem:
    """One object, three frames, arc costs chosen so that greedy and optimum differ."""
    layers = [[0], [1, 2, 3], [4, 5], [6, 7], [8]]
    costs = [[[1, 2, 5]], [[10, 8], [1, 8], [4, 6]], [[1, 5], [3, 7]], [[0], [0]]]
    arcs = [(t, h, c[i][j]) for tails, heads, c in zip(layers, layers[1:], costs)
            for i, t in enumerate(tails) for j, h in enumerate(heads)]
    tail, head, cost = (np.array(column) for column in zip(*arcs))
    observations = [1, 2, 4, 6]
    return WindowProblem(
        n_objects=1, n_frames=3,
        node_kind=np.array([SOURCE, OBSERVATION, OBSERVATION, OCCLUSION, OBSERVATION, OCCLUSION, OBSERVATION, OCCLUSION, SINK]),
        node_object=np.zeros(9, dtype=int), node_frame=np.array([0, 1, 1, 1, 2, 2, 3, 3, 4]),
        node_location=np.zeros((9, 2)),
        resources=sp.csr_matrix((np.ones(4), (observations, np.arange(4))), shape=(9, 4)),
        arc_tail=tail, arc_head=head, arc_cost=cost.astype(float),
        layout_pairs=np.zeros((0, 2), dtype=int), layout_weight=np.zeros(0),
    )
