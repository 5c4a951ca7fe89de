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
   front is the next best, since its cost is at most every bound behind it;
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


class RankedAssignment(NamedTuple):
    """One assignment: its cost and the column of each row (-1: unassigned, at its miss cost)."""

    cost: float
    columns: NDArray[np.intp]


@dataclass
class _Subproblem:
    """The extended problem with rows ``forced`` to columns and ``excluded`` (row, column) entries."""

    forced: dict[int, int]
    excluded: list[tuple[int, int]]
    key: float  # the bound until solved, then the exact cost
    columns: NDArray[np.intp] | None = field(default=None)

    def costs(self, extended: Costs) -> Costs:
        """The extended matrix with this subproblem's exclusions set to inf (a copy)."""
        costs = extended.copy()
        if self.excluded:
            costs[tuple(np.array(self.excluded).T)] = np.inf
        return costs


def ranked_assignments(cost: Costs, miss: Costs | None = None) -> Iterator[RankedAssignment]:
    """Every assignment of ``cost`` (R x C), cheapest first, lazily.

    Args:
        cost: ``(R, C)`` c_ij, inf where row i may not take column j.
        miss: ``(R,)`` u_i, the cost of leaving row i unassigned (None: every row must be
            assigned, which needs C >= R).
    """
    cost = np.asarray(cost, dtype=float)
    width, extended = cost.shape[1], _extended(cost, miss)
    queue: list[tuple[float, int, _Subproblem]] = []
    counter = itertools.count()
    heapq.heappush(queue, (-np.inf, next(counter), _Subproblem(forced={}, excluded=[], key=-np.inf)))
    while queue:
        _, _, problem = heapq.heappop(queue)
        if problem.columns is None:
            solved = _solve(extended, problem)
            if solved is not None:
                heapq.heappush(queue, (solved.key, next(counter), solved))
            continue
        columns = problem.columns.copy()
        columns[columns >= width] = -1
        yield RankedAssignment(problem.key, columns)
        for child in _partition(extended, problem):
            heapq.heappush(queue, (child.key, next(counter), child))


def next_bound(cost: Costs, miss: Costs | None, best: RankedAssignment) -> float:
    """A lower bound on the second-best assignment's cost (inf: there is none), from the
    bounds of the best one's children: no LAP solved."""
    cost = np.asarray(cost, dtype=float)
    rows, width = cost.shape
    columns = np.where(best.columns >= 0, best.columns, width + np.arange(rows))
    root = _Subproblem(forced={}, excluded=[], key=best.cost, columns=columns)
    return min((child.key for child in _partition(_extended(cost, miss), root)), default=np.inf)


def _extended(cost: Costs, miss: Costs | None) -> Costs:
    """``[cost | diag(miss)]`` with inf off the diagonal (``cost`` itself without misses)."""
    if miss is None:
        return cost
    misses = np.full((len(cost), len(cost)), np.inf)
    np.fill_diagonal(misses, miss)
    return np.hstack([cost, misses])


def _solve(extended: Costs, problem: _Subproblem) -> _Subproblem | None:
    """The subproblem with its best assignment, or None when it has none."""
    rows, width = extended.shape
    forced_rows = np.fromiter(problem.forced, dtype=np.intp, count=len(problem.forced))
    forced_columns = np.fromiter(problem.forced.values(), dtype=np.intp, count=len(problem.forced))
    free_rows, free_columns = _unforced(rows, forced_rows), _unforced(width, forced_columns)
    costs = problem.costs(extended)
    columns = np.empty(rows, dtype=np.intp)
    columns[forced_rows] = forced_columns
    if len(free_rows):
        try:
            r, c = linear_sum_assignment(costs[np.ix_(free_rows, free_columns)])
        except ValueError:  # no assignment avoids every inf
            return None
        if len(r) < len(free_rows):
            return None
        columns[free_rows[r]] = free_columns[c]
    total = float(costs[np.arange(rows), columns].sum())
    if not np.isfinite(total):
        return None
    return _Subproblem(forced=problem.forced, excluded=problem.excluded, key=total, columns=columns)


def _unforced(size: int, forced: NDArray[np.intp]) -> NDArray[np.intp]:
    """Indices in range(size) not in ``forced``."""
    keep = np.ones(size, dtype=bool)
    keep[forced] = False
    return np.flatnonzero(keep)


def _partition(extended: Costs, problem: _Subproblem) -> list[_Subproblem]:
    """Murty's children of a solved subproblem, each queued at its row-minimum bound."""
    assert problem.columns is not None
    chosen = problem.columns
    free = _unforced(extended.shape[0], np.fromiter(problem.forced, dtype=np.intp, count=len(problem.forced)))
    if len(free) == 0:
        return []
    allowed = problem.costs(extended)[free]
    allowed[:, list(problem.forced.values())] = np.inf
    at = np.arange(len(free))
    own = allowed[at, chosen[free]]
    row_min = allowed.min(axis=1)
    allowed[at, chosen[free]] = np.inf
    second = allowed.min(axis=1)
    order = np.argsort(-(second - own), kind="stable")  # largest exclusion penalty first
    free, own, row_min, second = free[order], own[order], row_min[order], second[order]
    forced_cost = float(extended[list(problem.forced), list(problem.forced.values())].sum())
    before = forced_cost + np.r_[0.0, np.cumsum(own)[:-1]]
    after = np.r_[np.cumsum(row_min[::-1])[::-1][1:], 0.0]
    bounds = np.maximum(problem.key, before + second + after)
    children = []
    forced = dict(problem.forced)
    for t, row in enumerate(free.tolist()):
        if np.isfinite(bounds[t]):
            excluded = [*problem.excluded, (row, int(chosen[row]))]
            children.append(_Subproblem(forced=dict(forced), excluded=excluded, key=float(bounds[t])))
        forced[row] = int(chosen[row])
    return children
