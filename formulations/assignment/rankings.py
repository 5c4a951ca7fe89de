"""One block's assignments in order, and a cache of them for matrices that share blocks.

A block of R rows whose rows have n_1..n_R finite options (columns and the miss) has at
most prod_i n_i assignments. When that product is small (``ENUMERATION_LIMIT``) they are
all enumerated at once, conflicts dropped and the rest sorted: exact, and cheaper than
Murty's per-subproblem overhead (a few LAPs and partitions, each some dozen numpy calls),
which on the contended blocks of a window of markers (two or three rows, a handful of
options) dominates. Larger blocks are ranked by ``murty.MurtyRanking``, lazily.

The ranking of a block depends on its costs only. In ``mht`` the hypotheses of a frame
differ in a few markers, so most blocks of their F matrices are equal, entry for entry:
``RankingCache`` keys rankings by the block's costs and ranks each distinct block once,
however many hypotheses hold it (and however far down the list any of them reads).
"""

from __future__ import annotations

import itertools
import math
import operator

import numpy as np
from numpy.typing import NDArray

from formulations.assignment.murty import Costs, Indices, MurtyRanking, RankedAssignment

ENUMERATION_LIMIT = 512  # assignments of a block at most, before conflicts, to enumerate it whole


class BlockRanking:
    """A block's assignments cheapest first (its own columns, -1 unassigned), pulled on demand and kept."""

    def __init__(self, cost: Costs, miss: Costs | None) -> None:
        """``cost`` (R x C) and ``miss`` (R,) as in ``murty.MurtyRanking``."""
        extended = np.column_stack([cost, np.full(len(cost), np.inf) if miss is None else miss])
        options: list[int] = np.isfinite(extended).sum(axis=1).tolist()
        self.more: MurtyRanking | None = None
        self.found: list[RankedAssignment] = []
        if is_enumerated(np.isfinite(extended)):
            self.costs, self.columns = _enumerated(extended, options)
        else:
            self.costs, self.columns = np.empty(0), np.empty((0, len(cost)), dtype=np.intp)
            self.more = MurtyRanking(cost, miss)

    def get(self, index: int) -> RankedAssignment | None:
        """The block's ``index``-th best assignment, or None when it has fewer."""
        if index < len(self.costs):
            return RankedAssignment(float(self.costs[index]), self.columns[index])
        self._rank(index)
        return self.found[index] if index < len(self.found) else None

    def cost(self, index: int) -> float | None:
        """The ``index``-th best cost, or None when there are fewer assignments."""
        if index < len(self.costs):
            return float(self.costs[index])
        self._rank(index)
        return self.found[index].cost if index < len(self.found) else None

    def bound(self, index: int) -> tuple[float, bool]:
        """A lower bound on the ``index``-th best cost (inf: there is none), no LAP solved;
        and whether it is exact (that assignment ranked already, or known not to exist)."""
        if index < len(self.costs):
            return float(self.costs[index]), True
        if index < len(self.found):
            return self.found[index].cost, True
        return (np.inf, True) if self.more is None else (self.more.lower_bound(), False)

    def _rank(self, index: int) -> None:
        """Pull Murty's ranking until the ``index``-th best is found or there is none."""
        while len(self.found) <= index and self.more is not None:
            found = next(self.more, None)
            if found is None:
                self.more = None
            else:
                self.found.append(found)


def is_enumerated(finite: NDArray[np.bool_]) -> bool:
    """Whether a block whose finite entries (miss column last) are ``finite`` is enumerated whole."""
    options: list[int] = finite.sum(axis=1).tolist()
    return math.prod(options) <= ENUMERATION_LIMIT


class RankingCache:
    """Block rankings by the block's costs: a block met again (in another hypothesis's F) is ranked once."""

    def __init__(self) -> None:
        self.rankings: dict[tuple[tuple[int, ...], bytes, bytes], BlockRanking] = {}

    def ranking(self, cost: Costs, miss: Costs | None) -> BlockRanking:
        """The ranking of the block ``cost`` with misses ``miss``, ranked on first request."""
        key = (cost.shape, cost.tobytes(), b"" if miss is None else miss.tobytes())
        ranking = self.rankings.get(key)
        if ranking is None:
            ranking = self.rankings[key] = BlockRanking(cost, miss)
        return ranking


def _enumerated(extended: Costs, options: list[int]) -> tuple[Costs, Indices]:
    """Every assignment of ``extended`` (the last column: the miss; ``options[i]`` finite
    entries in row i): the costs sorted, and the columns of each (-1 unassigned).

    Assignment a picks, in row i, the finite entry number (a // prod_{i' > i} n_i') mod n_i."""
    rows, miss_column = extended.shape[0], extended.shape[1] - 1
    _, finite_column = np.nonzero(np.isfinite(extended))  # row by row
    start = list(itertools.accumulate(options[:-1], initial=0))
    stride = list(itertools.accumulate(options[:0:-1], operator.mul, initial=1))[::-1]
    digit = (np.arange(math.prod(options))[:, None] // stride) % np.maximum(options, 1)
    grid = finite_column[start + digit]
    ordered = np.sort(grid, axis=1)
    clash = ((ordered[:, 1:] == ordered[:, :-1]) & (ordered[:, 1:] != miss_column)).any(axis=1)
    grid = grid[~clash]
    total = extended[np.arange(rows), grid].sum(axis=1)
    order = np.argsort(total, kind="stable")
    columns: Indices = np.where(grid == miss_column, -1, grid)[order]
    return total[order], columns
