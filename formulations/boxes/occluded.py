"""An object's boxes while it is occluded: between two of its sightings, on the straight line.

The tracker holds an object through up to ``Lifecycle.max_occluded`` frames unseen (Jiang's
occlusion nodes: the object is there, hidden), and an object that leaves is never seen again
under its identity. So every gap inside one track is a span the object was held occluded,
and its box at frame t between sightings (t_a, b_a) and (t_b, b_b) is

    b(t) = b_a + (t - t_a) / (t_b - t_a) * (b_b - b_a),

the constant-velocity path through both sightings: the mean a Kalman smoother gives when the
process noise is small against the span, and it needs no state from the run. Ground truth
such as MOTChallenge's keeps people while they are occluded, so a tracker that says an object
is behind another should also say where.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


def occluded_boxes(frame: Ints, ident: Ints, box: Array) -> tuple[Ints, Ints, Array]:
    """The frames, identities and boxes of every object between consecutive sightings.

    Args:
        frame: ``(K,)`` frame of each tracked box.
        ident: ``(K,)`` its object; an object has at most one box per frame.
        box: ``(K, 4)`` the box in any coordinates that move linearly (left, top, width, height).

    Returns:
        ``(frame, ident, box)`` of the occluded boxes, one row per frame of each gap.
    """
    order = np.lexsort((frame, ident))
    f, i, b = frame[order], ident[order], np.asarray(box, dtype=float)[order]
    gap = np.diff(f)
    before = np.flatnonzero((i[1:] == i[:-1]) & (gap > 1))  # the sighting each gap starts from
    missing = gap[before] - 1
    row = np.repeat(before, missing)
    step = np.arange(missing.sum()) - np.repeat(np.cumsum(missing) - missing, missing) + 1
    share = step / gap[row]
    return f[row] + step, i[row], b[row] + share[:, None] * (b[row + 1] - b[row])
