"""Exact formulations (ilp, dp-extended) against brute force; the greedy baseline against both."""

import numpy as np
import pytest
from windows import assert_feasible, brute_force, objective, random_window

from formulations.errors import FormulationError
from formulations.methods.dp_extended import DpExtended
from formulations.methods.dp_sequential import DpSequential
from formulations.methods.ilp import Ilp
from formulations.methods.lp_l1 import LpL1
from formulations.window.build import build_window
from service.evaluation.jiang_instance import jiang_instance

# (seed, objects, frames): 2-3 objects drawing 2 of 3 shared points per frame, so most
# windows are coupled by conflicts (and by the layout term when mu > 0).
SMALL = [(seed, n, m) for seed in range(8) for n, m in ((2, 4), (3, 3))]
MU = [0.0, 0.4]


def window(seed, n_objects, n_frames, mu, likelihood=False):
    return random_window(seed, n_objects=n_objects, n_frames=n_frames, n_points=3, per_object=2, mu=mu, likelihood=likelihood)


@pytest.mark.parametrize("seed,n_objects,n_frames", SMALL)
@pytest.mark.parametrize("mu", MU)
@pytest.mark.parametrize("likelihood", [False, True], ids=["weights", "likelihood"])
def test_exact_formulations_reach_the_brute_force_optimum(seed, n_objects, n_frames, mu, likelihood):
    problem = window(seed, n_objects, n_frames, mu, likelihood)
    optimum, _ = brute_force(problem)
    exact = (Ilp(), Ilp(decompose=False), Ilp(decompose=False, lp_first=False), DpExtended(), DpExtended(decompose=False))
    for formulation in exact:
        solution = formulation.solve(problem)
        assert_feasible(problem, solution.path)
        assert solution.cost == pytest.approx(optimum, abs=1e-6), formulation
        assert solution.cost == pytest.approx(objective(problem, solution.path))
        assert solution.integral and solution.status.startswith("Optimal")
        assert solution.lower_bound <= optimum + 1e-6
        assert solution.gap == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("seed,n_objects,n_frames", SMALL)
@pytest.mark.parametrize("mu", MU)
def test_lp_bound_below_ilp_optimum_below_lp_rounding(seed, n_objects, n_frames, mu):
    problem = window(seed, n_objects, n_frames, mu)
    lp = LpL1(decompose=False).solve(problem)
    ilp = Ilp(decompose=False).solve(problem)
    dp = DpExtended(decompose=False).solve(problem)
    assert ilp.cost == pytest.approx(dp.cost, abs=1e-6)
    assert lp.lower_bound <= ilp.cost + 1e-6
    assert ilp.cost <= lp.cost + 1e-6


@pytest.mark.parametrize("seed,n_objects,n_frames", SMALL)
@pytest.mark.parametrize("mu", MU)
def test_sequential_dp_is_feasible_and_never_below_the_optimum(seed, n_objects, n_frames, mu):
    problem = window(seed, n_objects, n_frames, mu)
    optimum, _ = brute_force(problem)
    solution = DpSequential().solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.cost >= optimum - 1e-9
    assert solution.cost == pytest.approx(objective(problem, solution.path))
    assert solution.lower_bound == -np.inf and not solution.integral
    assert ("layout term ignored" in solution.status) == (mu > 0)


def test_best_track_first_loses_where_the_joint_optimum_does_not():
    """The setup separates the methods: some windows' greedy tracks are strictly worse."""
    worse = []
    for seed in range(20):
        problem = window(seed, 3, 3, 0.0)
        optimum, _ = brute_force(problem)
        if DpSequential().solve(problem).cost > optimum + 1e-6:
            worse.append(seed)
            assert DpExtended().solve(problem).cost == pytest.approx(optimum, abs=1e-6)
            assert Ilp().solve(problem).cost == pytest.approx(optimum, abs=1e-6)
    assert len(worse) >= 3


def test_extended_dp_refuses_a_joint_state_space_over_max_states():
    problem = window(0, 3, 3, 0.0)  # 3 nodes per object and frame: 27 joint states
    with pytest.raises(FormulationError, match=r"27 states.*max_states = 26"):
        DpExtended(max_states=26, decompose=False).solve(problem)
    assert DpExtended(max_states=27, decompose=False).solve(problem).integral


@pytest.mark.parametrize("formulation,parameter,value", [
    (Ilp, "time_limit", -1.0), (Ilp, "time_limit", 0.0), (Ilp, "mip_gap", -1e-3),
    (DpExtended, "max_states", 0), (DpExtended, "max_states", 2.5),
])
def test_bad_parameter_values_are_named(formulation, parameter, value):
    with pytest.raises(FormulationError, match=parameter):
        formulation(**{parameter: value})


def test_ilp_time_limit_returns_feasible_paths_with_an_honest_certificate():
    """Stopped long before branch and bound can finish: feasible paths, not claimed optimal."""
    instance = jiang_instance(3, 20, n_observations=30, seed=0)
    problem = build_window(instance.candidates, instance.weights)[0]
    solution = Ilp(time_limit=0.01, decompose=False, lp_first=False).solve(problem)
    assert_feasible(problem, solution.path)
    assert not solution.integral and solution.status.startswith("Time limit reached")
    assert solution.cost == pytest.approx(objective(problem, solution.path))
    assert solution.lower_bound <= solution.cost and solution.gap > 0
