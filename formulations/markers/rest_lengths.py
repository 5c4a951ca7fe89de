"""The distance each rigid pair keeps: the labeled first frame's, unless the first frame is
an outlier of the distances the labelings agree on over the take.

The merges judge two labelings by how far each bends a marker's rigid mates off their rest
length (``first_frame_shape``). The first frame gives one sample of each distance, in one
pose. CMU 85_02 under the hard preset, seed 0: the right ankle marker is 182.6 mm from the toe
in the first frame and 163.5 mm (median; sd 5.9) over the take, as the first frame has the foot
on its toes; a point 163.4 mm from the ankle then fits "fifth metatarsal" (150.7 mm in the
first frame) better than "toe", and the merge kept the reading that gave the toe's 87 frames
to the fifth metatarsal.

Replacing every first-frame distance by the take's median was tried twice and moved rows
both ways (docs/track.md, "Second pass"): a pair over sliding skin (03_rolling's acromion
and upper arm, 146 to 191 mm over the take) has no one rest length, and the first frame
serves as well as any. So the median replaces the first frame's distance only where the
first frame is an outlier of the pair's own distribution: over the frames where every
labeling labels both markers at the same points (at least ``MIN_AGREED``), the median lies
more than ``OUTLIER_SDS`` of the pair's spread off the first frame's distance, and within the
pair's tolerance of it (labelings wrong alike over most of the take cannot move it by a
marker spacing).

Measured (lp-l1, 2026-12-06, against the first frame's distances alone; docs/track.md): seed-0
accuracy matrix 1 row up and none down of 85 (03_rolling at 4 mm 95.94 -> 96.62 %), seeds 1-2 4
up and 1 down of 170; hard preset 2 of 9 runs up (85_02 seed 0 99.23 -> 99.99 %, 03_rolling
seed 0 89.09 -> 89.83 %), none down; the matrix's other conditions, the whole-length takes and
the real takes the same but 5 labels of real 03_rolling.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

MIN_AGREED = 20  # as ``take_spread.MIN_FRAMES``: fewer frames say too little of a distance
OUTLIER_SDS = 3.0  # a first-frame distance this far off the take's median: that pose is rare


def rest_lengths(labelings: list[Array], mates: NDArray[np.int64], distance: Array, d0: Array, spread: Array,
                 tolerance: Array) -> Array:
    """``(N, R)`` each marker's rest length to each of its ``mates`` (module doc), mm.

    Args:
        labelings: ``(F, N, 3)`` labeled positions of each labeling, NaN where unlabeled.
        mates: ``(N, R)`` each marker's rigid mates.
        distance: ``(F, N, R)`` the first labeling's distance of each marker to its mates.
        d0: ``(N, R)`` the same in the labeled first frame (NaN for a marker it lacks).
        spread: ``(N, R)`` each pair's distance variance over the take, mm^2 (NaN unknown).
        tolerance: ``(N, R)`` how far a rest length may move off the first frame's, mm.
    """
    positions = labelings[0]
    same: NDArray[np.bool_] = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)  # (F, N)
    for other in labelings[1:]:
        same &= (other == positions).all(axis=2)
    agreed = same[:, :, None] & same[:, mates]  # (F, N, R)
    enough = agreed.sum(axis=0) >= MIN_AGREED
    median = np.full(d0.shape, np.nan)
    if enough.any():
        median[enough] = np.nanmedian(np.where(agreed, distance, np.nan)[:, enough], axis=0)
    off = np.abs(median - d0)
    outlier = enough & (off > OUTLIER_SDS * np.sqrt(spread)) & (off <= tolerance)  # NaN compares False
    rest: Array = np.where(outlier, median, d0)
    return rest
