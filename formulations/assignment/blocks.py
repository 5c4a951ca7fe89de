"""k-best assignments of a matrix that splits into independent blocks.

Rows that share no finite column never constrain each other: the rows and columns fall
into blocks B_1..B_b (connected components of the bipartite graph of finite entries),
every assignment is one assignment per block, and its cost is the sum,

    E(sigma) = sum_b E_b(sigma_b).

So the k best overall are the k smallest sums over the blocks' ranked lists: a heap over
index vectors (i_1..i_b), starting at (0..0); a popped vector pushes its successors that
advance one coordinate b' >= the last one advanced, which reaches every vector exactly
once and in order (each list is sorted). Only blocks whose second-best costs at most
delta_(k-1) more than their best (delta_(k-1): the (k-1)-th smallest such step over all
blocks) can leave their best among the k: the k-1 single steps below it already beat any
vector that moves another block. Any upper bound on delta_(k-1) (here: the one over
one-row blocks) and lower bounds on the steps (Murty's child bounds) keep that exact. A block's list is Murty's ranking
(``murty.ranked_assignments``), pulled lazily; a one-row block is its row sorted. In a
window of markers most rows are one-row blocks (a marker no other marker contests), so
Murty only runs on the few contended blocks.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

from formulations.assignment.murty import Costs, RankedAssignment, next_bound, ranked_assignments

Indices = NDArray[np.intp]


class _Ranking:
    """One block's assignments in order (columns of the whole matrix), pulled on demand and kept."""

    def __init__(self, rows: Indices, more: Iterator[RankedAssignment], columns: Indices | None = None) -> None:
        """``columns``: the block's columns in the whole matrix (None: ``more`` already uses those)."""
        self.rows, self.more = rows, more
        self.columns = None if columns is None else np.append(columns, -1)  # unassigned (-1) stays -1
        self.found: list[RankedAssignment] = []

    def get(self, index: int) -> RankedAssignment | None:
        """The block's ``index``-th best assignment, or None when it has fewer."""
        while len(self.found) <= index:
            found = next(self.more, None)
            if found is None:
                return None
            columns = found.columns if self.columns is None else self.columns[found.columns]
            self.found.append(RankedAssignment(found.cost, columns))
        return self.found[index]


def k_best_assignments(cost: Costs, miss: Costs | None = None, k: int = 1) -> list[RankedAssignment]:
    """The ``k`` cheapest assignments of ``cost`` (R x C) in order, fewer if fewer exist.

    Same problem as ``murty.ranked_assignments``: ``miss[i]`` is row i's cost of staying
    unassigned (column -1), None when every row must be assigned. Ties come in any order.
    """
    cost = np.asarray(cost, dtype=float)
    rows, width = cost.shape
    extended = np.column_stack([cost, np.full(rows, np.inf) if miss is None else miss])
    lone, shared = _blocks(cost)
    # One-row blocks, all at once: each row's options sorted (the last column is the miss).
    order = np.argsort(extended[lone], axis=1, kind="stable")
    ranked_cost = np.take_along_axis(extended[lone], order, axis=1)
    ranked_col = np.where(order == width, -1, order)
    rankings = [_Ranking(r, ranked_assignments(cost[np.ix_(r, c)], None if miss is None else miss[r]), c) for r, c in shared]
    best = [ranking.get(0) for ranking in rankings]
    if not np.isfinite(ranked_cost[:, 0]).all() or any(b is None for b in best):
        return []
    columns = np.empty(rows, dtype=np.intp)
    columns[lone] = ranked_col[:, 0]
    for ranking, b in zip(rankings, best):
        assert b is not None
        columns[ranking.rows] = b.columns
    total = float(ranked_cost[:, 0].sum() + sum(b.cost for b in best if b is not None))
    if k == 1:
        return [RankedAssignment(total, columns)]
    # Blocks that may move: a one-row block whose step to its second best is at most the
    # (k-1)-th smallest such step among one-row blocks (>= the limit over all blocks), and a
    # block of several rows whose step is not bounded above that (Murty's child bounds).
    lone_steps = ranked_cost[:, 1] - ranked_cost[:, 0] if extended.shape[1] > 1 else np.full(len(lone), np.inf)
    limit = np.sort(lone_steps)[k - 2] if len(lone) >= k - 1 else np.inf
    active = [_lone_ranking(lone[i], ranked_cost[i], ranked_col[i]) for i in np.flatnonzero(lone_steps <= limit)]
    for (r, c), ranking, b in zip(shared, rankings, best):
        assert b is not None
        local = RankedAssignment(b.cost, np.where(b.columns >= 0, np.searchsorted(c, b.columns), -1))
        if next_bound(cost[np.ix_(r, c)], None if miss is None else miss[r], local) - b.cost <= limit:
            active.append(ranking)
    return _merge(total, columns, active, k)


def _merge(total: float, columns: Indices, blocks: list[_Ranking], k: int) -> list[RankedAssignment]:
    """The k smallest sums over the blocks' lists, from the all-best assignment ``columns``."""
    counter = itertools.count()
    queue = [(total, next(counter), (0,) * len(blocks), 0)]
    ranked: list[RankedAssignment] = []
    while queue and len(ranked) < k:
        total, _, index, last = heapq.heappop(queue)
        chosen = columns.copy()
        for block, i in zip(blocks, index):
            if i:
                part = block.get(i)
                assert part is not None
                chosen[block.rows] = part.columns
        ranked.append(RankedAssignment(total, chosen))
        for b in range(last, len(blocks)):
            now, then = blocks[b].get(index[b]), blocks[b].get(index[b] + 1)
            if now is not None and then is not None:
                advanced = index[:b] + (index[b] + 1,) + index[b + 1:]
                heapq.heappush(queue, (total - now.cost + then.cost, next(counter), advanced, b))
    return ranked


def _lone_ranking(row: int, costs: Costs, columns: Indices) -> _Ranking:
    """A one-row block's ranking from its sorted options."""
    options = (RankedAssignment(float(c), np.array([j], dtype=np.intp)) for c, j in zip(costs, columns) if np.isfinite(c))
    return _Ranking(np.array([row], dtype=np.intp), options)


def _blocks(cost: Costs) -> tuple[Indices, list[tuple[Indices, Indices]]]:
    """Rows alone in their block, and the rows and columns of every block of several rows."""
    rows, width = cost.shape
    finite = np.isfinite(cost)
    linking = np.flatnonzero(finite.sum(axis=0) >= 2)  # columns two rows can take
    r, c = np.nonzero(finite[:, linking])
    graph = sp.coo_matrix((np.ones(len(r)), (r, rows + c)), shape=(rows + len(linking),) * 2)
    _, label = connected_components(graph, directed=False)
    size = np.bincount(label[:rows], minlength=label.max() + 1)
    lone = np.flatnonzero(size[label[:rows]] == 1)
    shared = []
    row_label = label[:rows]
    for group in np.flatnonzero(size >= 2):
        members = np.flatnonzero(row_label == group)
        shared.append((members, np.flatnonzero(finite[members].any(axis=0))))
    return lone, shared
