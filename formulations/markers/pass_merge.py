"""Two labelings of one take, merged where they disagree, group by group.

Two passes over a take (``service.labeling.second_pass``) mostly agree; where they do not,
each is often right somewhere the other is wrong (CMU Hamner running, default condition,
seed 0: the first pass had the right wrist's two markers right and the left wrist's
exchanged, the second the reverse; keeping either whole kept one exchange for 500 frames).
What the passes disagree on falls apart into groups that share no point: markers a and b
are joined when, in some frame, one pass gives a the point the other gives b (a = b too:
a marker whose labels differ). Each group is judged on its own by the labeled first frame
(``first_frame_shape``: its markers' distances to their rigid mates, capped, the cap where
a pass leaves a pair out), run by run: a run is a stretch of frames in which some member's
labels differ, between frames where the passes agree on the whole group. The group as a whole
takes the labels of the pass that bends it less over the take; a run whose own frames say
clearly otherwise (one pass bends the group there less by ``NEAR_TIE`` of the larger bend) takes
the other pass's. A group is often right in one pass in one stretch and in the other pass in
the next (a wrist exchanged by the first pass early and by the second late); judged over the
whole take it kept one of the two errors. A short run's bends are close and noisy, so a near
tie keeps the whole take's verdict (every run judged alone: on the seed-0 accuracy matrix 12
rows up and 9 down, racing at 2 mm -1.4 and 03_rolling with ghosts -1.0 points).

No frame then gives one point to two markers: a point taken by a in one pass and by b in
the other joins a and b into one group, which takes both labels from one pass in each
frame (outside its runs the passes give the group the same labels).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from formulations.markers.runs import runs

Array = NDArray[np.float64]

NEAR_TIE = 0.1  # of the larger bend: a run's two readings closer than this are a tie


def labels_taken(
    points: tuple[NDArray[np.int64], NDArray[np.int64]], capped: Array, judged: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """``(F, N)`` True where a marker's label is taken from the second pass (module doc).

    Args:
        points: Each pass's ``(F, N)`` point index per frame and marker, -1 unlabeled: those of
            the labels merged, or the groups do not keep one point to one marker.
        capped, judged: The passes' offsets off the labeled first frame, in the order of
            ``points`` (``first_frame_shape.pair_offsets``).
    """
    group, differs = _groups(*points)
    taken = np.zeros(points[0].shape, dtype=bool)
    if not differs.any():
        return taken
    per_label = np.where(judged, capped, 0.0).sum(axis=3)  # (2, F, N)
    for g in np.unique(group[differs]):
        members = np.flatnonzero(differs & (group == g))
        apart = (points[0][:, members] != points[1][:, members]).any(axis=1)
        bend = per_label[:, :, members].sum(axis=2)  # (2, F)
        whole = bend[1].sum() < bend[0].sum()
        for start, length in runs(apart):
            run = slice(start, start + length)
            mine, theirs = bend[0, run].sum(), bend[1, run].sum()
            clear = abs(mine - theirs) >= NEAR_TIE * max(mine, theirs)
            if (theirs < mine) if clear else whole:
                taken[run, members] = True
    return taken


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
    if len(key2):
        at = np.minimum(np.searchsorted(key2[order], key1), len(key2) - 1)
        shared = key2[order][at] == key1
        a, b = m1[shared], m2[order][at][shared]
    else:  # the second labels nothing: no point is shared
        a = b = np.zeros(0, dtype=np.int64)
    rows, cols = np.r_[a, np.arange(n)], np.r_[b, np.arange(n)]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    group: NDArray[np.int64] = connected_components(graph, directed=False)[1]
    return group, differs
