"""Solve a window LP over a few arcs first, adding arcs only while they can help.

Column generation (delayed column pricing): solve the LP restricted to a subset S of
the arc columns, read the row duals y, and compute every left-out arc's reduced cost

    rc_a = c_a - A_a^T y.

If no rc_a < 0 the restricted optimum is optimal for the full LP (LP duality); otherwise
add the most negative arcs and re-solve from the current basis. On dense windows (every
observation a candidate of every object) most arcs are never priced in, which is what
makes Jiang's Table I instance solvable in milliseconds rather than seconds.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from formulations.solvers import LinearModel, SolverBackend, SolveResult


def solve_with_pricing(
    model: LinearModel, backend: SolverBackend, initial: np.ndarray, tolerance: float = 1e-9,
    max_new_columns: int = 5000, time_limit: float | None = None,
) -> tuple[SolveResult, int]:
    """Solve ``model`` by pricing columns in from ``initial``.

    Args:
        model: The full LP.
        backend: A solver backend that supports ``add_columns`` with a warm start.
        initial: ``(n,)`` bool, the columns to start with. Must give a feasible LP.
        tolerance: Reduced cost below ``-tolerance`` enters.
        max_new_columns: At most this many columns enter per round (most negative first).
        time_limit: Seconds per restricted solve (None: no limit).

    Returns:
        The result with ``x`` mapped onto all columns, and the number of pricing rounds.
    """
    matrix = sp.csc_matrix(model.matrix)
    active = np.flatnonzero(initial)
    backend.set_model(_columns(model, matrix, active), time_limit)
    result = backend.solve()
    rounds = 1
    while result.optimal:
        reduced = model.cost - matrix.T @ result.row_dual
        reduced[active] = 0.0
        entering = np.flatnonzero(reduced < -tolerance)
        if len(entering) == 0:
            break
        entering = entering[np.argsort(reduced[entering])[:max_new_columns]]
        backend.add_columns(model.cost[entering], model.col_lower[entering], model.col_upper[entering], matrix[:, entering])
        active = np.concatenate([active, entering])
        result = backend.solve()
        rounds += 1
    x = np.zeros(len(model.cost))
    if len(result.x):
        x[active] = result.x
    result.x = x
    return result, rounds


def _columns(model: LinearModel, matrix: sp.csc_matrix, columns: np.ndarray) -> LinearModel:
    return LinearModel(
        cost=model.cost[columns], matrix=matrix[:, columns], row_lower=model.row_lower,
        row_upper=model.row_upper, col_lower=model.col_lower[columns], col_upper=model.col_upper[columns],
    )
