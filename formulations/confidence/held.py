"""Which nodes another object's chosen path makes unusable, and which nodes exclude each other.

With every object but one (or two) held on its chosen path, a node is usable only if no
held object's chosen node takes a resource it needs (Jiang's conflict groups). The
chosen paths are feasible, so each contested resource has at most one holder.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from formulations.window.problem import WindowProblem

FREE, HELD_BY_SEVERAL = -1, -2


def foreign_holder(problem: WindowProblem, path: NDArray[np.intp]) -> NDArray[np.intp]:
    """``(V,)`` per node: FREE, the one other object whose chosen path holds one of its
    resources, or HELD_BY_SEVERAL when two or more others do."""
    groups = problem.conflict_groups.tocsc()  # (G, V)
    holder = np.full(groups.shape[0], FREE, dtype=np.intp)
    chosen = path.ravel()
    taken = groups[:, chosen].tocoo()
    holder[taken.row] = problem.node_object[chosen[taken.col]]
    membership = groups.tocoo()  # (group, node) entries
    node, other = membership.col, holder[membership.row]
    foreign = (other >= 0) & (other != problem.node_object[node])
    node, other = node[foreign], other[foreign]
    result = np.full(problem.n_nodes, FREE, dtype=np.intp)
    low = np.full(problem.n_nodes, np.iinfo(np.intp).max)
    high = np.full(problem.n_nodes, -1)
    np.minimum.at(low, node, other)
    np.maximum.at(high, node, other)
    held = high >= 0
    result[held] = np.where(low[held] == high[held], high[held], HELD_BY_SEVERAL)
    return result


def exclusive_pairs(problem: WindowProblem) -> NDArray[np.intp]:
    """``(E, 2)`` node pairs of different objects and one frame that share a resource.

    Pairs of different frames (groups that span frames; none of markerflow's windows has
    them) are not listed: a pair's joint programme cannot see them, so a two-object
    alternative may then break such a group and its margin comes out too small.
    """
    groups = problem.conflict_groups
    if groups.shape[0] == 0:
        return np.zeros((0, 2), dtype=np.intp)
    share = sp.triu(groups.T @ groups, k=1).tocoo()  # (V, V)
    u, w = share.row.astype(np.intp), share.col.astype(np.intp)
    keep = (problem.node_object[u] != problem.node_object[w]) & (problem.node_frame[u] == problem.node_frame[w])
    return np.column_stack([u[keep], w[keep]])
