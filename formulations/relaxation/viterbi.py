"""Shortest source-to-sink path of every object, each on its own (Viterbi).

Each object's network is a layered DAG, so its best path obeys

    D(j) = min_{i -> j} D(i) + c(i, j),   D(s_n) = 0,

evaluated one layer (frame) at a time. All objects advance together: one vectorised
step per frame, never a loop over objects or arcs. Conflicts and the layout term are
ignored: this is exact for an object coupled to nobody, and a lower bound otherwise.
"""

from __future__ import annotations

import numpy as np

from formulations.window.problem import WindowProblem


def shortest_paths(problem: WindowProblem, arc_cost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Independent shortest path of every object.

    Args:
        problem: The window.
        arc_cost: Costs to use instead of ``problem.arc_cost`` (e.g. with used arcs removed
            by setting them to inf).

    Returns:
        ``(N, M)`` node per object and frame, and ``(N,)`` path costs (inf if no path).
    """
    cost = problem.arc_cost if arc_cost is None else arc_cost
    tail, head = problem.arc_tail, problem.arc_head
    layer = problem.node_frame[tail]
    order = np.lexsort((head, layer))
    distance = np.full(problem.n_nodes, np.inf)
    distance[problem.source_nodes()] = 0.0
    predecessor = np.full(problem.n_nodes, -1)
    bounds = np.searchsorted(layer[order], np.arange(problem.n_frames + 2))
    for f in range(problem.n_frames + 1):
        arcs = order[bounds[f]:bounds[f + 1]]
        _relax(distance, predecessor, tail[arcs], head[arcs], cost[arcs])
    sinks = problem.sink_nodes()
    return _backtrack(problem, predecessor, sinks), distance[sinks]


def _relax(distance: np.ndarray, predecessor: np.ndarray, tail: np.ndarray, head: np.ndarray, cost: np.ndarray) -> None:
    """One layer: arcs sorted by head; take the cheapest incoming arc of each head."""
    if len(head) == 0:
        return
    candidate = distance[tail] + cost
    starts = np.flatnonzero(np.r_[True, head[1:] != head[:-1]])
    best = np.minimum.reduceat(candidate, starts)
    group = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(head)]))
    # first arc attaining the minimum in each head group
    hits = np.flatnonzero(candidate <= best[group])
    first = hits[np.r_[True, group[hits][1:] != group[hits][:-1]]]
    heads = head[starts]
    distance[heads] = best
    predecessor[heads] = tail[first]


def _backtrack(problem: WindowProblem, predecessor: np.ndarray, sinks: np.ndarray) -> np.ndarray:
    path = np.empty((problem.n_objects, problem.n_frames), dtype=int)
    node = predecessor[sinks]
    for m in range(problem.n_frames - 1, -1, -1):
        path[:, m] = node
        node = predecessor[node]
    return path
