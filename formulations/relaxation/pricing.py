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

from formulations.relaxation.viterbi import shortest_paths
from formulations.solvers import LinearModel, SolverBackend, SolveResult
from formulations.window.objective import path_arcs
from formulations.window.problem import OCCLUSION, SINK, WindowProblem

PRICING_MIN_ARCS = 4000  # price columns in only when a (sub-)window has more arcs
PRICING_SUCCESSORS = 1  # cheapest out-arcs per node in the first restricted LP


def solve_with_pricing(
    model: LinearModel, backend: SolverBackend, initial: np.ndarray, tolerance: float = 1e-9,
    max_new_columns: int = 5000,
) -> tuple[SolveResult, int]:
    """Solve ``model`` by pricing columns in from ``initial``.

    Args:
        model: The full LP.
        backend: A solver backend that supports ``add_columns`` with a warm start (its
            timeout, if set, holds per restricted solve). Switched to primal simplex.
        initial: ``(n,)`` bool, the columns to start with. Must give a feasible LP.
        tolerance: Reduced cost below ``-tolerance`` enters.
        max_new_columns: At most this many columns enter per round (most negative first).

    Returns:
        The result with ``x`` mapped onto all columns, and the number of pricing rounds.
    """
    matrix = sp.csc_matrix(model.matrix)
    active = np.flatnonzero(initial)
    # Primal simplex: columns added by pricing keep the basis primal feasible.
    backend.set_primal_simplex()
    backend.set_model(_columns(model, matrix, active))
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


def initial_columns(problem: WindowProblem, n_columns: int, successors: int = PRICING_SUCCESSORS) -> np.ndarray:
    """``(n_columns,)`` bool: the k cheapest successors of each node, every arc into an
    occlusion node or sink (so the restricted LP is feasible), the Viterbi arcs, and every
    column after the arcs (the layout columns)."""
    initial = np.ones(n_columns, dtype=bool)
    arcs = _cheapest_per_tail(problem, successors)
    head_kind = problem.node_kind[problem.arc_head]
    arcs |= (head_kind == OCCLUSION) | (head_kind == SINK)
    arcs[path_arcs(problem, shortest_paths(problem)[0]).ravel()] = True
    initial[: problem.n_arcs] = arcs
    return initial


def _cheapest_per_tail(problem: WindowProblem, k: int) -> np.ndarray:
    """Mask of the k cheapest out-arcs of every node.

    Arcs are built grouped by tail, so k passes of a segmented minimum do it without
    sorting all arcs.
    """
    order = np.arange(problem.n_arcs) if np.all(np.diff(problem.arc_tail) >= 0) else np.argsort(problem.arc_tail, kind="stable")
    tail, cost = problem.arc_tail[order], problem.arc_cost[order].copy()
    starts = np.flatnonzero(np.r_[True, tail[1:] != tail[:-1]])
    group = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(tail)]))
    chosen = np.zeros(problem.n_arcs, dtype=bool)
    for _ in range(k):
        best = np.minimum.reduceat(cost, starts)
        hits = np.flatnonzero((cost <= best[group]) & np.isfinite(cost))
        first = hits[np.r_[True, group[hits][1:] != group[hits][:-1]]]
        chosen[order[first]] = True
        cost[first] = np.inf
    return chosen


def _columns(model: LinearModel, matrix: sp.csc_matrix, columns: np.ndarray) -> LinearModel:
    return LinearModel(
        cost=model.cost[columns], matrix=matrix[:, columns], row_lower=model.row_lower,
        row_upper=model.row_upper, col_lower=model.col_lower[columns], col_upper=model.col_upper[columns],
    )
