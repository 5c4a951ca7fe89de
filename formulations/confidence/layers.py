"""A window's per-object networks as dense layered cost tensors, for dynamic programming.

Object n's network is layered by frame: the source at frame 0, its candidate and occlusion
nodes at frames 1..M, its sink at M+1 (``WindowProblem``). With K the largest block, node v
of object n at frame f is *slot* ``v - first[n, f]`` of that block, and every arc is one
entry of

    step[n, f, i, j] = c(slot i of (n, f), slot j of (n, f + 1)),   f = 0..M,

inf where there is no arc. Dynamic programmes over one object (``single``) or two
(``pairs``) then run one frame at a time over whole arrays, never over arcs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.window.problem import WindowProblem


@dataclass(frozen=True)
class Layers:
    """The window as ``(N, M + 2, K)`` slots and ``(N, M + 1, K, K)`` step costs.

    Attributes:
        first: ``(N, M + 2)`` first node of each (object, frame) block.
        step: ``(N, M + 1, K, K)`` arc costs between consecutive blocks, inf where none.
        valid: ``(N, M + 2, K)`` the slot is a node.
        chosen: ``(N, M + 2)`` slot of the chosen path in every frame (0 at source and sink).
    """

    first: NDArray[np.intp]
    step: NDArray[np.float64]
    valid: NDArray[np.bool_]
    chosen: NDArray[np.intp]

    @property
    def width(self) -> int:
        """K, the largest block."""
        return int(self.step.shape[-1])

    def slot(self, problem: WindowProblem, node: NDArray[np.intp]) -> NDArray[np.intp]:
        """Slot of each node in its block."""
        slots: NDArray[np.intp] = node - self.first[problem.node_object[node], problem.node_frame[node]]
        return slots

    def nodes(self, problem: WindowProblem) -> NDArray[np.intp]:
        """``(N, M + 2, K)`` node of every slot (a valid node index also where not ``valid``)."""
        node: NDArray[np.intp] = np.minimum(self.first[..., None] + np.arange(self.width), problem.n_nodes - 1)
        return node

    def path_cost(self, step: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(N,)`` each object's chosen path priced by ``step`` (``(N, M + 1, K, K)``)."""
        n, frames = np.indices(self.chosen[:, :-1].shape)
        cost: NDArray[np.float64] = step[n, frames, self.chosen[:, :-1], self.chosen[:, 1:]].sum(axis=1)
        return cost


def layers(problem: WindowProblem, path: NDArray[np.intp]) -> Layers:
    """The dense layered view of ``problem`` and its chosen ``path`` (``(N, M)`` nodes)."""
    first, size = problem.blocks()
    width = int(size.max())
    n, frames = problem.n_objects, problem.n_frames
    step = np.full((n, frames + 1, width, width), np.inf)
    tail, head = problem.arc_tail, problem.arc_head
    obj, frame = problem.node_object[tail], problem.node_frame[tail]
    step[obj, frame, tail - first[obj, frame], head - first[obj, frame + 1]] = problem.arc_cost
    chosen = np.zeros((n, frames + 2), dtype=np.intp)
    chosen[:, 1:-1] = path - first[:, 1:-1]
    return Layers(first=first, step=step, valid=np.arange(width) < size[..., None], chosen=chosen)
