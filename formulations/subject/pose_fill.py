"""A gap the rigid fill cannot agree on, filled where the segment's pose puts the marker.

``rigid_refill`` carries a lost marker from each sighting by its donors and blends the two
carries; how far they disagree, d_t = |y_a(t) - y_b(t)| / 2, says how little its donors
held the marker. Where two of a segment's three markers are lost while its neighbours lose
markers too (Rajagopal: LTB1 at frames 340-368 while the thigh and the foot each miss one),
the only donors left at both sightings are on other segments, and the carries disagree by
centimetres. In those frames the segment may still be posed: by its own labeled markers and
the centres of its joints as its neighbours' own markers place them (``segment_poses``,
each correspondence within ``RIGID_WITHIN`` tolerances). Where

    d_t > WITHIN_TOLERANCES * tau_p,

tau_p the marker's tolerance in the model, the fill is R_t u_p + d_t instead where the
segment is posed, and the rigid fill where it is not, the gap tied to both sightings
(``tie_gap_ends``: the marker sits on this subject a little off where the model has it).
Only joints the model places within ``GUIDE_RMS_MM`` pose through the chain: a poorly
fitted centre turns the segment it poses.

Measured (``bench/model_start.py``, fill RMSE of markers on segments of three or more, after
the joint-centre donors): Rajagopal 15.4 -> 12.4 mm, gait2354 6.4, CMU 85_02 10.8 and 135_02
221 unchanged; the bar at 1, 2 and 4 tolerances gave Rajagopal 13.3, 12.4 and 13.6.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.gap_ends import tie_gap_ends
from formulations.subject.geometry import ModelGeometry
from formulations.subject.joint_tracks import placed_well
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses

Array = NDArray[np.float64]
WITHIN_TOLERANCES = 2.0


def pose_fill(geometry: ModelGeometry, names: list[str], positions: Array, filled: Array, doubt: Array) -> Array:
    """``filled`` ``(F, N, 3)`` of the take ``positions`` ``(F, N, 3)`` (markers ``names``, NaN
    where not labeled), replaced by the tied segment pose where the rigid fill's ``doubt``
    ``(F, N)`` (its variance, mm^2) is above the bar and the segment is posed."""
    sure = replace(geometry, joints=placed_well(geometry))
    placed = segment_poses(sure, geometry.in_model_order(names, positions), RIGID_WITHIN).place(geometry)
    column = {name: i for i, name in enumerate(names)}
    has = [k for k, name in enumerate(geometry.names) if name in column]
    at = [column[geometry.names[k]] for k in has]
    unseen: NDArray[np.bool_] = ~np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    by_pose = np.full(filled.shape, np.nan)
    by_pose[:, at] = placed[:, has]
    bar = np.full(len(names), np.inf)
    bar[at] = (WITHIN_TOLERANCES * geometry.tolerance[has]) ** 2
    posed = unseen & np.isfinite(by_pose).all(axis=2)
    tied = tie_gap_ends(positions, np.where(posed[..., None], by_pose, filled))
    use = unseen & np.isfinite(tied).all(axis=2) & (doubt > bar[None])
    return np.where(use[..., None], tied, filled)
