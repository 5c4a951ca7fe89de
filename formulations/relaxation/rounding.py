"""Jiang's greedy rounding of a fractional solution (Sec. II-D, last paragraphs).

In each frame, repeatedly take the node with the largest y among those not yet visited,
set it to 1, and mark as visited the other nodes of its object in that frame and every
node sharing a conflict group with it. Occlusion nodes conflict with nothing, so every
object ends with exactly one node per frame and no conflict group is used twice: the
result is always feasible. Where the layers are not fully connected (skip arcs,
``formulations.window.skips``: gap nodes remember the path's last box, and returned copies
of a box are entered only by paths that re-entered), each chosen node its predecessor on
the path has no arc into is replaced by the node of its block standing for the same thing
(same kind and location: the other copy of the box, or the gap node of the path's own last
box) that it has an arc into, else by the one occlusion node it enters. Either consumes the
same resources or none, so feasibility holds; an integral solution's own paths are left as
they are.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from formulations.window.problem import OCCLUSION, WindowProblem


def round_greedy(problem: WindowProblem, y: np.ndarray) -> np.ndarray:
    """Round node values ``y`` (inflow of each node) to integral paths.

    Args:
        problem: The window.
        y: ``(V,)`` node values in [0, 1].

    Returns:
        ``(N, M)`` chosen node per object and frame.
    """
    groups = problem.conflict_groups
    rivals = (groups.T @ groups).tocsr() if groups.shape[0] else sp.csr_matrix((problem.n_nodes,) * 2)
    path = np.full((problem.n_objects, problem.n_frames), -1)
    inner = np.flatnonzero((problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames))
    # Largest y first; on ties prefer the occlusion node (it blocks nobody).
    order = inner[np.lexsort((problem.node_kind[inner] != OCCLUSION, -np.round(y[inner], 9), problem.node_frame[inner]))]
    visited = np.zeros(problem.n_nodes, dtype=bool)
    for v in order:
        n, m = problem.node_object[v], problem.node_frame[v] - 1
        if visited[v] or path[n, m] >= 0:
            continue
        path[n, m] = v
        visited[rivals.indices[rivals.indptr[v]:rivals.indptr[v + 1]]] = True
    return _connected(problem, path)


def _connected(problem: WindowProblem, path: np.ndarray) -> np.ndarray:
    """``path`` with each node its predecessor has no arc into replaced (module doc). The
    check is one lookup per frame; only the nodes it finds unconnected are looped over (none
    in Jiang's fully connected layers)."""
    keys = np.sort(problem.arc_tail.astype(np.int64) * problem.n_nodes + problem.arc_head)
    by_tail = np.argsort(problem.arc_tail, kind="stable")
    start = np.searchsorted(problem.arc_tail[by_tail], np.arange(problem.n_nodes + 1))
    previous = problem.source_nodes()
    for m in range(problem.n_frames):
        wanted = previous.astype(np.int64) * problem.n_nodes + path[:, m]
        found = keys[np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)] == wanted
        for n in np.flatnonzero(~found):
            heads = problem.arc_head[by_tail[start[previous[n]]:start[previous[n] + 1]]]
            v = path[n, m]
            same = heads[(problem.node_kind[heads] == problem.node_kind[v])
                         & (problem.node_location[heads] == problem.node_location[v]).all(axis=1)]
            path[n, m] = same[0] if len(same) else problem.gap_successor[previous[n]]
        previous = path[:, m]
    return path
