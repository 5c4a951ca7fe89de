"""Two labelings of one take, merged where they disagree, group by group.

Two passes over a take (``service.labeling.second_pass``) mostly agree; where they do not,
each is often right somewhere the other is wrong (CMU Hamner running, default condition,
seed 0: the first pass had the right wrist's two markers right and the left wrist's
exchanged, the second the reverse; keeping either whole kept one exchange for 500 frames).
What the passes disagree on falls apart into groups that share no point: markers a and b
are joined when, in some frame, one pass gives a the point the other gives b (a = b too:
a marker whose labels differ). Each group is judged on its own by the labeled first frame
(``first_frame_shape``: its markers' distances to their rigid mates, capped, the cap where
a pass leaves a pair out) and takes the labels of the pass that bends them less.

No frame then gives one point to two markers: a point taken by a in one pass and by b in
the other joins a and b into one group, which takes both labels from one pass.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

Array = NDArray[np.float64]


def pass_per_marker(
    points: tuple[NDArray[np.int64], NDArray[np.int64]], capped: Array, judged: NDArray[np.bool_],
) -> NDArray[np.int64]:
    """``(N,)`` 0 or 1: whose labels each marker keeps (module doc); 0 where the passes agree.

    Args:
        points: Each pass's ``(F, N)`` point index per frame and marker, -1 unlabeled: those of
            the labels merged, or the groups do not keep one point to one marker.
        capped, judged: The passes' offsets off the labeled first frame, in the order of
            ``points`` (``first_frame_shape.pair_offsets``).
    """
    group, differs = _groups(*points)
    kept = np.zeros(points[0].shape[1], dtype=np.int64)
    if not differs.any():
        return kept
    per_marker = np.where(judged, capped, 0.0).sum(axis=(1, 3))  # (2, N)
    for g in np.unique(group[differs]):
        members = differs & (group == g)
        kept[members] = int(per_marker[1, members].sum() < per_marker[0, members].sum())
    return kept


def _groups(first: NDArray[np.int64], second: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
    """Each marker's group, and which markers' labels differ between the passes."""
    n = first.shape[1]
    differs = (first != second).any(axis=0)
    # Join the marker holding each (frame, point) in the first pass with its holder in the second.
    stride = int(max(first.max(initial=0), second.max(initial=0))) + 1
    f1, m1 = np.nonzero(first >= 0)
    f2, m2 = np.nonzero(second >= 0)
    key1, key2 = f1 * stride + first[f1, m1], f2 * stride + second[f2, m2]
    order = np.argsort(key2)
    at = np.minimum(np.searchsorted(key2[order], key1), max(len(key2) - 1, 0))
    shared = (key2[order][at] == key1) if len(key2) else np.zeros(len(key1), bool)
    a, b = m1[shared], m2[order][at][shared]
    rows, cols = np.r_[a, np.arange(n)], np.r_[b, np.arange(n)]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    group: NDArray[np.int64] = connected_components(graph, directed=False)[1]
    return group, differs
