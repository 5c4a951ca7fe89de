"""One hypothesis's next frame as an assignment problem: Ringer & Lasenby's F (eq. 10).

Rows are the objects (markers). A candidate node that holds a contested resource (a point
or detection another object can take) sits in that resource's column, so two objects
cannot both take it; every other observation node is a private column of its own object;
the object's occlusion node is its miss (the row left unassigned: F's "not detected"
columns, priced by the occlusion arc, which is where the window carries -log(1 - P_D)):

    F[n, col(v)] = c(prev_n, v),    miss_n = c(prev_n, occlusion node of n).

Every choice of one node per object that holds no resource twice is exactly one
assignment of F, at the same cost, when each node holds at most one contested resource
and no two nodes of one object share it. Otherwise (joint-3d points holding several
detections) a node sits in its first resource's column or, if its object already has a
node there, in a private column: every feasible choice is still one assignment, but some
assignments are infeasible, so ``checked`` tells the caller to filter them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from formulations.assignment.murty import Costs
from formulations.window.problem import OCCLUSION


@dataclass(frozen=True)
class Association:
    """F of one hypothesis and frame.

    Attributes:
        cost: ``(N, K)`` F, inf where an object has no node in the column.
        miss: ``(N,)`` the cost of each object's occlusion node.
        cell_node: ``(N, K)`` the node behind each finite entry.
        occlusion: ``(N,)`` each object's occlusion node.
        checked: Whether an assignment may hold a resource twice (then filter).
    """

    cost: Costs
    miss: Costs
    cell_node: NDArray[np.intp]
    occlusion: NDArray[np.intp]
    checked: bool

    def nodes(self, columns: NDArray[np.intp]) -> NDArray[np.intp]:
        """The node each object takes under assignments ``(..., N)`` (-1 columns: occluded)."""
        chosen: NDArray[np.intp] = np.column_stack([self.cell_node, self.occlusion])[np.arange(len(self.occlusion)), columns]
        return chosen  # column -1 picks the last: the occlusion node


def association(
    n_objects: int, node_object: NDArray[np.intp], node_kind: NDArray[np.intp],
    node: NDArray[np.intp], cost: NDArray[np.float64], held: sp.csr_matrix,
) -> Association:
    """F from the next frame's options ``node`` (with their arc ``cost`` and ``held`` groups)."""
    obj, occluded = node_object[node], node_kind[node] == OCCLUSION
    occlusion, miss = np.empty(n_objects, dtype=np.intp), np.full(n_objects, np.inf)
    occlusion[obj[occluded]], miss[obj[occluded]] = node[occluded], cost[occluded]
    count = np.diff(held.indptr)
    group = np.where(count > 0, np.append(held.indices, -1)[held.indptr[:-1]], -1)  # first group held
    observed = np.flatnonzero(~occluded)
    obj, group, count, node, cost = obj[observed], group[observed], count[observed], node[observed], cost[observed]
    # A node keeps its group's column unless an earlier node of its object already has it.
    first_of_cell = np.zeros(len(node), dtype=bool)
    contested = np.flatnonzero(group >= 0)
    cells = obj[contested] * (group.max(initial=0) + 1) + group[contested]
    first_of_cell[contested[_first_of_each(cells)]] = True
    column, n_groups = _dense_rank(group[first_of_cell])
    col = np.empty(len(node), dtype=np.intp)
    col[first_of_cell] = column
    private = ~first_of_cell  # the other nodes: a column each, after the groups'
    col[private] = n_groups + np.arange(np.count_nonzero(private))
    matrix = np.full((n_objects, n_groups + np.count_nonzero(private)), np.inf)
    matrix[obj, col] = cost
    cell_node = np.full(matrix.shape, -1, dtype=np.intp)
    cell_node[obj, col] = node
    checked = bool((count > 1).any() or ((group >= 0) & ~first_of_cell).any())
    return Association(cost=matrix, miss=miss, cell_node=cell_node, occlusion=occlusion, checked=checked)


def _first_of_each(values: NDArray[np.intp]) -> NDArray[np.intp]:
    """Index of the first occurrence of each distinct value (``np.unique``'s ``return_index``, without its overhead)."""
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    first: NDArray[np.intp] = order[np.concatenate([[True], ordered[1:] != ordered[:-1]])] if len(values) else order
    return first


def _dense_rank(values: NDArray[np.intp]) -> tuple[NDArray[np.intp], int]:
    """Each value's rank among the distinct values (``np.unique``'s ``return_inverse``), and their number."""
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    rank = np.empty(len(values), dtype=np.intp)
    rank[order] = np.cumsum(np.concatenate([[False], ordered[1:] != ordered[:-1]]))
    return rank, int(rank.max(initial=-1)) + 1
