"""k-best assignments of a matrix that splits into independent blocks.

Rows that share no finite column never constrain each other: the rows and columns fall
into blocks B_1..B_b (connected components of the bipartite graph of finite entries),
every assignment is one assignment per block, and its cost is the sum,

    E(sigma) = sum_b E_b(sigma_b).

So the k best overall are the k smallest sums over the blocks' ranked lists: a heap over
index vectors (i_1..i_b), starting at (0..0); a popped vector pushes its successors that
advance one coordinate b' >= the last one advanced, which reaches every vector exactly
once and in order (each list is sorted). As in Miller–Stone–Cox, a successor enters the
heap at a lower bound (its block's ``bound``: Murty's queue front, no LAP solved) and is
only ranked exactly when it reaches the front, so a block whose next assignment cannot be
among the k is never solved past its best. Only blocks whose second best costs at most
delta_(k-1) more than their best can leave it (delta_(k-1): the (k-1)-th smallest such
step over all blocks, bounded above by the steps known exactly, of one-row and enumerated
blocks): the k-1 single steps below it already beat any vector that moves another. A
block's list is ``rankings.BlockRanking`` (enumerated when small, Murty's otherwise),
from a ``RankingCache`` the caller may share across matrices; a one-row block is its row
sorted. In a window of markers most rows are one-row blocks (a
marker no other marker contests), so ranking only runs on the few contended blocks.
"""

from __future__ import annotations

import heapq
import itertools

import numpy as np
from numpy.typing import NDArray

from formulations.assignment.dominated import without_dominated
from formulations.assignment.murty import Costs, Indices, RankedAssignment
from formulations.assignment.rankings import BlockRanking, RankingCache, is_enumerated


class _Placed:
    """A block's ranking placed in the whole matrix: its rows, its columns mapped to the matrix's."""

    def __init__(self, rows: Indices, columns: Indices, ranking: BlockRanking) -> None:
        self.rows, self.ranking = rows, ranking
        self.place = np.append(columns, -1)  # unassigned (-1) stays -1
        self.cost, self.bound = ranking.cost, ranking.bound

    def columns(self, index: int) -> Indices:
        found = self.ranking.get(index)
        assert found is not None
        placed: Indices = self.place[found.columns]
        return placed


class _Lone:
    """A one-row block: its finite options sorted (columns of the whole matrix)."""

    def __init__(self, row: int, costs: Costs, columns: Indices) -> None:
        finite = np.isfinite(costs)
        self.rows = np.array([row], dtype=np.intp)
        self.costs, self.options = costs[finite].tolist(), columns[finite]

    def cost(self, index: int) -> float | None:
        return self.costs[index] if index < len(self.costs) else None

    def bound(self, index: int) -> tuple[float, bool]:
        return (self.costs[index] if index < len(self.costs) else np.inf), True

    def columns(self, index: int) -> Indices:
        column: Indices = self.options[index : index + 1]
        return column


def k_best_assignments(
    cost: Costs, miss: Costs | None = None, k: int = 1, cache: RankingCache | None = None,
) -> list[RankedAssignment]:
    """The ``k`` cheapest assignments of ``cost`` (R x C) in order, fewer if fewer exist.

    Same problem as ``murty.MurtyRanking``: ``miss[i]`` is row i's cost of staying
    unassigned (column -1), None when every row must be assigned. Ties come in any order.
    ``cache`` shares block rankings with other calls (None: this call's own).
    """
    cost = np.asarray(cost, dtype=float)
    rows, width = cost.shape
    cache = RankingCache() if cache is None else cache
    extended = np.column_stack([cost, np.full(rows, np.inf) if miss is None else miss])
    finite = np.isfinite(extended)
    lone, shared = _blocks(finite[:, :width])
    if k > 1 and not all(is_enumerated(finite[r][:, np.append(c, width)]) for r, c in shared):
        # a block for Murty's ranking: drop the entries none of the k best takes, which
        # splits it (one LAP more, worth it only then), and find the blocks again
        cost = without_dominated(cost, miss, k)
        extended[:, :width] = cost
        finite = np.isfinite(extended)
        lone, shared = _blocks(finite[:, :width])
    # One-row blocks, all at once: each row's options sorted (the last column is the miss).
    order = np.argsort(extended[lone], axis=1, kind="stable")
    ranked_cost = np.take_along_axis(extended[lone], order, axis=1)
    ranked_col = np.where(order == width, -1, order)
    placed = [_Placed(r, c, cache.ranking(cost[np.ix_(r, c)], None if miss is None else miss[r])) for r, c in shared]
    best = [p.cost(0) for p in placed]
    if not np.isfinite(ranked_cost[:, 0]).all() or any(b is None for b in best):
        return []
    columns = np.empty(rows, dtype=np.intp)
    columns[lone] = ranked_col[:, 0]
    for p in placed:
        columns[p.rows] = p.columns(0)
    total = float(ranked_cost[:, 0].sum() + sum(b for b in best if b is not None))
    if k == 1:
        return [RankedAssignment(total, columns)]
    # Only blocks whose second best costs at most delta_(k-1) more than their best can move
    # (delta_(k-1): the (k-1)-th smallest step, bounded above by the steps known exactly:
    # each one-row block's, and each ranked block's once its second best is found).
    lone_steps = ranked_cost[:, 1] - ranked_cost[:, 0] if width else np.full(len(lone), np.inf)
    placed_steps = [(p.bound(1), b) for p, b in zip(placed, best)]
    exact_steps = np.concatenate([lone_steps, [then - b for (then, exact), b in placed_steps if exact and b is not None]])
    limit = np.partition(exact_steps, k - 2)[k - 2] if len(exact_steps) >= k - 1 else np.inf
    moving = np.flatnonzero((lone_steps <= limit) & (lone_steps < np.inf))
    parts: list[_Placed | _Lone] = [_Lone(int(lone[i]), ranked_cost[i], ranked_col[i]) for i in moving]
    parts += [p for p, ((then, _), b) in zip(placed, placed_steps) if b is not None and then - b <= limit and then < np.inf]
    return _merge(total, columns, parts, k)


def _merge(total: float, columns: Indices, blocks: list[_Placed | _Lone], k: int) -> list[RankedAssignment]:
    """The k smallest sums over the blocks' lists, from the all-best assignment ``columns``.

    A heap entry is (key, tie, base, index, last, exact): ``index`` advanced ``last`` from a
    vector of cost ``base`` + the block's previous cost; ``key`` is exact or a lower bound."""
    counter = itertools.count()
    queue: list[tuple[float, int, float, tuple[int, ...], int, bool]] = [
        (total, next(counter), total, (0,) * len(blocks), 0, True),
    ]
    ranked: list[RankedAssignment] = []
    while queue and len(ranked) < k:
        total, _, base, index, last, exact = heapq.heappop(queue)
        if not exact:  # rank the advanced block's next assignment, and queue it at its cost
            then = blocks[last].cost(index[last])
            if then is not None:
                heapq.heappush(queue, (base + then, next(counter), base, index, last, True))
            continue
        chosen = columns.copy()
        for block, i in zip(blocks, index):
            if i:
                chosen[block.rows] = block.columns(i)
        ranked.append(RankedAssignment(total, chosen))
        for b in range(last, len(blocks)):
            now = blocks[b].cost(index[b])
            assert now is not None
            then, exact = blocks[b].bound(index[b] + 1)
            if then < np.inf:
                advanced = index[:b] + (index[b] + 1,) + index[b + 1 :]
                base = total - now
                heapq.heappush(queue, (base + then, next(counter), base, advanced, b, exact))
    return ranked


def _blocks(finite: NDArray[np.bool_]) -> tuple[Indices, list[tuple[Indices, Indices]]]:
    """Rows alone in their block, and the rows and columns of every block of several rows.

    Among the rows that share a column with another, ``reach`` (which rows a row reaches
    through shared columns) is closed by squaring, a few rounds for the short chains of
    contention in a window of markers; a block's label is its first row."""
    linking = finite[:, finite.sum(axis=0) >= 2]
    is_contested = linking.any(axis=1)
    contested, lone = np.flatnonzero(is_contested), np.flatnonzero(~is_contested)
    if len(contested) == 0:
        return lone, []
    links = linking[contested].astype(np.float64)
    reach = links @ links.T > 0
    while True:
        grown = reach.astype(np.float64) @ reach > 0
        if np.count_nonzero(grown) == np.count_nonzero(reach):  # grown only adds
            break
        reach = grown
    label = reach.argmax(axis=1)  # the first row it reaches: the same for every row of a block
    block_finite = finite[contested]
    used = np.flatnonzero(block_finite.any(axis=0))
    column_label = label[block_finite[:, used].argmax(axis=0)]
    row_order, column_order = np.argsort(label, kind="stable"), np.argsort(column_label, kind="stable")
    groups = np.unique(label)
    row_splits = np.searchsorted(label[row_order], groups).tolist() + [len(label)]
    column_splits = np.searchsorted(column_label[column_order], groups).tolist() + [len(used)]
    rows, columns = contested[row_order], used[column_order]
    return lone, [(rows[a:b], columns[c:d]) for a, b, c, d in zip(row_splits, row_splits[1:], column_splits, column_splits[1:])]
