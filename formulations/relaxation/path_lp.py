"""The window LP without a layout term, solved over whole paths (Dantzig-Wolfe).

Without the layout term, the arc LP (``lp_model``) is one unit flow per object through its
own layered DAG, coupled only by the conflict rows. A DAG's flow polytope is the convex
hull of its source-sink paths, so the same LP reads, over the paths P_n of each object n
(c_p the sum of its arc costs, a_gp how many of its nodes lie in conflict group g):

    min  sum_p c_p lambda_p
    s.t. sum_{p in P_n} lambda_p = 1            (sigma_n)   each object
         sum_p a_gp lambda_p    <= 1            (pi_g <= 0) each conflict group
         lambda >= 0,           xi_a = sum_{p through a} lambda_p.

Column generation: start from each object's Viterbi path and its all-occlusion path
(occlusion nodes are in no group, so this is feasible), solve, and price every object's
best path under the duals, one Viterbi with arc costs c_a - (G^T pi)_{head(a)}:

    rc_n = D_n(pi) - sigma_n.

Paths with rc_n < 0 enter; when none does, the restricted LP is the full LP's optimum.
Whatever the round, Lagrangian duality on the conflict rows gives a proven bound

    L(pi) = sum_n D_n(pi) + sum_g pi_g  <=  LP optimum  <=  min E,

and the restricted optimum is proven when it meets L(pi). The master has N + G rows
against the arc LP's one per node, which on large windows (long-occluded markers gating
many points, e.g. 03_rolling) makes it several times faster. Of the G rows it holds only
those of groups some column crosses (``_GroupRows``): a group no column crosses is slack
(its dual 0 at every optimum). By the last round nearly every group is crossed, but the
early masters are smaller, and their duals price fewer columns in (03_rolling's first-pass
windows 13,365 -> 12,437 columns, racing's 7,676 -> 5,966; LP time 3.90 -> 3.34 s and
5.56 -> 4.31 s, medians of 3 interleaved, noisy).

The master is solved by interior point until pricing finds nothing new: its duals are
central in the optimal dual face, where a simplex vertex's are extreme and swing from
round to round (on 03_rolling's largest windows the primal optimum is reached in a
quarter of the rounds, the rest only raise L(pi); central duals end in about a sixth of
the rounds with a tenth of the columns). The interior point is Clarabel's
(``solvers.clarabel_lp``: on masters this small HiGHS' IPX spent most of its time in a
fixed cost per solve). One primal simplex solve of the last master by HiGHS then gives the
vertex optimum the rounding expects, and pricing goes on with its duals, warm, in the rare
case they still price a column in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from formulations.relaxation.viterbi import ArcLayers
from formulations.solvers import LinearModel, SolveResult, create_backend
from formulations.window.objective import arc_index
from formulations.window.problem import WindowProblem

MAX_ROUNDS = 1000  # a stall guard for a caller that sets none
STALLED = "path pricing stopped at its round limit"
PROVEN = 1e-9  # relative gap between the restricted optimum and L(pi) that proves it optimal
# The interior point only supplies duals to price with: any pi <= 0 gives a valid bound
# L(pi), and the optimum reported is the simplex vertex's, so they need not be exact. At 1e-6
# (HiGHS' default 1e-8) the window LPs of a first pass took 43.7 -> 35.7 s on 03_rolling,
# 16.4 -> 14.4 s on racing and 0.46 -> 0.51 s (noise) on tennis, every window proven with
# the same objective (``bench/path_lp.py``, medians of 3 interleaved; measured with HiGHS'
# interior point, kept for Clarabel's).
PRICING_TOLERANCE = 1e-6
INTERIOR_POINT = "clarabel"  # the backend giving central duals (module docstring; ``bench/path_lp.py``)


def solve_path_lp(
    problem: WindowProblem, time_limit: float | None = None, max_rounds: int = MAX_ROUNDS,
) -> tuple[SolveResult, int]:
    """The LP optimum as arc values, by path column generation (see the module docstring).

    Args:
        problem: A (sub-)window without layout pairs of positive weight.
        time_limit: Seconds per restricted solve (None: no limit).
        max_rounds: Pricing rounds after which it stops, not optimal, with status ``STALLED``.

    Returns:
        The result (``x`` over the arcs, ``bound`` = the best L(pi), -inf if no restricted
        solve finished; ``optimal`` when the restricted optimum meets it), and the number of
        path columns.
    """
    if np.any(problem.layout_weight > 0):
        raise ValueError("the path LP has no layout term")
    n, groups, layers = problem.n_objects, problem.conflict_groups.tocsr(), ArcLayers.of(problem)
    node_groups = groups.tocsc()
    starts, sizes = problem.blocks()
    occluded = (starts + sizes - 1)[:, 1:-1]  # occlusion is the last node of each block
    # Priced in the layers' order: G^T pi and the arc costs are gathered there once per window.
    cost, node_groups_t = problem.arc_cost[layers.order], groups.T
    first, _ = layers.shortest_path_arcs(problem, cost)
    paths = np.vstack([first, _arcs_through(problem, np.arange(n), occluded)])
    objects = np.r_[np.arange(n), np.arange(n)]
    backend = interior = create_backend(INTERIOR_POINT)
    backend.set_timeout(time_limit)
    backend.set_interior_point(PRICING_TOLERANCE)
    rows = _GroupRows(np.full(groups.shape[0], -1))
    matrix = _columns(problem, node_groups, objects, paths, rows)
    backend.set_model(LinearModel(
        cost=problem.arc_cost[paths].sum(axis=1), matrix=matrix,
        row_lower=np.r_[np.ones(n), np.full(rows.count, -np.inf)], row_upper=np.ones(n + rows.count),
        col_lower=np.zeros(2 * n), col_upper=np.full(2 * n, np.inf),
    ))
    seen = {(o, p.tobytes()) for o, p in zip(objects, paths)}
    result = backend.solve()
    bound, central = -np.inf, True
    for _ in range(max_rounds):
        entering: list[int] = []
        if result.optimal:
            sigma, pi = result.row_dual[:n], rows.group_duals(np.minimum(result.row_dual[n:], 0.0))
            priced = cost - (node_groups_t @ pi)[layers.head] if len(pi) else cost
            best, distance = layers.shortest_path_arcs(problem, priced)
            bound = max(bound, float(distance.sum() + pi.sum()))
            if not _proven(result.objective, bound):
                entering = [int(o) for o in np.flatnonzero(distance - sigma < 0) if (o, best[o].tobytes()) not in seen]
        if central and not entering:  # done (or the interior point failed): a vertex, warm from here on
            central = False
            backend = create_backend("highs")
            backend.set_timeout(time_limit)
            backend.set_primal_simplex()  # added columns keep its basis primal feasible
            backend.set_model(interior.model)
            result = backend.solve()
            continue
        if not entering:
            break
        seen.update((o, best[o].tobytes()) for o in entering)
        new = best[entering]
        held = rows.count
        matrix = _columns(problem, node_groups, np.asarray(entering), new, rows)
        if rows.count > held:  # groups first crossed
            backend.add_rows(np.full(rows.count - held, -np.inf), np.ones(rows.count - held))
        backend.add_columns(problem.arc_cost[new].sum(axis=1), np.zeros(len(new)), np.full(len(new), np.inf), matrix)
        objects, paths = np.r_[objects, entering], np.vstack([paths, new])
        result = backend.solve()
    xi = np.zeros(problem.n_arcs)
    if len(result.x):
        np.add.at(xi, paths.ravel(), np.repeat(result.x, paths.shape[1]))
    result.x, result.bound = np.minimum(xi, 1.0), bound
    if result.optimal and entering:  # the last round still priced columns in
        result.optimal, result.status = False, STALLED
    elif result.optimal and not _proven(result.objective, bound):
        result.optimal, result.status = False, "path pricing stopped short of the LP optimum"
    return result, len(paths)


def _proven(objective: float, bound: float) -> bool:
    return objective - bound <= PROVEN * max(1.0, abs(objective))


def _arcs_through(problem: WindowProblem, objects: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """``(K, M+1)`` arcs of the paths of ``objects`` through ``nodes`` ``(K, M)``, source to sink."""
    full = np.column_stack([problem.source_nodes()[objects], nodes, problem.sink_nodes()[objects]])
    return arc_index(problem, full[:, :-1].ravel(), full[:, 1:].ravel()).reshape(len(nodes), -1)


@dataclass
class _GroupRows:
    """Which conflict groups the master holds a row for: those some column crosses, in the
    order they were first crossed, after the N object rows.

    Attributes:
        row: ``(G,)`` each group's row among the master's group rows, -1 while none.
        count: Group rows in the master.
    """

    row: np.ndarray
    count: int = 0

    def of(self, groups: np.ndarray) -> np.ndarray:
        """The group rows of ``groups`` (counted after the object rows), new ones appended."""
        new = np.unique(groups[self.row[groups] < 0])
        self.row[new] = self.count + np.arange(len(new))
        self.count += len(new)
        rows: np.ndarray = self.row[groups]
        return rows

    def group_duals(self, dual: np.ndarray) -> np.ndarray:
        """``(G,)`` the duals of every group from the master's group rows' ``dual``: 0 for a group
        no column crosses (its row would be slack)."""
        full = np.zeros(len(self.row))
        held = self.row >= 0
        full[held] = dual[self.row[held]]
        return full


def _columns(problem: WindowProblem, node_groups: sp.csc_matrix, objects: np.ndarray, paths: np.ndarray,
             rows: _GroupRows) -> sp.csc_matrix:
    """The master columns of paths (their arcs ``(K, M+1)``): the object's row, then a_gp per group
    (``rows`` gives each group its master row, adding those first crossed).

    ``node_groups`` is the ``(G, V)`` conflict matrix in CSC: a node's groups are one slice.
    Built from index arithmetic, as a scipy product per round costs more than the solve.
    """
    k, n = len(paths), problem.n_objects
    nodes = problem.arc_head[paths[:, :-1]]
    counts = np.diff(node_groups.indptr)[nodes]  # (K, M) groups per node on each path
    per_column = counts.sum(axis=1)
    first = np.repeat(node_groups.indptr[nodes.ravel()], counts.ravel())
    within = np.arange(len(first)) - np.repeat(np.cumsum(counts.ravel()) - counts.ravel(), counts.ravel())
    group_rows = n + rows.of(node_groups.indices[first + within])
    # CSC arrays written directly, as the COO route gave them (scipy sorts each column's rows and
    # sums duplicates: a group a path crosses twice is one entry of 2), at a fraction of its cost.
    height = n + rows.count
    key = np.sort(np.repeat(np.arange(k), per_column) * height + group_rows)  # (column, group row)
    opens = np.ones(len(key), bool)
    np.not_equal(key[1:], key[:-1], out=opens[1:])
    distinct = key[opens]
    column = distinct // height
    index = np.int32 if max(height, k + len(key)) < 2**31 else np.int64  # scipy's choice of index type
    indptr = np.zeros(k + 1, index)
    np.cumsum(np.bincount(column, minlength=k) + 1, out=indptr[1:])
    heads = np.zeros(indptr[-1], bool)
    heads[indptr[:-1]] = True  # each column's object row first: below every group row
    indices, data = np.empty(indptr[-1], index), np.ones(indptr[-1])
    indices[heads], indices[~heads] = objects, distinct - column * height
    data[~heads] = np.diff(np.flatnonzero(np.append(opens, True)))
    matrix = sp.csc_matrix((data, indices, indptr), shape=(height, k))
    matrix.has_canonical_format = True  # sorted, no duplicates: scipy need not check again
    return matrix
