"""Entries of an assignment matrix that none of its k best assignments can take.

A row i with a finite miss cost u_i may always be left unassigned, which frees its column.
So an assignment sigma taking entries S with c_ij - u_i > D >= 0 is dearer, by more than D,
than sigma with the rows of S left unassigned (the sum of c_ij - u_i over S): every
assignment outside the matrix P that drops those entries costs more than best(P) + D.

D is chosen so that P keeps k assignments within D of the best sigma*. Each single change
of sigma* that stays feasible is another assignment: an assigned row left out (u_i - c_i*),
or any row moved to a column sigma* leaves free (c_ij - cost_i*); all are distinct, and none
takes a dropped entry (cost_i* <= u_i, as sigma* is optimal). With D the (k-1)-th smallest
of these steps the k-th best of P costs at most best + D, so P's k best are the whole
matrix's, exactly. In a window of markers a lost marker's wide gate reaches many points and
joins most rows into one block (median 4 rows, 90th percentile 64, on 03_rolling's ``mht``
reading); with the entries dearer than missing by more than D dropped, 2 and 4 rows, which
``rankings`` enumerates instead of running Murty's ranking over the whole block. It costs a
LAP on the whole matrix, so ``blocks`` drops entries only where a block is too large to
enumerate (on the milder scenario of ``bench/mht_speed.py``, where blocks are small, dropping
them always made ``mht`` slower: 2.17 -> 2.71 ms/frame on CMU 85_02). Real
03_rolling from frame 562 with ``--mht-reading`` took 62.2 s against 78.4 s (means of two
runs alternated, 2026-12-06), with the same labels.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from formulations.assignment.murty import Costs, with_miss_columns


def without_dominated(cost: Costs, miss: Costs | None, k: int) -> Costs:
    """``cost`` with inf where no one of the ``k`` best assignments can take the entry (a copy
    when any is dropped; ``cost`` itself when none can be: no misses, or k = 1)."""
    if miss is None or k < 2 or not np.isfinite(miss).all():
        return cost
    width = cost.shape[1]
    extended = with_miss_columns(cost, miss)
    row, column = linear_sum_assignment(extended)  # feasible: every row may miss
    own = extended[row, column]  # each row's cost in the best assignment (rows come in order)
    assigned = column < width
    free = np.ones(width, dtype=bool)
    free[column[assigned]] = False
    finite = np.isfinite(cost)
    steps = np.concatenate([(miss - own)[assigned], (cost[:, free] - own[:, None])[finite[:, free]]])
    if len(steps) < k - 1:
        return cost
    limit = np.partition(steps, k - 2)[k - 2]
    dropped = finite & (cost - miss[:, None] > limit)
    if not dropped.any():
        return cost
    return np.where(dropped, np.inf, cost)
