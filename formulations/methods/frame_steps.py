"""The frame-by-frame view of a window that ``nn-hungarian`` and ``mht`` share.

From one node per object at frame m (the sources at m = 0), the next step's options are
the arcs out of those nodes, minus heads that hold a conflict group already taken: a
resource used earlier stays used (groups may span frames).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from formulations.window.problem import WindowProblem


class FrameSteps:
    """Out-arcs of chosen nodes, indexed once per window."""

    def __init__(self, problem: WindowProblem) -> None:
        self.by_tail = np.argsort(problem.arc_tail, kind="stable")
        self.out_start = np.searchsorted(problem.arc_tail[self.by_tail], np.arange(problem.n_nodes + 1))
        self.node_groups: sp.csr_matrix = problem.conflict_groups.T.tocsr()  # (V, G)
        self.arc_head, self.arc_cost = problem.arc_head, problem.arc_cost

    def successors(
        self, previous: NDArray[np.intp], taken: NDArray[np.float64],
    ) -> tuple[NDArray[np.intp], NDArray[np.float64], sp.csr_matrix]:
        """Heads of the arcs out of ``previous`` holding no ``taken`` group (0/1 per group),
        their arc costs, and the ``(heads, G)`` groups each head holds."""
        arcs = self.by_tail[_ranges(self.out_start[previous], self.out_start[previous + 1])]
        node, cost = self.arc_head[arcs], self.arc_cost[arcs]
        free = self.node_groups[node] @ taken == 0
        node, cost = node[free], cost[free]
        return node, cost, self.node_groups[node]


def _ranges(first: NDArray[np.intp], stop: NDArray[np.intp]) -> NDArray[np.intp]:
    """Concatenation of arange(first[i], stop[i]) without a Python loop."""
    counts = stop - first
    ranges: NDArray[np.intp] = np.repeat(first - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
    return ranges
