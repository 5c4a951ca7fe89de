"""``dp-sequential``: best-track-first sequential DP, the greedy baseline of Jiang Sec. IV-A1.

Repeat until every object has a path:

    1. for every object still open, its shortest path alone (Viterbi) under costs c';
    2. fix the open object whose path is cheapest;
    3. c'(i, j) = inf for every arc into a node j sharing a conflict group with a node
       of the fixed path (those observations are taken).

Occlusion nodes conflict with nothing, so an all-occlusion path always survives and the
result is feasible. It is fast (N Viterbi passes) but proves nothing: an early cheap
track can take the observation a later object needed (Jiang Figs. 10-11). The layout
term cannot enter a per-object Viterbi, so it is ignored while choosing; the reported
cost still includes it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from formulations.methods.formulation import Formulation
from formulations.relaxation.viterbi import shortest_paths
from formulations.window.objective import path_cost
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution


@dataclass(frozen=True)
class DpSequential(Formulation):
    """Best-track-first sequential Viterbi (no optimality proof, layout term ignored).

    ``lower_bound`` is -inf and ``integral`` False: the paths are feasible, nothing more.
    It has no parameters.
    """

    name: ClassVar[str] = "dp-sequential"

    def solve(self, problem: WindowProblem) -> WindowSolution:
        start = time.perf_counter()
        groups = problem.conflict_groups
        cost = problem.arc_cost.copy()
        path = np.empty((problem.n_objects, problem.n_frames), dtype=int)
        open_ = np.ones(problem.n_objects, dtype=bool)
        for _ in range(problem.n_objects):
            # One batched Viterbi of every object; fixed objects are just not picked.
            paths, costs = shortest_paths(problem, cost)
            chosen = int(np.argmin(np.where(open_, costs, np.inf)))
            path[chosen], open_[chosen] = paths[chosen], False
            on_path = np.zeros(problem.n_nodes)
            on_path[paths[chosen]] = 1.0
            taken = groups.T @ (groups @ on_path) > 0  # nodes sharing a group with the path
            cost[taken[problem.arc_head]] = np.inf
        solve = time.perf_counter() - start
        ignored = problem.n_frames > 1 and bool(np.any(problem.layout_weight > 0))
        return WindowSolution(
            path=path, cost=path_cost(problem, path), lower_bound=-np.inf, integral=False,
            n_variables=problem.n_arcs,
            status="Heuristic; layout term ignored" if ignored else "Heuristic",
            solve_seconds=solve,
        )
