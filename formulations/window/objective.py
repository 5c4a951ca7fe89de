"""The window objective evaluated on integral paths (Jiang Sec. II-C).

    E(paths) = sum over arcs on paths of c(i, j)
             + sum_{(a, b) in N} mu_ab sum_{m=1}^{M-1} || (p_a,m+1 - p_b,m+1) - (p_a,m - p_b,m) ||_1

Every formulation reports this same number for the paths it returns, so costs are
comparable across formulations.
"""

from __future__ import annotations

import numpy as np

from formulations.window.problem import WindowProblem


def arc_index(problem: WindowProblem, tail: np.ndarray, head: np.ndarray) -> np.ndarray:
    """Index of the arc (tail, head) for each pair; raises if one is not an arc."""
    keys = problem.arc_tail.astype(np.int64) * problem.n_nodes + problem.arc_head
    order = np.argsort(keys, kind="stable")
    wanted = np.asarray(tail, np.int64) * problem.n_nodes + np.asarray(head)
    pos = np.searchsorted(keys, wanted, sorter=order)
    pos = np.minimum(pos, len(keys) - 1)
    found: np.ndarray = order[pos]
    if not np.array_equal(keys[found], wanted):
        raise ValueError("path uses a node pair that is not an arc of the window")
    return found


def path_arcs(problem: WindowProblem, path: np.ndarray) -> np.ndarray:
    """Arc indices along each object's path: source -> path[n, 0] -> ... -> sink."""
    full = np.column_stack([problem.source_nodes(), path, problem.sink_nodes()])
    return arc_index(problem, full[:, :-1].ravel(), full[:, 1:].ravel()).reshape(len(path), -1)


def layout_cost(problem: WindowProblem, path: np.ndarray) -> float:
    """The L1 layout term of integral paths ``(N, M)``."""
    if len(problem.layout_pairs) == 0 or problem.n_frames < 2:
        return 0.0
    p = problem.node_location[path]  # (N, M, D)
    a, b = problem.layout_pairs[:, 0], problem.layout_pairs[:, 1]
    relative = p[a] - p[b]  # (P, M, D)
    change = np.abs(np.diff(relative, axis=1)).sum(axis=(1, 2))
    return float(problem.layout_weight @ change)


def path_cost(problem: WindowProblem, path: np.ndarray) -> float:
    """Objective E of integral paths ``(N, M)`` of node indices."""
    arcs = path_arcs(problem, path)
    return float(problem.arc_cost[arcs].sum()) + layout_cost(problem, path)


def conflicts(problem: WindowProblem, path: np.ndarray) -> np.ndarray:
    """Indices of conflict groups used more than once by the paths."""
    groups = problem.conflict_groups
    used = np.zeros(problem.n_nodes)
    used[path.ravel()] = 1.0
    return np.flatnonzero(groups @ used > 1.0 + 1e-9)
