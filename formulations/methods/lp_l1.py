"""``lp-l1``: Jiang's LP relaxation with the L1 layout term, rounded and certified."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from formulations.methods.formulation import check_parameters
from formulations.relaxation.decomposition import ComponentwiseFormulation
from formulations.relaxation.lp_model import inflow_matrix, window_lp
from formulations.relaxation.pricing import solve_with_pricing
from formulations.relaxation.rounding import round_greedy
from formulations.relaxation.viterbi import shortest_paths
from formulations.solvers import create_backend
from formulations.window.objective import path_arcs, path_cost
from formulations.window.problem import OCCLUSION, SINK, WindowProblem
from formulations.window.solution import WindowSolution

PRIMAL_SIMPLEX = 4  # HiGHS simplex_strategy


@dataclass(frozen=True)
class LpL1(ComponentwiseFormulation):
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
    pricing_successors: int = 1
    time_limit: float | None = None

    def __post_init__(self) -> None:
        check_parameters(self, positive=("integrality_tolerance", "pricing_successors"),
                         non_negative=("pricing_min_arcs",), optional_positive=("time_limit",))

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Build, solve, round and certify one LP over the whole (sub-)window."""
        start = time.perf_counter()
        model = window_lp(problem)
        build = time.perf_counter() - start
        if problem.n_arcs > self.pricing_min_arcs:
            # Primal simplex: columns added by pricing keep the basis primal feasible.
            backend = create_backend("highs", simplex_strategy=PRIMAL_SIMPLEX)
            initial = self._initial_columns(problem, len(model.cost))
            result, _ = solve_with_pricing(model, backend, initial, time_limit=self.time_limit)
        else:
            backend = create_backend("highs")
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
        initial = np.ones(n_columns, dtype=bool)
        arcs = _cheapest_per_tail(problem, self.pricing_successors)
        head_kind = problem.node_kind[problem.arc_head]
        arcs |= (head_kind == OCCLUSION) | (head_kind == SINK)
        arcs[path_arcs(problem, shortest_paths(problem)[0]).ravel()] = True
        initial[: problem.n_arcs] = arcs
        return initial


def _cheapest_per_tail(problem: WindowProblem, k: int) -> np.ndarray:
    """Mask of the k cheapest out-arcs of every node.

    Arcs are built grouped by tail, so k passes of a segmented minimum do it without
    sorting all arcs.
    """
    order = np.arange(problem.n_arcs) if np.all(np.diff(problem.arc_tail) >= 0) else np.argsort(problem.arc_tail, kind="stable")
    tail, cost = problem.arc_tail[order], problem.arc_cost[order].copy()
    starts = np.flatnonzero(np.r_[True, tail[1:] != tail[:-1]])
    group = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(tail)]))
    chosen = np.zeros(problem.n_arcs, dtype=bool)
    for _ in range(k):
        best = np.minimum.reduceat(cost, starts)
        hits = np.flatnonzero((cost <= best[group]) & np.isfinite(cost))
        first = hits[np.r_[True, group[hits][1:] != group[hits][:-1]]]
        chosen[order[first]] = True
        cost[first] = np.inf
    return chosen
