"""Labeled tracks extended over the points no marker took, frame by frame from each gap's ends.

A window leaves a marker occluded where its gate missed it: one back from a gap whose
prediction had drifted, picked up frames later, or one a subject model names only at the next
template frame. Its point was there, and no marker took it. Once every window is labeled,
each gap of marker n (frames s..e, unlabeled) is entered from each labeled side with at
least two labeled frames before it, by constant velocity,

    x^(s) = x(s - 1) + (x(s - 1) - x(s - 2))      (from the left; mirrored from the right),

and takes the point of frame s that no marker holds within g_n of x^ when it is the only
such point; the step is repeated from the point taken. g_n = ``GATE_MEDIANS`` times the median
of |x(t + 1) - 2 x(t) + x(t - 1)| over the marker's own labeled triples (at least
``MIN_TRIPLES``): its own constant-velocity residual, about 4.6 sd per axis for Gaussian
acceleration, so a ghost is as unlikely to fall inside as the take's noise allows. That
median is the calm motion's. Where the limb accelerates at a gap's end, the end's gate is
``GATE_MEDIANS`` times the least residual of its own last ``END_TRIPLES`` labeled triples when
that is larger (a triple not all labeled counts 0): an acceleration every one of the last
three steps showed, where one noisy or wrong label shows in one. In a tennis serve's strike
at 50 Hz the upper arm's step left constant velocity by 20-74 mm a frame against g_n = 19 mm,
and the walk in from the end labeled in the strike stopped at its first frame (accuracy
matrix, tennis with deletions, seed 0: RUPA's point free and unlabeled for 32 frames). Every end
moves one frame per round, from both sides; a point two ends want in one round goes to
neither, nor does a frame that a marker's two ends read differently (nothing here can say
which is right), so the result does not depend on the markers' order.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import chain

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from formulations.markers.lengths import lengths

Array = NDArray[np.float64]
Index = NDArray[np.int64]
GATE_MEDIANS = 3.0  # the 99.9th percentile of a 3D Gaussian's norm is 2.6 times its median
MIN_TRIPLES = 10  # fewer labeled triples say nothing of how the marker moves
_FRAME_APART = 1e9  # mm between frames in the search tree: a query finds its own frame only
END_TRIPLES = 3  # an acceleration lasts frames; one residual may be noise or a wrong label
_CHUNK_FRAMES = 4096  # residuals at a time in ``_gates``: over the whole take, 3 kB a frame at 41 markers


def extend_tracks(points: Sequence[Array], point_index: Index) -> Index:
    """``point_index`` ``(F, N)`` (-1 unlabeled) with gaps entered over unclaimed points (module doc)."""
    taken = np.array(point_index, dtype=np.int64)
    counts = np.array([len(p) for p in points])
    if not counts.sum():
        return taken
    offsets = np.concatenate([[0], np.cumsum(counts)])
    # the tree's (x, y, z, frame * _FRAME_APART), built in place: its first three columns are
    # the points themselves, not a copy of them beside it (the tree keeps the array it is given)
    searched = np.empty((offsets[-1], 4))
    np.concatenate([np.asarray(p, float).reshape(-1, 3) for p in points], out=searched[:, :3])
    searched[:, 3] = np.repeat(np.arange(len(points)) * _FRAME_APART, counts)
    flat = searched[:, :3]
    tree = cKDTree(searched)
    claimed = np.zeros(len(flat), bool)
    held = taken >= 0
    claimed[(offsets[:-1, None] + taken)[held]] = True
    gate = _gates(flat, offsets, taken)
    gated: dict[int, dict[int, list[int]]] = {1: {}, -1: {}}
    while _extend_once(tree, flat, offsets, claimed, taken, gate, gated):
        pass
    return taken


def _extend_once(
    tree: cKDTree, flat: Array, offsets: Index, claimed: NDArray[np.bool_], taken: Index, gate: Array,
    gated: dict[int, dict[int, list[int]]],
) -> bool:
    """Move every gap end one frame inwards; True if any marker took a point. ``gated``: per
    direction, the points in each end's gate (``_wanted``)."""
    frame, marker, want = (np.concatenate(a) for a in zip(*(
        _wanted(tree, flat, offsets, claimed, taken, gate, step, gated[step]) for step in (1, -1))))
    ok = want >= 0
    frame, marker, want = np.unique(np.column_stack([frame[ok], marker[ok], want[ok]]), axis=0).T
    # a point two ends want, or a frame one marker's two ends read differently: nothing here can say which is right
    _, by_point, point_count = np.unique(want, return_inverse=True, return_counts=True)
    _, by_slot, slot_count = np.unique(np.column_stack([frame, marker]), axis=0, return_inverse=True, return_counts=True)
    keep = (point_count[by_point] == 1) & (slot_count[by_slot.ravel()] == 1)
    claimed[want[keep]] = True
    taken[frame[keep], marker[keep]] = want[keep] - offsets[frame[keep]]
    return bool(keep.any())


def _wanted(
    tree: cKDTree, flat: Array, offsets: Index, claimed: NDArray[np.bool_], taken: Index, gate: Array, step: int,
    gated: dict[int, list[int]],
) -> tuple[Index, Index, Index]:
    """Gap ends entered in direction ``step``: frame, marker and the one free point in the gate (-1 none).

    ``gated`` keeps the points in each end's gate by slot (frame * N + marker) from round to
    round: x^ reads two labeled frames, which no round changes, and most ends wait many
    rounds (two free points in the gate) while another end moves. The end's gate reads up to
    five: a frame behind a short labeled run that a later round labels is not read again, so
    that end keeps the narrower gate (the result still does not depend on the markers' order).
    """
    labeled = taken >= 0
    ends = ~labeled & _shifted(labeled, step) & _shifted(labeled, 2 * step) & np.isfinite(gate)[None]
    frame, marker = np.nonzero(ends)
    want = np.full(len(frame), -1, dtype=np.int64)
    if not len(frame):
        return frame, marker, want
    slots = (frame * taken.shape[1] + marker).tolist()
    new = np.array([k for k, slot in enumerate(slots) if slot not in gated], dtype=np.int64)
    if len(new):
        f, m = frame[new], marker[new]
        last = flat[offsets[f - step] + taken[f - step, m]]
        prior = flat[offsets[f - 2 * step] + taken[f - 2 * step, m]]
        guess = np.column_stack([2 * last - prior, f * _FRAME_APART])
        radius = _end_gates(flat, offsets, taken, f, m, step, gate)
        for k, points in zip(new.tolist(), tree.query_ball_point(guess, radius)):
            gated[slots[k]] = points
    found = [gated[slot] for slot in slots]
    # every end's points as one flat array: no Python loop over the ends' points
    count = np.fromiter(map(len, found), np.int64, len(found))
    point = np.fromiter(chain.from_iterable(found), np.int64, count.sum())
    free = ~claimed[point]
    end = np.repeat(np.arange(len(found)), count)[free]
    alone = np.bincount(end, minlength=len(found))[end] == 1
    want[end[alone]] = point[free][alone]
    return frame, marker, want


def _shifted(labeled: NDArray[np.bool_], lag: int) -> NDArray[np.bool_]:
    """``(F, N)`` whether the frame ``lag`` before (``lag`` < 0: after) was labeled; False off the take."""
    out = np.zeros_like(labeled)
    if lag > 0:
        out[lag:] = labeled[:-lag]
    else:
        out[:lag] = labeled[-lag:]
    return out


def _gates(flat: Array, offsets: Index, taken: Index) -> Array:
    """``(N,)`` g_n (module doc); inf where a marker has fewer than ``MIN_TRIPLES`` triples."""
    gate = np.full(taken.shape[1], np.inf)
    position = np.full(taken.shape + (3,), np.nan)
    held = taken >= 0
    position[held] = flat[(offsets[:-1, None] + taken)[held]]
    residual = np.empty((max(len(position) - 2, 0), taken.shape[1]))
    for start in range(0, len(residual), _CHUNK_FRAMES):  # its (F, N, 3) temporaries a chunk at a time
        near = position[start : start + _CHUNK_FRAMES + 2]
        residual[start : start + len(near) - 2] = lengths(near[2:] - 2 * near[1:-1] + near[:-2])
    enough = np.isfinite(residual).sum(axis=0) >= MIN_TRIPLES
    gate[enough] = GATE_MEDIANS * np.nanmedian(residual[:, enough], axis=0)
    return gate


def _end_gates(flat: Array, offsets: Index, taken: Index, f: Index, m: Index, step: int, gate: Array) -> Array:
    """``(E,)`` each end's gate (module doc): g_n, or ``GATE_MEDIANS`` times the least residual
    of the marker's last ``END_TRIPLES`` labeled triples before the end, when that is larger."""
    residual = np.zeros((END_TRIPLES, len(f)))
    for j in range(END_TRIPLES):
        frames = f[:, None] - step * (np.arange(3) + 1 + j)  # the triple, nearest the end first
        inside = ((frames >= 0) & (frames < len(taken))).all(axis=1)
        held = np.zeros(len(f), bool)
        held[inside] = (taken[frames[inside], m[inside, None]] >= 0).all(axis=1)
        if held.any():
            a, b, c = (flat[offsets[frames[held, k]] + taken[frames[held, k], m[held]]] for k in range(3))
            residual[j, held] = lengths(a - 2 * b + c)
    out: Array = np.maximum(gate[m], GATE_MEDIANS * residual.min(axis=0))
    return out
