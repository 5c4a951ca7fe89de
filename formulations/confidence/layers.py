"""A window's per-object networks as dense layered cost tensors, for dynamic programming.

Object n's network is layered by frame: the source at frame 0, its candidate and occlusion
nodes at frames 1..M, its sink at M+1 (``WindowProblem``). With W_n at least n's largest
block, node v of object n at frame f is *slot* ``v - first[n, f]`` of that block, and every
arc is one entry of

    step_n[f, i, j] = c(slot i of (n, f), slot j of (n, f + 1)),   f = 0..M, i, j < W_n,

inf where there is no arc. Dynamic programmes over one object (``single``) or two
(``pairs``) then run one frame at a time over whole arrays, never over arcs.

Objects are batched by their widest block (powers of two), so that the few markers with a
wide gate do not widen everyone's W x W steps: a batch's objects share the batch's widest
block as W_n, and their tensors lie one after the other in one flat array, the batch's
``(objects, M + 1, W, W)`` a view of it. An entry past an object's W_n (a slot no block of
it has) reads the inf after the last tensor. On 03_rolling's windows (68 markers, a gate up
to 42 candidates wide) that is ~150k entries where one K x K tensor for all had 2.4M.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.window.problem import WindowProblem


@dataclass(frozen=True)
class Layers:
    """The window as ``(N, M + 2, K)`` slots (K the largest block) and every object's step costs.

    Attributes:
        first: ``(N, M + 2)`` first node of each (object, frame) block.
        step: Every object's ``(M + 1, W_n, W_n)`` arc costs between consecutive blocks, flat,
            inf where none; one inf more at the end.
        span: ``(N,)`` W_n.
        offset: ``(N,)`` where each object's steps start in ``step``.
        batches: The objects of each batch, ascending; their steps lie in that order.
        valid: ``(N, M + 2, K)`` the slot is a node.
        chosen: ``(N, M + 2)`` slot of the chosen path in every frame (0 at source and sink).
    """

    first: NDArray[np.intp]
    step: NDArray[np.float64]
    span: NDArray[np.intp]
    offset: NDArray[np.intp]
    batches: list[NDArray[np.intp]]
    valid: NDArray[np.bool_]
    chosen: NDArray[np.intp]

    @property
    def width(self) -> int:
        """K, the largest block."""
        return int(self.valid.shape[-1])

    def slot(self, problem: WindowProblem, node: NDArray[np.intp]) -> NDArray[np.intp]:
        """Slot of each node in its block."""
        slots: NDArray[np.intp] = node - self.first[problem.node_object[node], problem.node_frame[node]]
        return slots

    def nodes(self, problem: WindowProblem) -> NDArray[np.intp]:
        """``(N, M + 2, K)`` node of every slot (a valid node index also where not ``valid``)."""
        node: NDArray[np.intp] = np.minimum(self.first[..., None] + np.arange(self.width), problem.n_nodes - 1)
        return node

    def at(self, objects: NDArray[np.intp], frame: NDArray[np.intp], tail: NDArray[np.intp],
           head: NDArray[np.intp]) -> NDArray[np.intp]:
        """Index in ``step`` of step_n[f, i, j] (broadcast), the last inf where i or j >= W_n."""
        span = self.span[objects]
        index: NDArray[np.intp] = self.offset[objects] + (frame * span + tail) * span + head
        return np.where((tail < span) & (head < span), index, len(self.step) - 1)

    def batch(self, step: NDArray[np.float64], objects: NDArray[np.intp]) -> NDArray[np.float64]:
        """``(objects, M + 1, W, W)`` a batch's steps in ``step`` (laid out as ``self.step``), a view."""
        w, frames = int(self.span[objects[0]]), self.chosen.shape[1] - 1
        start = int(self.offset[objects[0]])
        return step[start : start + len(objects) * frames * w * w].reshape(len(objects), frames, w, w)

    def path_cost(self, step: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(N,)`` each object's chosen path priced by ``step`` (laid out as ``self.step``)."""
        n, frames = np.ogrid[: self.chosen.shape[0], : self.chosen.shape[1] - 1]
        cost: NDArray[np.float64] = step[self.at(n, frames, self.chosen[:, :-1], self.chosen[:, 1:])].sum(axis=1)
        return cost


def layers(problem: WindowProblem, path: NDArray[np.intp]) -> Layers:
    """The layered view of ``problem`` and its chosen ``path`` (``(N, M)`` nodes)."""
    first, size = problem.blocks()
    n, frames = problem.n_objects, problem.n_frames
    widest = size.max(axis=1)
    group = np.ceil(np.log2(np.maximum(widest, 1)))
    batches = [np.flatnonzero(group == value) for value in np.unique(group)]
    span = np.zeros(n, np.intp)
    for objects in batches:
        span[objects] = widest[objects].max()
    laid = np.concatenate(batches) if batches else np.zeros(0, np.intp)
    extent = (frames + 1) * span[laid] ** 2
    offset = np.zeros(n, np.intp)
    offset[laid] = np.cumsum(extent) - extent
    grid = Layers(first=first, step=np.full(int(extent.sum()) + 1, np.inf), span=span, offset=offset, batches=batches,
                  valid=np.arange(int(size.max())) < size[..., None], chosen=np.zeros((n, frames + 2), dtype=np.intp))
    # per node its slot and where its row of steps out starts (step_n[f, slot, 0]): an arc's
    # entry is then its tail's row plus its head's slot
    obj, frame = problem.node_object, problem.node_frame
    slot = np.arange(problem.n_nodes) - first[obj, frame]
    row = offset[obj] + (frame * span[obj] + slot) * span[obj]
    grid.step[row[problem.arc_tail] + slot[problem.arc_head]] = problem.arc_cost
    grid.chosen[:, 1:-1] = path - first[:, 1:-1]
    return grid
