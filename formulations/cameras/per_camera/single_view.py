"""Depth of a marker seen by one camera, from the markers that move rigidly with it.

One view fixes two of a marker's three coordinates: the point lies on the camera's ray
o + s d (s >= 0). While labeling, the depth s comes from the marker's prediction
(``Rig.on_ray``), which drifts as the marker stays single-viewed: on CMU 85_02 in the
Pose2Sim rig a toe seen by one camera for nine frames sat 45-60 mm off along its ray,
and the gap after it was filled between two such sightings, 61-65 mm off.

Once the take is labeled, the markers around it have been triangulated on both sides of
the single-view stretch, and the rigid-body fill (``markers.rigid_fill``: the weighted
Kabsch motion of the marker's most rigid donors, carried from both sightings and blended)
says where the marker is there, as it does for a gap. The single-view sightings are
therefore treated as a gap, refilled, and each is moved to the point of its own ray
nearest that refill y,

    x = o + max(0, d . (y - o)) d,

which keeps what the view measured and takes only the depth from the donors. Where the
refill has no donors on both sides it returns the fill it was given: here the sighting
itself, tied to the triangulated sightings on both sides (``gap_ends``), so the depth at
least meets theirs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.gap_ends import tie_gap_ends
from formulations.markers.rigid_fill import rigid_fill

Array = NDArray[np.float64]


def single_views_on_rays(
    positions: Array, filled: Array, single: NDArray[np.bool_], origin: Array, direction: Array,
) -> Array:
    """``positions`` ``(F, N, 3)`` with each single-view sighting moved along its ray (module doc).

    Args:
        positions: Located markers, NaN where no view.
        filled: The windows' fill where no view (NaN elsewhere).
        single: ``(F, N)`` marker-frames located from one view.
        origin, direction: ``(S, 3)`` camera centre and unit ray direction of each
            single-view sighting, in the order of ``np.nonzero(single)``.
    """
    if not single.any():
        return positions
    unseen = positions.copy()
    unseen[single] = np.nan
    prior = np.where(np.isfinite(filled), filled, positions)  # a gap's fill, or the sighting itself
    refill = rigid_fill(unseen, tie_gap_ends(unseen, prior))[single]
    along = np.maximum(np.einsum("sd,sd->s", refill - origin, direction), 0.0)
    placed = positions.copy()
    placed[single] = np.where(np.isfinite(refill), origin + along[:, None] * direction, positions[single])
    return placed
