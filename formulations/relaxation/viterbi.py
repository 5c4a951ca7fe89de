"""Shortest source-to-sink path of every object, each on its own (Viterbi).

Each object's network is a layered DAG, so its best path obeys

    D(j) = min_{i -> j} D(i) + c(i, j),   D(s_n) = 0,

evaluated one layer (frame) at a time. All objects advance together: one vectorised
step per frame, never a loop over objects or arcs. Conflicts and the layout term are
ignored: this is exact for an object coupled to nobody, and a lower bound otherwise.

The arcs' order (by layer, then head) depends on the window only, not on the costs, so a
caller that prices the same window many times (``path_lp``) sorts it once (``ArcLayers``),
and with it each layer's slice, head groups and heads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.window.problem import WindowProblem


@dataclass(frozen=True)
class Layer:
    """The arcs out of one frame, a slice of the sorted order.

    Attributes:
        arcs: Their slice of ``ArcLayers.order``.
        group_start: Position within the slice of the first arc into each head.
        group_size: Arcs into each head.
        head: Head node of each group.
    """

    arcs: slice
    group_start: np.ndarray
    group_size: np.ndarray
    head: np.ndarray


@dataclass(frozen=True)
class ArcLayers:
    """The window's arcs sorted by (frame of the tail, head), cut into layers.

    Attributes:
        order: ``(A,)`` arc indices in that order.
        tail, head: ``(A,)`` tails and heads in that order.
        layers: The non-empty layers, frame 0 first.
        sources, sinks: ``(N,)`` source and sink node of each object.
    """

    order: np.ndarray
    tail: np.ndarray
    head: np.ndarray
    layers: list[Layer]
    sources: np.ndarray
    sinks: np.ndarray

    @classmethod
    def of(cls, problem: WindowProblem) -> ArcLayers:
        order = problem.arc_order  # sorted once per window, a sub-window's taken from it
        head = problem.arc_head[order]
        group_start = np.flatnonzero(np.r_[True, head[1:] != head[:-1]]) if len(order) else np.zeros(0, np.intp)
        # a group's layer is the frame of its tails, one before its head's
        layer_groups = np.searchsorted(problem.node_frame[head[group_start]], np.arange(1, problem.n_frames + 3))
        starts = np.r_[group_start, len(order)]
        size = np.diff(starts)
        layers = []
        for g0, g1 in zip(layer_groups[:-1], layer_groups[1:]):
            if g0 < g1:
                lo, hi = starts[g0], starts[g1]
                layers.append(Layer(slice(lo, hi), group_start[g0:g1] - lo, size[g0:g1], head[group_start[g0:g1]]))
        return cls(order, problem.arc_tail[order], head, layers, problem.source_nodes(), problem.sink_nodes())

    def shortest_path_arcs(self, problem: WindowProblem, cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``shortest_path_arcs`` with the arc costs given in this order (``cost[i]`` of arc ``order[i]``)."""
        distance = np.full(problem.n_nodes, np.inf)
        distance[self.sources] = 0.0
        into = np.full(problem.n_nodes, -1)  # position in self.order of the best arc into each node
        for layer in self.layers:
            candidate = distance[self.tail[layer.arcs]] + cost[layer.arcs]
            best = np.minimum.reduceat(candidate, layer.group_start)
            # The first arc attaining each group's minimum: the first hit at or after its start
            # (every group has one, its minimum).
            hits = np.flatnonzero(candidate <= np.repeat(best, layer.group_size))
            distance[layer.head] = best
            into[layer.head] = layer.arcs.start + hits[np.searchsorted(hits, layer.group_start)]
        return self._backtrack(problem, into), distance[self.sinks]

    def _backtrack(self, problem: WindowProblem, into: np.ndarray) -> np.ndarray:
        # Per node its best arc in and the tail of that arc, -1 where none; index -1 (no arc, or
        # the node before a missing one) reads the -1 after the last node.
        arc_into, previous = np.full(problem.n_nodes + 1, -1), np.full(problem.n_nodes + 1, -1)
        reached = np.flatnonzero(into >= 0)
        arc_into[reached], previous[reached] = self.order[into[reached]], self.tail[into[reached]]
        arcs = np.empty((problem.n_objects, problem.n_frames + 1), dtype=int)
        node = self.sinks
        for m in range(problem.n_frames, -1, -1):
            arcs[:, m] = arc_into[node]
            node = previous[node]
        return arcs


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
    return layers.shortest_path_arcs(problem, (problem.arc_cost if arc_cost is None else arc_cost)[layers.order])
