"""Jiang's greedy rounding of a fractional solution (Sec. II-D, last paragraphs).

In each frame, repeatedly take the node with the largest y among those not yet visited,
set it to 1, and mark as visited the other nodes of its object in that frame and every
node sharing a conflict group with it. Occlusion nodes conflict with nothing, so every
object ends with exactly one node per frame and no conflict group is used twice: the
result is always feasible.
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
    path = np.full((problem.n_objects, problem.n_frames), -1)
    value = np.round(y, 9)
    inner = np.flatnonzero((problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames))
    inner = inner[_takeable(problem, value, inner)]
    # Largest y first; on ties prefer the occlusion node (it blocks nobody).
    order = inner[np.lexsort((problem.node_kind[inner] != OCCLUSION, -value[inner], problem.node_frame[inner]))]
    # An occlusion node blocks nobody and is never blocked: it takes its block unless a node
    # before it did, and no node after it can. So the greedy runs over the nodes before their
    # block's occlusion node (with ``_takeable``, every candidate), the occlusion nodes after.
    block = problem.node_object * problem.n_frames + problem.node_frame - 1
    occluded = problem.node_kind[order] == OCCLUSION
    occlusion_at = np.full(problem.n_objects * problem.n_frames, len(order))
    occlusion_at[block[order[occluded]]] = np.flatnonzero(occluded)
    candidate = order[np.flatnonzero(~occluded & (np.arange(len(order)) < occlusion_at[block[order]]))]
    groups = problem.conflict_groups  # the nodes a candidate takes from others: its groups' nodes
    rivals = groups.T.tocsr()[candidate] @ groups if groups.shape[0] else sp.csr_matrix((len(candidate), problem.n_nodes))
    # The greedy is sequential; it reads Python ints and lists, numpy scalars cost 5x as much.
    visited = np.zeros(problem.n_nodes, dtype=bool)
    taken = path.ravel()  # block (n, m) at n * M + m
    first, last = rivals.indptr[:-1].tolist(), rivals.indptr[1:].tolist()
    for v, b, lo, hi in zip(candidate.tolist(), block[candidate].tolist(), first, last):
        if visited[v] or taken[b] >= 0:
            continue
        taken[b] = v
        visited[rivals.indices[lo:hi]] = True
    occlusion = order[occluded]
    left = taken[block[occlusion]] < 0
    taken[block[occlusion[left]]] = occlusion[left]
    return path


def _takeable(problem: WindowProblem, value: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """``(len(inner),)`` the nodes the greedy can take: a node valued at most its object's
    occlusion node in that frame comes after it in the order, and an occlusion node is never
    blocked, so it is never taken (a window's LP puts most candidates at 0)."""
    occlusion = np.full((problem.n_objects, problem.n_frames + 2), -np.inf)
    occluded = inner[problem.node_kind[inner] == OCCLUSION]
    occlusion[problem.node_object[occluded], problem.node_frame[occluded]] = value[occluded]
    bar = occlusion[problem.node_object[inner], problem.node_frame[inner]]
    takeable: np.ndarray = (problem.node_kind[inner] == OCCLUSION) | (value[inner] > bar)
    return takeable
