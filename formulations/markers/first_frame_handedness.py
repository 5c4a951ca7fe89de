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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.first_frame_shape import PARTNERS, rigid_mates
from formulations.markers.mirror import MIN_SINE, sines

Array = NDArray[np.float64]

MIRRORED_SHARE = 0.7  # most of a stretch's judged labels flipped: a reflection, not noise
KEPT_SHARE = 0.1  # ... against almost none in the other labeling
MIN_JUDGED = 3  # judged labels in each labeling: one or two may be a flat moment's noise


def handedness_flips(labelings: list[Array], first: Array, neighbours: NDArray[np.int64]) -> Array:
    """``(P, F, N)`` 1 where a labeling's label flips its quadruple's handedness off the first
    frame, 0 where it keeps it, NaN where it is not judged (module doc).

    Args:
        labelings: ``(F, N, 3)`` labeled positions of each labeling, NaN where unlabeled.
        first: ``(N, 3)`` the labeled first frame (NaN for a marker it lacks).
        neighbours: ``(N, K)`` each marker's neighbours (``MarkerState.neighbours``).
    """
    mates, _ = rigid_mates(labelings, neighbours, PARTNERS)
    quads = np.column_stack([np.arange(len(first)), mates])
    then = sines(first[quads])
    then = np.where(np.abs(then) >= MIN_SINE, then, np.nan)  # NaN: a flat or unlabeled first quadruple
    flips = []
    for positions in labelings:
        now = sines(positions[:, quads].reshape(-1, 4, 3)).reshape(positions.shape[:2])
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
