"""``lp-l1``: Jiang's LP relaxation with the L1 layout term, rounded and certified."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from formulations.decomposed import solve_decomposed
from formulations.formulation import Formulation
from formulations.lp_model import inflow_matrix, window_lp
from formulations.objective import path_arcs, path_cost
from formulations.pricing import solve_with_pricing
from formulations.rounding import round_greedy
from formulations.solution import WindowSolution
from formulations.solvers import create_backend
from formulations.viterbi import shortest_paths
from formulations.window import OCCLUSION, SINK, WindowProblem


@dataclass(frozen=True)
class LpL1(Formulation):
    """The LP relaxation of multi-path flow with conflict groups (Jiang et al. 2008, II-D).

    Solved with HiGHS dual simplex; a fractional optimum is rounded greedily (II-D) and
    every window carries its certificate: LP bound, cost of the rounded paths, gap.

    Attributes:
        decompose: Solve independent components apart (Viterbi where exact).
        integrality_tolerance: xi within this of 0 or 1 counts as integral.
        pricing_min_arcs: Use column generation when a component has more arcs.
        pricing_successors: Cheapest out-arcs per node in the first restricted LP.
        time_limit: Seconds per LP solve (None: no limit).
    """

    name: ClassVar[str] = "lp-l1"
    decompose: bool = True
    integrality_tolerance: float = 1e-6
    pricing_min_arcs: int = 4000
    pricing_successors: int = 3
    time_limit: float | None = None

    def solve(self, problem: WindowProblem) -> WindowSolution:
        if self.decompose:
            return solve_decomposed(problem, self.solve_coupled)
        return self.solve_coupled(problem)

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Build, solve, round and certify one LP over the whole (sub-)window."""
        start = time.perf_counter()
        model = window_lp(problem)
        build = time.perf_counter() - start
        backend = create_backend("highs")
        if problem.n_arcs > self.pricing_min_arcs:
            result, _ = solve_with_pricing(model, backend, self._initial_columns(problem, len(model.cost)))
        else:
            backend.set_model(model, self.time_limit)
            result = backend.solve()
        solve = time.perf_counter() - start - build
        xi = result.x[: problem.n_arcs] if len(result.x) else np.zeros(problem.n_arcs)
        fractional = int(np.sum(np.minimum(xi, 1.0 - xi) > self.integrality_tolerance))
        path = round_greedy(problem, inflow_matrix(problem) @ xi)
        cost = path_cost(problem, path)
        return WindowSolution(
            path=path, cost=cost, lower_bound=result.bound if result.optimal else -np.inf,
            integral=result.optimal and fractional == 0, n_fractional=fractional,
            n_variables=len(model.cost), status=result.status, build_seconds=build,
            solve_seconds=solve, round_seconds=time.perf_counter() - start - build - solve,
        )

    def _initial_columns(self, problem: WindowProblem, n_columns: int) -> np.ndarray:
        """Cheapest successors of each node, every arc into occlusion or sink, Viterbi arcs."""
        order = np.lexsort((problem.arc_cost, problem.arc_tail))
        tails = problem.arc_tail[order]
        group_start = np.flatnonzero(np.r_[True, tails[1:] != tails[:-1]])
        rank = np.arange(len(order)) - np.repeat(group_start, np.diff(np.r_[group_start, len(order)]))
        initial = np.ones(n_columns, dtype=bool)
        arcs = np.zeros(problem.n_arcs, dtype=bool)
        arcs[order[rank < self.pricing_successors]] = True
        head_kind = problem.node_kind[problem.arc_head]
        arcs |= (head_kind == OCCLUSION) | (head_kind == SINK)
        arcs[path_arcs(problem, shortest_paths(problem)[0]).ravel()] = True
        initial[: problem.n_arcs] = arcs
        return initial
