"""Two labelings of one take, merged where they disagree, event by event.

Two passes over a take (``service.labeling.second_pass``) mostly agree; where they do not,
each is often right somewhere the other is wrong (CMU Hamner running, default condition,
seed 0: the first pass had the right wrist's two markers right and the left wrist's
exchanged, the second the reverse; keeping either whole kept one exchange for 500 frames).
What the passes disagree on falls apart into *events*: the (frame, marker) cells whose labels
differ, two cells joined when, in one frame, one pass gives one the point the other gives
the other, or when they are one marker's in consecutive frames. An event is judged on its own
by the labeled first frame (``first_frame_shape``: its markers' distances to their rigid
mates, the cap where a pass leaves a pair out or bends it past the tolerance), over its
frames and markers, and takes the labels of the pass that bends it less by ``NEAR_TIE`` of
the larger bend. A near tie is close and noisy, so it keeps the verdict of the event's
*group*, the markers joined by a shared point anywhere in the take, judged over the whole
take (every event judged alone: on the seed-0 accuracy matrix 12 rows up and 9 down, racing
at 2 mm -1.4 and 03_rolling with ghosts -1.0 points, when events were still runs).

Each label's bend is R times the mean capped offset of its judged pairs, R times the cap
where it is left out: a marker left out costs the same whoever it is. Summed over its pairs,
a leave-out cost the cap per pair judged, so leaving out a marker with three partners seen
outweighed leaving out one with one (03_rolling with ghosts, seed 0: LL_USP, absent, put on
LL_RSP's point for 94 frames with LL_RSP left out, kept over the right labels).

Events, not groups: a group joined across the body by one shared point (an acromion, a heel,
thigh and shank markers on 03_rolling) was judged as a whole over every frame where any
member differed, so two exchanges at once, one in each pass, tied and one stayed.

Handedness before bends: where one pass's labels of an event mirror their markers' rigid
quadruples off the first frame and the other's do not (``first_frame_handedness``), the event
takes the other's, whatever the bends say; distances cannot see such an exchange.

No frame then gives one point to two markers: a point taken by a in one pass and by b in
the other joins the two cells into one event, which takes both labels from one pass.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from formulations.markers.first_frame_handedness import mirrored_side
from formulations.markers.first_frame_shape import CAP_MM

Array = NDArray[np.float64]
Cells = tuple[NDArray[np.int64], NDArray[np.int64]]

NEAR_TIE = 0.1  # of the larger bend: an event's two readings closer than this are a tie


def labels_taken(
    points: tuple[NDArray[np.int64], NDArray[np.int64]], capped: Array, judged: NDArray[np.bool_],
    cap_mm: float = CAP_MM, flips: Array | None = None,
) -> NDArray[np.bool_]:
    """``(F, N)`` True where a marker's label is taken from the second pass (module doc).

    Args:
        points: Each pass's ``(F, N)`` point index per frame and marker, -1 unlabeled: those of
            the labels merged, or the events do not keep one point to one marker.
        capped, judged: The passes' offsets off the labeled first frame, in the order of
            ``points`` (``first_frame_shape.pair_offsets``).
        cap_mm: The cap those offsets were computed with: a leave-out costs it per partner.
        flips: ``(2, F, N)`` the passes' handedness flips, in the same order
            (``first_frame_handedness.handedness_flips``); None judges by bends alone.
    """
    taken = np.zeros(points[0].shape, dtype=bool)
    (frame, marker), event = _events(*points)
    if not len(frame):
        return taken
    bend = _label_bends(points, capped, judged, cap_mm)
    group = _groups(*points)
    differs = np.unique(marker)
    # Each group's bend over the take, summed over its markers whose labels differ somewhere.
    whole = [np.bincount(group[differs], bend[p][:, differs].sum(axis=0), len(group)) for p in (0, 1)]
    order = np.argsort(event, kind="stable")
    for cells in np.split(order, np.flatnonzero(np.diff(event[order])) + 1):
        frames, markers = frame[cells], marker[cells]
        box = np.ix_(np.unique(frames), np.unique(markers))
        mine, theirs = bend[0][box].sum(), bend[1][box].sum()
        clear = abs(mine - theirs) >= NEAR_TIE * max(mine, theirs)
        g = group[markers[0]]
        mirrored = None if flips is None else mirrored_side(flips[:, frames, markers])
        if mirrored == 0 or (mirrored is None and ((theirs < mine) if clear else whole[1][g] < whole[0][g])):
            taken[frames, markers] = True
    return taken


def _label_bends(
    points: tuple[NDArray[np.int64], NDArray[np.int64]], capped: Array, judged: NDArray[np.bool_], cap_mm: float,
) -> Array:
    """``(2, F, N)`` each label's bend (module doc): R times its mean capped offset over its
    judged pairs, R times the cap where it is left out or has no pair judged."""
    partners = capped.shape[3]
    count = judged.sum(axis=2)
    mean = np.where(judged, capped, 0.0).sum(axis=3) / np.maximum(count, 1)
    bends: Array = partners * np.where((np.stack(points) >= 0) & (count > 0), mean, cap_mm)
    return bends


def _events(first: NDArray[np.int64], second: NDArray[np.int64]) -> tuple[Cells, NDArray[np.int64]]:
    """The (frame, marker) cells whose labels differ, and each one's event (module doc)."""
    frame, marker = np.nonzero(first != second)
    cell = np.full(first.shape, -1)
    cell[frame, marker] = np.arange(len(frame))
    has_next = frame + 1 < first.shape[0]
    following = cell[frame[has_next] + 1, marker[has_next]]
    a, b = np.flatnonzero(has_next)[following >= 0], following[following >= 0]
    stride = _stride(first, second)
    one, two = first[frame, marker], second[frame, marker]
    i, j = _same_point(np.where(one >= 0, frame * stride + one, -1), np.where(two >= 0, frame * stride + two, -2))
    rows, cols = np.r_[a, i, np.arange(len(frame))], np.r_[b, j, np.arange(len(frame))]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(frame), len(frame)))
    event: NDArray[np.int64] = connected_components(graph, directed=False)[1]
    return (frame, marker), event


def _groups(first: NDArray[np.int64], second: NDArray[np.int64]) -> NDArray[np.int64]:
    """Each marker's group: markers joined when one pass gives one the point the other gives
    the other in some frame."""
    stride = _stride(first, second)
    f1, m1 = np.nonzero(first >= 0)
    f2, m2 = np.nonzero(second >= 0)
    i, j = _same_point(f1 * stride + first[f1, m1], f2 * stride + second[f2, m2])
    n = first.shape[1]
    rows, cols = np.r_[m1[i], np.arange(n)], np.r_[m2[j], np.arange(n)]
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    group: NDArray[np.int64] = connected_components(graph, directed=False)[1]
    return group


def _stride(first: NDArray[np.int64], second: NDArray[np.int64]) -> int:
    """More than any point index: ``frame * stride + point`` numbers every frame's points apart."""
    return int(max(first.max(initial=0), second.max(initial=0))) + 1


def _same_point(key1: NDArray[np.int64], key2: NDArray[np.int64]) -> Cells:
    """The pairs (i, j) with ``key1[i] == key2[j]`` (a pass holds a point once a frame, so
    ``key2``'s keys are distinct)."""
    if not len(key2):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.argsort(key2)
    at = np.minimum(np.searchsorted(key2[order], key1), len(key2) - 1)
    found = key2[order][at] == key1
    return np.flatnonzero(found), order[at][found]
