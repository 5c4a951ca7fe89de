"""Murty's k-best assignments, with the Miller–Stone–Cox optimisations and miss costs.

Rows i = 1..R are assigned to distinct columns j = 1..C at cost c_ij (inf: forbidden); a
row may instead stay unassigned at its miss cost u_i (inf: it must be assigned). As in
Ringer & Lasenby's F matrix (eq. 10) the misses are R extra columns, the diagonal block
diag(u) with inf off the diagonal, so every assignment is one of the extended R x (C+R)
problem, of cost

    E(sigma) = sum_{i assigned} c_{i sigma(i)} + sum_{i unassigned} u_i.

Murty (1968) ranks them by partitioning: once sigma* (the best of a subproblem P) is
reported, P minus sigma* is split over its free rows r_1..r_k (in an order of our choosing)
into the children

    P_t = P  with  r_1..r_{t-1} forced to sigma*(r_1..r_{t-1})  and  (r_t, sigma*(r_t)) excluded,

which are disjoint and cover P \\ {sigma*}; the next best assignment is the best among the
children of everything reported so far. A child is solved with its forced rows and columns
removed (the inherited partial solution: a smaller problem). Miller, Stone & Cox (1997) add

1. lazy evaluation: a child enters the queue with a lower bound, and is only solved when
   it reaches the front (then re-queued at its exact cost); a solved subproblem at the
   front is the next best, since its cost is at most every bound behind it. The front's
   key is so a lower bound on the next assignment, before any LAP is solved
   (``MurtyRanking.lower_bound``, which ``blocks`` merges by);
2. an optimised partition order: rows whose exclusion raises the bound most go first, so
   the children that are cheap to reach (more rows forced, smaller problems) come last.

The bound of P_t is the row-minimum relaxation (drop column uniqueness among free rows):

    b_t = max( E(P), sum_{s<t} c_{r_s sigma*(r_s)} + min_{j != sigma*(r_t)} c_{r_t j} + sum_{s>t} min_j c_{r_s j} ),

over the columns P allows. Their third optimisation (inheriting the dual variables so a
child costs one shortest augmenting path) needs a solver exposing its duals, which
``linear_sum_assignment`` does not; each child is a fresh, smaller LAP.

``formulations.assignment.blocks`` splits a matrix into independent blocks first, so Murty
only runs where rows contend for columns. No maintained PyPI package does this (ranked
assignments with miss costs on a standard LAP solver; ``lapsolver``, last released 2020,
returns the best one only), hence this module.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

Costs = NDArray[np.float64]
Indices = NDArray[np.intp]


class RankedAssignment(NamedTuple):
    """One assignment: its cost and the column of each row (-1: unassigned, at its miss cost)."""

    cost: float
    columns: NDArray[np.intp]


@dataclass
class _Subproblem:
    """The extended problem with ``forced_rows`` taking ``forced_columns`` and ``excluded`` (row, column) entries."""

    forced_rows: Indices
    forced_columns: Indices
    excluded: tuple[tuple[int, int], ...]
    key: float  # the bound until solved, then the exact cost
    columns: Indices | None = field(default=None)

    def free(self, extended: Costs) -> tuple[Indices, Indices, Costs]:
        """The unforced rows and columns, and their costs with this subproblem's exclusions at inf."""
        free_rows = _unforced(extended.shape[0], self.forced_rows)
        free_columns = _unforced(extended.shape[1], self.forced_columns)
        costs = extended[np.ix_(free_rows, free_columns)]
        if self.excluded:
            excluded = np.array(self.excluded)
            r = _positions(extended.shape[0], free_rows)[excluded[:, 0]]
            c = _positions(extended.shape[1], free_columns)[excluded[:, 1]]
            live = (r >= 0) & (c >= 0)  # exclusions on forced rows or columns no longer matter
            costs[r[live], c[live]] = np.inf
        return free_rows, free_columns, costs


@dataclass
class _Child:
    """A child of a solved subproblem as queued: its parent, the rows it newly forces (to the
    parent's columns) and the row whose parent's column it excludes; built when it is solved,
    so the many children never solved cost a tuple each."""

    parent: _Subproblem
    newly_forced: Indices
    row: int
    key: float

    def subproblem(self) -> _Subproblem:
        parent = self.parent
        assert parent.columns is not None
        forced_rows = np.concatenate([parent.forced_rows, self.newly_forced])
        excluded = (*parent.excluded, (self.row, int(parent.columns[self.row])))
        return _Subproblem(forced_rows, parent.columns[forced_rows], excluded, self.key)


class MurtyRanking(Iterator[RankedAssignment]):
    """Every assignment of ``cost`` (R x C), cheapest first, lazily.

    Args:
        cost: ``(R, C)`` c_ij, inf where row i may not take column j.
        miss: ``(R,)`` u_i, the cost of leaving row i unassigned (None: every row must be
            assigned, which needs C >= R).
    """

    def __init__(self, cost: Costs, miss: Costs | None = None) -> None:
        cost = np.asarray(cost, dtype=float)
        self.width, self.extended = cost.shape[1], with_miss_columns(cost, miss)
        none = np.empty(0, dtype=np.intp)
        self.counter = itertools.count()
        root = _Subproblem(none, none, (), key=-np.inf)
        self.queue: list[tuple[float, int, _Subproblem | _Child]] = [(-np.inf, next(self.counter), root)]

    def __next__(self) -> RankedAssignment:
        while self.queue:
            _, _, queued = heapq.heappop(self.queue)
            problem = queued.subproblem() if isinstance(queued, _Child) else queued
            if problem.columns is None:
                solved = _solve(self.extended, problem)
                if solved is not None:
                    heapq.heappush(self.queue, (solved.key, next(self.counter), solved))
                continue
            for child in _partition(self.extended, problem):
                heapq.heappush(self.queue, (child.key, next(self.counter), child))
            columns = problem.columns.copy()
            columns[columns >= self.width] = -1
            return RankedAssignment(problem.key, columns)
        raise StopIteration

    def lower_bound(self) -> float:
        """A lower bound on the next assignment's cost (inf: there is none), no LAP solved."""
        return self.queue[0][0] if self.queue else np.inf


def ranked_assignments(cost: Costs, miss: Costs | None = None) -> MurtyRanking:
    """Every assignment of ``cost`` (R x C) with row misses ``miss``, cheapest first, lazily."""
    return MurtyRanking(cost, miss)


def with_miss_columns(cost: Costs, miss: Costs | None) -> Costs:
    """``[cost | diag(miss)]`` with inf off the diagonal (``cost`` itself without misses)."""
    if miss is None:
        return cost
    misses = np.full((len(cost), len(cost)), np.inf)
    np.fill_diagonal(misses, miss)
    return np.hstack([cost, misses])


def _solve(extended: Costs, problem: _Subproblem) -> _Subproblem | None:
    """The subproblem with its best assignment, or None when it has none."""
    rows = extended.shape[0]
    free_rows, free_columns, costs = problem.free(extended)
    columns = np.empty(rows, dtype=np.intp)
    columns[problem.forced_rows] = problem.forced_columns
    if len(free_rows):
        try:
            r, c = linear_sum_assignment(costs)
        except ValueError:  # no assignment avoids every inf
            return None
        if len(r) < len(free_rows) or not np.isfinite(costs[r, c]).all():
            return None
        columns[free_rows[r]] = free_columns[c]
    total = float(extended[np.arange(rows), columns].sum())
    if not np.isfinite(total):
        return None
    return _Subproblem(problem.forced_rows, problem.forced_columns, problem.excluded, key=total, columns=columns)


def _unforced(size: int, forced: Indices) -> Indices:
    """Indices in range(size) not in ``forced``."""
    keep = np.ones(size, dtype=bool)
    keep[forced] = False
    return np.flatnonzero(keep)


def _positions(size: int, kept: Indices) -> Indices:
    """Each index's position in ``kept`` (-1: not kept)."""
    at = np.full(size, -1, dtype=np.intp)
    at[kept] = np.arange(len(kept))
    return at


def _partition(extended: Costs, problem: _Subproblem) -> list[_Child]:
    """Murty's children of a solved subproblem, each queued at its row-minimum bound."""
    assert problem.columns is not None
    chosen = problem.columns
    free = _unforced(extended.shape[0], problem.forced_rows)
    if len(free) == 0:
        return []
    own_column = chosen[free]
    allowed = extended[free]  # a copy
    if problem.excluded:  # exclusions on forced rows no longer matter
        excluded = np.array(problem.excluded)
        r = _positions(extended.shape[0], free)[excluded[:, 0]]
        allowed[r[r >= 0], excluded[r >= 0, 1]] = np.inf
    allowed[:, problem.forced_columns] = np.inf
    at = np.arange(len(free))
    own = allowed[at, own_column]
    row_min = allowed.min(axis=1)
    allowed[at, own_column] = np.inf
    second = allowed.min(axis=1)
    order = np.argsort(own - second, kind="stable")  # largest exclusion penalty first
    free, own, row_min, second = free[order], own[order], row_min[order], second[order]
    forced_cost = float(extended[problem.forced_rows, problem.forced_columns].sum())
    before = forced_cost + np.concatenate([[0.0], np.cumsum(own)[:-1]])
    after = np.concatenate([np.cumsum(row_min[::-1])[::-1][1:], [0.0]])
    bounds = np.maximum(problem.key, before + second + after)
    rows = free.tolist()
    return [_Child(problem, free[:t], rows[t], bound) for t, bound in enumerate(bounds.tolist()) if bound < np.inf]
