"""The contract every registered formulation honours, checked against brute force.

Parametrised over ``registry.names()``, so a formulation is covered by adding its file
and its registry line, with no edit here. On each shared tiny window (conflicts and
occlusions; separately the layout term), with min E found by enumerating every feasible
joint assignment and E evaluated by ``windows.objective`` (both written apart from the
code under test):

    the paths are feasible,   cost = E(paths),   lower_bound <= min E <= cost,
    integral  =>  cost = min E and gap = 0.

A formulation that proves nothing reports lower_bound = -inf, which passes.
"""

import dataclasses
import functools

import pytest
import scipy.sparse as sp
from windows import SHARED_WINDOWS, assert_feasible, brute_force, layout_term, objective, shared_window

from formulations.methods.lp_l1 import LpL1
from formulations.methods.registry import get_formulation, names
from formulations.window.problem import OCCLUSION

TOLERANCE = 1e-6  # relative to max(1, |min E|)


@functools.cache
def solved(label: str):
    """The shared window, its brute-force optimum and optimal paths (enumerated once)."""
    problem = shared_window(label)
    return problem, *brute_force(problem)


@pytest.mark.parametrize("label", sorted(SHARED_WINDOWS))
@pytest.mark.parametrize("name", names())
def test_formulation_honours_the_contract_on_the_shared_windows(name, label):
    problem, optimum, _ = solved(label)
    tolerance = TOLERANCE * max(1.0, abs(optimum))
    solution = get_formulation(name).solve(problem)
    assert_feasible(problem, solution.path)
    assert solution.cost == pytest.approx(objective(problem, solution.path), abs=tolerance)
    assert solution.lower_bound <= optimum + tolerance
    assert optimum <= solution.cost + tolerance
    if solution.integral:
        assert solution.cost == pytest.approx(optimum, abs=tolerance)
        assert solution.gap == pytest.approx(0.0, abs=TOLERANCE)


def test_the_shared_windows_exercise_conflicts_occlusions_layout_and_rounding():
    """Without these the contract could pass on windows where nothing can go wrong."""
    binding = occluded = fractional = 0
    for label in SHARED_WINDOWS:
        problem, optimum, best = solved(label)
        assert objective(problem, best) == pytest.approx(optimum), label  # the loop agrees with the enumeration
        free = dataclasses.replace(problem, resources=sp.csr_matrix(problem.resources.shape))
        binding += brute_force(free)[0] < optimum - 1e-6
        occluded += bool((problem.node_kind[best] == OCCLUSION).any())
        fractional += LpL1(decompose=False).solve(problem).n_fractional > 0
        if label.startswith("layout"):
            assert layout_term(problem, best) > 0, label
    assert binding >= 5 and occluded >= 5 and fractional >= 5
