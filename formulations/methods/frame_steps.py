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
        # The heads' rows of node_groups gathered by index arithmetic: scipy's row indexing,
        # twice a step, cost more than the rest of a frame-by-frame step (CSR rows kept in order).
        indptr, indices, data = self.node_groups.indptr, self.node_groups.indices, self.node_groups.data
        first = indptr[node]
        size = indptr[node + 1] - first
        entries = _ranges(first, first + size)
        # A head is free where its groups' row . taken is 0: with 0/1 entries and taken, none is taken.
        blocked = np.zeros(len(node), bool)
        blocked[np.repeat(np.arange(len(node)), size)[data[entries] * taken[indices[entries]] != 0]] = True
        free = ~blocked
        entries = entries[np.repeat(free, size)]
        pointers = np.zeros(len(node) - np.count_nonzero(blocked) + 1, indptr.dtype)
        np.cumsum(size[free], out=pointers[1:])
        held = sp.csr_matrix((data[entries], indices[entries], pointers), shape=(len(pointers) - 1, self.node_groups.shape[1]))
        return node[free], cost[free], held


def _ranges(first: NDArray[np.intp], stop: NDArray[np.intp]) -> NDArray[np.intp]:
    """Concatenation of arange(first[i], stop[i]) without a Python loop."""
    counts = stop - first
    ranges: NDArray[np.intp] = np.repeat(first - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
    return ranges
