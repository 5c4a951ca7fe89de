"""The window problem: a layered network per object over one window of frames.

Jiang, Fels & Little (2008), Sec. II-B. For object ``n`` the network has a source
``s_n`` (the template, frame 0), per frame ``m = 1..M`` one node per candidate plus one
occlusion node (always the last node of its frame), and a sink ``t_n`` (frame M+1).
Arcs join every node of frame m to every node of frame m+1 of the same object.

Everything is held as flat arrays sorted by (object, frame, occlusion last) so that the
LP build, Viterbi and rounding are vectorised and never loop over arcs.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

SOURCE, OBSERVATION, OCCLUSION, SINK = 0, 1, 2, 3


@dataclass(frozen=True)
class WindowProblem:
    """One window of the multi-path tracking problem.

    Attributes:
        n_objects: Number of objects (markers) ``N``.
        n_frames: Frames after the template, ``M``.
        node_kind: ``(V,)`` one of SOURCE, OBSERVATION, OCCLUSION, SINK.
        node_object: ``(V,)`` object of each node.
        node_frame: ``(V,)`` 0 for sources, 1..M for candidates and occlusions, M+1 for sinks.
        node_location: ``(V, D)`` location vector r of each node (occlusion nodes carry the
            position the layout term should assume, e.g. the predicted one).
        resources: ``(V, R)`` sparse 0/1: the resources (e.g. point ids) a node consumes.
            Nodes of different objects sharing a resource form a conflict group.
        arc_tail, arc_head: ``(A,)`` node indices; arcs only join consecutive frames of one
            object.
        arc_cost: ``(A,)`` cost c of each arc.
        layout_pairs: ``(P, 2)`` object pairs under the layout term.
        layout_weight: ``(P,)`` weight mu of each pair.
    """

    n_objects: int
    n_frames: int
    node_kind: np.ndarray
    node_object: np.ndarray
    node_frame: np.ndarray
    node_location: np.ndarray
    resources: sp.csr_matrix
    arc_tail: np.ndarray
    arc_head: np.ndarray
    arc_cost: np.ndarray
    layout_pairs: np.ndarray
    layout_weight: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.node_kind)

    @property
    def n_arcs(self) -> int:
        return len(self.arc_tail)

    @property
    def dimension(self) -> int:
        return int(self.node_location.shape[1])

    @cached_property
    def conflict_groups(self) -> sp.csr_matrix:
        """Conflict groups as a ``(G, V)`` 0/1 matrix, one row per contested resource.

        A resource used by nodes of at least two objects gives one group: at most one of
        those nodes may lie on a path (Jiang's mutual-occlusion constraint).
        """
        used = self.resources.T.tocsr()  # (R, V)
        objects_per_resource = _distinct_objects_per_row(used, self.node_object)
        return used[objects_per_resource >= 2]

    @cached_property
    def arc_order(self) -> np.ndarray:
        """``(A,)`` the arcs sorted (stably) by (frame of the tail, head): ``viterbi.ArcLayers``'
        order, kept with the window so that a sub-window (``components.restrict``) takes its own
        from it instead of sorting again.

        Arcs join consecutive frames, so that order is the head's rank among the nodes by
        (frame, index): one stable sort on a key small enough for a radix sort.
        """
        rank = np.empty(self.n_nodes, np.min_scalar_type(max(self.n_nodes - 1, 0)))
        rank[np.argsort(self.node_frame, kind="stable")] = np.arange(self.n_nodes)
        order: np.ndarray = np.argsort(rank[self.arc_head], kind="stable")
        return order

    def blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """``(N, M+2)`` first node and node count of every (object, frame) block, frames 0..M+1."""
        starts = np.flatnonzero(_block_starts(self.node_object, self.node_frame))
        sizes = np.diff(np.r_[starts, self.n_nodes])
        shape = (self.n_objects, self.n_frames + 2)
        return starts.reshape(shape), sizes.reshape(shape)

    def frame_nodes(self) -> np.ndarray:
        """``(N, M)`` index of the first node of each (object, frame) block, frames 1..M."""
        return self.blocks()[0][:, 1:-1]

    def source_nodes(self) -> np.ndarray:
        return np.flatnonzero(self.node_kind == SOURCE)

    def sink_nodes(self) -> np.ndarray:
        return np.flatnonzero(self.node_kind == SINK)


def _block_starts(objects: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """True where a node opens a new (object, frame) block in the sorted order."""
    starts = np.ones(len(objects), dtype=bool)
    starts[1:] = (objects[1:] != objects[:-1]) | (frames[1:] != frames[:-1])
    return starts


def _distinct_objects_per_row(matrix: sp.csr_matrix, node_object: np.ndarray) -> np.ndarray:
    """Number of distinct objects among the nodes of each row of a (rows, V) matrix."""
    rows = np.repeat(np.arange(matrix.shape[0]), np.diff(matrix.indptr))
    if len(rows) == 0:
        return np.zeros(matrix.shape[0], dtype=int)
    # Each distinct (row, object) pair once, as one integer key. Sorted and deduplicated by hand:
    # np.unique hashes integers, 10x slower here, where the keys mostly come sorted already.
    n = int(node_object.max()) + 1
    keys = np.sort(rows * n + node_object[matrix.indices])
    pairs = keys[np.r_[True, keys[1:] != keys[:-1]]]
    return np.bincount(pairs // n, minlength=matrix.shape[0])
