"""Shortest source-to-sink path of every object, each on its own (Viterbi).

Each object's network is a layered DAG, so its best path obeys

    D(j) = min_{i -> j} D(i) + c(i, j),   D(s_n) = 0,

evaluated one layer (frame) at a time. All objects advance together: one vectorised
step per frame, never a loop over objects or arcs. Conflicts and the layout term are
ignored: this is exact for an object coupled to nobody, and a lower bound otherwise.

The arcs' order (by layer, then head) depends on the window only, not on the costs, so a
caller that prices the same window many times (``path_lp``) sorts it once (``ArcLayers``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.window.problem import WindowProblem


@dataclass(frozen=True)
class ArcLayers:
    """The window's arcs sorted by (frame of the tail, head), with the head groups of each layer.

    Attributes:
        order: ``(A,)`` arc indices in that order.
        tail: ``(A,)`` tails in that order.
        group_start: Position in ``order`` of the first arc into each head.
        group_of: ``(A,)`` head group of each sorted arc.
        head: Head node of each group.
        layer_groups: ``(M+2,)`` first group of each layer (frames 0..M), then the group count.
    """

    order: np.ndarray
    tail: np.ndarray
    group_start: np.ndarray
    group_of: np.ndarray
    head: np.ndarray
    layer_groups: np.ndarray

    @classmethod
    def of(cls, problem: WindowProblem) -> ArcLayers:
        layer = problem.node_frame[problem.arc_tail]
        order = np.lexsort((problem.arc_head, layer))
        head, layer = problem.arc_head[order], layer[order]
        new_group = np.r_[True, (head[1:] != head[:-1]) | (layer[1:] != layer[:-1])] if len(order) else np.zeros(0, bool)
        group_start = np.flatnonzero(new_group)
        layer_groups = np.searchsorted(layer[group_start], np.arange(problem.n_frames + 2))
        return cls(order, problem.arc_tail[order], group_start, np.cumsum(new_group) - 1, head[group_start], layer_groups)


def shortest_paths(
    problem: WindowProblem, arc_cost: np.ndarray | None = None, layers: ArcLayers | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Independent shortest path of every object.

    Args:
        problem: The window.
        arc_cost: Costs to use instead of ``problem.arc_cost`` (e.g. with used arcs removed
            by setting them to inf).
        layers: ``ArcLayers.of(problem)``, when the caller keeps it.

    Returns:
        ``(N, M)`` node per object and frame (-1 where no path), and ``(N,)`` path costs
        (inf if no path).
    """
    arcs, cost = shortest_path_arcs(problem, arc_cost, layers)
    path = np.where(arcs[:, :-1] >= 0, problem.arc_head[arcs[:, :-1]], -1)
    return path, cost


def shortest_path_arcs(
    problem: WindowProblem, arc_cost: np.ndarray | None = None, layers: ArcLayers | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Like ``shortest_paths``, but each path as its ``(N, M+1)`` arcs, source arc first (-1: no path)."""
    layers = ArcLayers.of(problem) if layers is None else layers
    cost = (problem.arc_cost if arc_cost is None else arc_cost)[layers.order]
    distance = np.full(problem.n_nodes, np.inf)
    distance[problem.source_nodes()] = 0.0
    into = np.full(problem.n_nodes, -1)  # position in layers.order of the best arc into each node
    starts = np.r_[layers.group_start, len(layers.order)]
    for f in range(problem.n_frames + 1):
        g0, g1 = layers.layer_groups[f], layers.layer_groups[f + 1]
        if g0 == g1:
            continue
        lo, hi = starts[g0], starts[g1]
        candidate = distance[layers.tail[lo:hi]] + cost[lo:hi]
        best = np.minimum.reduceat(candidate, starts[g0:g1] - lo)
        group = layers.group_of[lo:hi] - g0
        hits = np.flatnonzero(candidate <= best[group])  # first arc attaining each group's minimum
        first = hits[np.r_[True, group[hits][1:] != group[hits][:-1]]]
        heads = layers.head[g0:g1]
        distance[heads] = best
        into[heads] = lo + first
    sinks = problem.sink_nodes()
    return _backtrack(problem, layers, into, sinks), distance[sinks]


def _backtrack(problem: WindowProblem, layers: ArcLayers, into: np.ndarray, sinks: np.ndarray) -> np.ndarray:
    arcs = np.full((problem.n_objects, problem.n_frames + 1), -1)
    node = sinks
    for m in range(problem.n_frames, -1, -1):
        reached = node >= 0
        position = np.where(reached, into[np.maximum(node, 0)], -1)
        found = position >= 0
        arcs[found, m] = layers.order[position[found]]
        node = np.where(found, layers.tail[np.maximum(position, 0)], -1)
    return arcs
