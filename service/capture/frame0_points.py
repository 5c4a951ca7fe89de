"""Whether a 3D capture's labeled first frame sits on its frame 0's points.

Frame 0 is the labeled frame: each labeled marker is one of frame 0's points, up to the
noise. A first frame in another unit, other axes or from another take put 30 of CMU 85_02's
41 markers "occluded" in frame 0 with confidence 1 and labeled the rest from there, without
a word; camera mode refuses the same mistake (``reprojection.frame0_problem``). A marker is
*off* when no point of frame 0 lies within half its distance to its nearest labeled
neighbour (beyond that the point is as likely a neighbour's); a take whose labeled markers
are mostly off is refused. One marker off (its point missing in frame 0) is the take's own.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from service.errors import InputError

OFF_SHARE = 0.5  # more than half the labeled markers off: the frame is not frame 0's


def check_frame0_points(first_frame: np.ndarray, points0: np.ndarray) -> None:
    """Raise ``InputError`` when most labeled markers of ``first_frame`` ``(N, 3)`` (NaN where
    unlabeled) have no point of frame 0 ``(P, 3)`` near them (module doc)."""
    labeled = first_frame[np.isfinite(first_frame).all(axis=1)]
    if len(labeled) < 3 or len(points0) == 0:  # too few to tell a spacing, or frame 0 is empty
        return
    spacing = cKDTree(labeled).query(labeled, k=2)[0][:, 1]
    offset = cKDTree(points0).query(labeled)[0]
    off = offset > spacing / 2
    if off.mean() > OFF_SHARE:
        raise InputError(
            f"first_frame: {off.sum()} of {len(labeled)} labeled markers have no point of frame 0 within half their "
            f"spacing (median {np.median(offset):.3g} off): the labeled frame must be frame 0 of the points, in their "
            "unit and axes"
        )
