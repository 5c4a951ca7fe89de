"""``nn-hungarian``: the frame-by-frame baseline, no look-ahead (Ringer & Lasenby's
"standard tracking technique").

For m = 1..M, every object picks one of its frame-m nodes, minimising the total arc cost
from the nodes picked at m-1 (the sources at m = 1):

    min sum_n c(prev_n, v_n)   s.t. v_n in block (n, m), no conflict group used twice,

and a resource taken in an earlier frame stays taken (groups span the whole window).
When every candidate holds at most one contested resource this is a one-to-one
assignment, objects x (contested resources + one private column per object), solved by
``linear_sum_assignment``; an object's private column holds its cheapest node that
contests nothing (its occlusion node or a point no other object can take). A frame where
some candidate holds several contested resources is not a bipartite matching: it falls
back to greedy, cheapest (object, node) first among the nodes still free.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment

from formulations.methods.formulation import Formulation
from formulations.methods.frame_steps import FrameSteps
from formulations.window.objective import path_cost
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution


@dataclass(frozen=True)
class NnHungarian(Formulation):
    """Frame-by-frame optimal assignment from the previous frame's choice; proves nothing.

    No parameters: the arc costs and conflict groups of the window define it fully.
    """

    name: ClassVar[str] = "nn-hungarian"
    look_ahead: ClassVar[bool] = False

    def solve(self, problem: WindowProblem) -> WindowSolution:
        start = time.perf_counter()
        steps = FrameSteps(problem)
        taken = np.zeros(steps.node_groups.shape[1])
        previous = problem.source_nodes()
        path = np.empty((problem.n_objects, problem.n_frames), dtype=int)
        for m in range(problem.n_frames):
            node, cost, held = steps.successors(previous, taken)
            if (np.diff(held.indptr) > 1).any():
                previous = _greedy(problem, node, cost, held)
            else:
                previous = _assign(problem, node, cost, held)
            taken[steps.node_groups[previous].indices] = 1.0
            path[:, m] = previous
        solve = time.perf_counter() - start
        return WindowSolution(
            path=path, cost=path_cost(problem, path), lower_bound=-np.inf, integral=False,
            status="baseline", solve_seconds=solve, round_seconds=time.perf_counter() - start - solve,
        )


def _assign(problem: WindowProblem, node: np.ndarray, cost: np.ndarray, held: sp.csr_matrix) -> np.ndarray:
    """Optimal one-to-one choice when every node holds at most one contested resource."""
    n = problem.n_objects
    obj = problem.node_object[node]
    contests = np.diff(held.indptr) == 1
    groups, column = np.unique(held.indices, return_inverse=True)
    col = obj + len(groups)  # private column of the node's object
    col[contests] = column
    width = len(groups) + n
    cell = obj * width + col
    # Cheapest node per (object, column): first of each cell after sorting by (cell, cost).
    order = np.lexsort((cost, cell))
    first = order[np.unique(cell[order], return_index=True)[1]]
    matrix = np.full(n * width, np.inf)
    matrix[cell[first]] = cost[first]
    best = np.full(n * width, -1)
    best[cell[first]] = node[first]
    rows, cols = linear_sum_assignment(matrix.reshape(n, width))
    chosen = np.empty(n, dtype=int)
    chosen[rows] = best[rows * width + cols]
    return chosen


def _greedy(problem: WindowProblem, node: np.ndarray, cost: np.ndarray, held: sp.csr_matrix) -> np.ndarray:
    """Cheapest (object, node) first, skipping nodes whose resources are already held."""
    chosen = np.full(problem.n_objects, -1)
    used = np.zeros(held.shape[1], dtype=bool)
    for i in np.argsort(cost, kind="stable"):
        n, groups = problem.node_object[node[i]], held.indices[held.indptr[i]:held.indptr[i + 1]]
        if chosen[n] < 0 and not used[groups].any():
            chosen[n] = node[i]
            used[groups] = True
    return chosen
