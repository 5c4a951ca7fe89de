"""The window LP of Jiang, Fels & Little (2008), Sec. II-D, as sparse matrices.

Columns: one xi per arc, then p+ and p- per layout row. The node values y and
locations p are linear in xi, so they are substituted rather than kept as columns:

    y_v = sum_{a: head(a) = v} xi_a                    (inflow)
    p_{n,m} = sum_{v in (n, m)} r_v y_v

Rows:
    sum_{a: tail(a) = s_n} xi_a = 1                     source of each object
    y_v - sum_{a: tail(a) = v} xi_a = 0                 conservation, frames 1..M
    sum_{v in G} y_v <= 1                               each conflict group G
    (p_{a,m} - p_{a,m+1} - p_{b,m} + p_{b,m+1})_l - p+ + p- = 0
                                                        layout pair (a, b), m = 1..M-1, each l
minimise  sum_a c_a xi_a + sum mu_ab (p+ + p-),   xi, p+, p- >= 0.

(The sink row is implied by conservation.) Built without a Python loop over arcs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from formulations.solvers import LinearModel
from formulations.window.problem import WindowProblem


def inflow_matrix(problem: WindowProblem) -> sp.csr_matrix:
    """``(V, A)`` with a 1 where arc a enters node v: y = H xi."""
    a = problem.n_arcs
    return sp.csr_matrix((np.ones(a), (problem.arc_head, np.arange(a))), shape=(problem.n_nodes, a))


def _outflow_matrix(problem: WindowProblem) -> sp.csr_matrix:
    a = problem.n_arcs
    return sp.csr_matrix((np.ones(a), (problem.arc_tail, np.arange(a))), shape=(problem.n_nodes, a))


def _layout_rows(problem: WindowProblem) -> sp.csr_matrix:
    """``(L, A)``: the L1 layout differences as linear functions of xi, rows (l, pair, m)."""
    n, m = problem.n_objects, problem.n_frames
    pairs = problem.layout_pairs
    if len(pairs) == 0 or m < 2:
        return sp.csr_matrix((0, problem.n_arcs))
    head = problem.arc_head
    inner = np.flatnonzero((problem.node_frame[head] >= 1) & (problem.node_frame[head] <= m))
    block = problem.node_object[head[inner]] * m + problem.node_frame[head[inner]] - 1
    steps = m - 1
    rows = np.arange(len(pairs) * steps)
    frame = np.tile(np.arange(steps), len(pairs))
    a_obj, b_obj = np.repeat(pairs[:, 0], steps), np.repeat(pairs[:, 1], steps)
    difference = sp.csr_matrix(
        (np.tile([1.0, -1.0, -1.0, 1.0], len(rows)),
         (np.repeat(rows, 4),
          np.column_stack([a_obj * m + frame, a_obj * m + frame + 1, b_obj * m + frame, b_obj * m + frame + 1]).ravel())),
        shape=(len(rows), n * m),
    )
    per_dim = []
    for l in range(problem.dimension):
        location = sp.csr_matrix(
            (problem.node_location[head[inner], l], (block, inner)), shape=(n * m, problem.n_arcs)
        )
        per_dim.append(difference @ location)
    return sp.vstack(per_dim).tocsr()


def window_lp(problem: WindowProblem, integer: bool = False) -> LinearModel:
    """The LP (or, with ``integer``, the 0/1 program) of a window."""
    inflow, outflow = inflow_matrix(problem), _outflow_matrix(problem)
    inner = np.flatnonzero((problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames))
    groups = problem.conflict_groups
    layout = _layout_rows(problem)
    n_layout = layout.shape[0]
    mu = np.tile(np.repeat(problem.layout_weight, max(problem.n_frames - 1, 0)), problem.dimension)
    arc_block = sp.vstack([
        outflow[problem.source_nodes()],
        inflow[inner] - outflow[inner],
        groups @ inflow,
        layout,
    ])
    eye = sp.identity(n_layout, format="csr")
    zeros = sp.csr_matrix((arc_block.shape[0] - n_layout, 2 * n_layout))
    aux_block = sp.vstack([zeros, sp.hstack([-eye, eye])])
    matrix = sp.hstack([arc_block, aux_block]).tocsc()
    n_src, n_inner, n_groups = problem.n_objects, len(inner), groups.shape[0]
    row_lower = np.concatenate([np.ones(n_src), np.zeros(n_inner), np.full(n_groups, -np.inf), np.zeros(n_layout)])
    row_upper = np.concatenate([np.ones(n_src), np.zeros(n_inner), np.ones(n_groups), np.zeros(n_layout)])
    n_cols = problem.n_arcs + 2 * n_layout
    integer_cols = np.r_[np.ones(problem.n_arcs, bool), np.zeros(2 * n_layout, bool)] if integer else None
    return LinearModel(
        cost=np.concatenate([problem.arc_cost, mu, mu]),
        matrix=matrix, row_lower=row_lower, row_upper=row_upper,
        col_lower=np.zeros(n_cols),
        col_upper=np.concatenate([np.ones(problem.n_arcs), np.full(2 * n_layout, np.inf)]),
        integer=integer_cols,
    )
