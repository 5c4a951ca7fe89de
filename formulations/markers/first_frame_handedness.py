"""Which of two labelings of one stretch mirrors its markers' rigid quadruples off the labeled first frame.

Distances are blind to reflections. A toe and a fifth-metatarsal marker, nearly equidistant
from heel and ankle, keep every distance to their rigid mates when exchanged, so the merges'
bends (``first_frame_shape``, ``pass_merge``) tie on such an exchange, or favour it under
noise (CMU 85_02 with every condition combined, seed 0: LTOE and LMT5 exchanged in both window
passes from frame 423 to the end, bends 13,999 against 14,440 for the frame-by-frame reading,
which has them right). Handedness is not blind: the signed volume of four markers

    V(a, b, c, d) = ((b - a) x (c - a)) . (d - a)

keeps its sign under every rigid motion and flips under any exchange among them (``mirror``,
which repairs the same at templates where all four are seen). For each label (t, m) of a
labeling that labels m's three rigid mates too (``first_frame_shape.rigid_mates``), the
quadruple's sine s = V / (|b - a| |c - a| |d - a|) is compared with the first frame's. It is
judged where both are at least ``MIN_SINE`` from 0 (a flatter quadruple flips through flat as
skin slides), and flipped where the signs differ.

Of two labelings of the same cells, one is the mirrored one when at least ``MIRRORED_SHARE`` of
its judged labels there are flipped, at most ``KEPT_SHARE`` of the other's, and each has at
least ``MIN_JUDGED``: most of one and almost none of the other, so noise near ``MIN_SINE``
does not decide.

Measured (both merges, 2026-12-06, against the bends alone): seed-0 accuracy matrix 2 rows up
and 1 down of 85, seeds 1-2 7 up and 5 down of 170 (validation means 99.32 -> 99.32 % and
99.22 -> 99.25 %, swaps 826 -> 815 and 1,753 -> 1,733), the matrix's clean, 3 mm and combined
rows 2 up and 2 down of 51; every real take the same (``docs/track.md``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from formulations.markers.first_frame_shape import PARTNERS, mate_offsets, rigid_mates
from formulations.markers.mirror import MIN_SINE, sines

Array = NDArray[np.float64]

MIRRORED_SHARE = 0.7  # most of a stretch's judged labels flipped: a reflection, not noise
KEPT_SHARE = 0.1  # ... against almost none in the other labeling
MIN_JUDGED = 3  # judged labels in each labeling: one or two may be a flat moment's noise


class FirstFrameJudges(NamedTuple):
    """What the merges judge two labelings by, from one choice of rigid mates: the capped pair
    offsets and the triples judged (``first_frame_shape.pair_offsets``), and the handedness flips."""

    capped: Array
    judged: NDArray[np.bool_]
    flips: Array


def first_frame_judges(labelings: list[Array], first: Array, neighbours: NDArray[np.int64]) -> FirstFrameJudges:
    """Both judges of ``labelings`` (``(F, N, 3)``, NaN unlabeled) against the labeled ``first``
    frame, each marker's rigid mates found once among its ``neighbours``."""
    mates, spread = rigid_mates(labelings, neighbours, PARTNERS)
    return FirstFrameJudges(*mate_offsets(labelings, first, mates, spread), handedness_flips(labelings, first, mates))


def handedness_flips(labelings: list[Array], first: Array, mates: NDArray[np.int64],
                     markers: NDArray[np.int64] | None = None) -> Array:
    """``(P, F, M)`` 1 where a labeling's label flips its quadruple's handedness off the first
    frame, 0 where it keeps it, NaN where it is not judged (module doc).

    Args:
        labelings: ``(F, N, 3)`` labeled positions of each labeling, NaN where unlabeled.
        first: ``(N, 3)`` the labeled first frame (NaN for a marker it lacks).
        mates: ``(N, 3)`` each marker's rigid mates (``first_frame_shape.rigid_mates``).
        markers: the M markers judged; every one when None.
    """
    judged_markers = np.arange(len(first)) if markers is None else np.asarray(markers)
    if mates.shape[1] < 3:  # a take of three markers or fewer has no quadruple: nothing judged
        return np.full((len(labelings), len(labelings[0]), len(judged_markers)), np.nan)
    quads = np.column_stack([judged_markers, mates[judged_markers]])
    then = sines(first[quads])
    then = np.where(np.abs(then) >= MIN_SINE, then, np.nan)  # NaN: a flat or unlabeled first quadruple
    flips = []
    for positions in labelings:
        now = sines(positions[:, quads].reshape(-1, 4, 3)).reshape(len(positions), len(quads))
        judged = np.isfinite(then)[None] & (np.abs(now) >= MIN_SINE)  # NaN compares False: not judged
        flips.append(np.where(judged, (now * then[None] < 0).astype(float), np.nan))
    return np.stack(flips)


def mirrored_side(flips: Array) -> int | None:
    """Of ``(2, C)`` two labelings' flips over the same cells, the index of the mirrored one
    (module doc), or None when neither is clearly."""
    judged = np.isfinite(flips).sum(axis=1)
    if (judged < MIN_JUDGED).any():
        return None
    share = np.nansum(flips, axis=1) / judged
    for side in (0, 1):
        if share[side] >= MIRRORED_SHARE and share[1 - side] <= KEPT_SHARE:
            return side
    return None
