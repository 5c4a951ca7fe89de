"""A filled marker put on the ray of the one camera that still sees it.

With ``joint-3d`` a marker is labeled only where two or more cameras' detections meet in
a 3D point; seen by one camera it is occluded, and its position is the fill (its rigid
donors' motion, tied to both sightings). Yet that one detection fixes two of the
marker's three coordinates. In CMU 85_02 in Pose2Sim's 4-camera rig, RWRA and RFIN,
lost together for 20-60 frames while one camera kept each in view, were filled 28-31 mm
off; on their rays only the depth along the ray is left to the fill.

Per frame and camera, the detections no labeled marker explains (none of the 3D points
the labels took uses them, and none lies within ``EXPLAINED_PX`` of a labeled marker's
image, since a point need not use every view of its marker) are matched to the filled
markers by the least total image distance (Hungarian), within a gate of ``GATE_MM`` at
the marker's depth, ``GATE_MM`` f_c / z_c pixels: a fill drifts in millimetres, not
pixels. A marker matched in exactly one camera moves to the point of that ray nearest
its fill,

    x = o + max(0, d . (y - o)) d,

which keeps what the view measured and takes only the depth from the fill. A marker
matched in two or more cameras is left as it is: those views should have made a 3D
point, and one that did not is suspect.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from formulations.cameras.rig import Rig

Array = NDArray[np.float64]
# A marker lost for tens of frames is filled a few cm off (85_02: 28-31 mm RMSE at the
# wrist); twice that still excludes a neighbour's detection 60 mm away only by its
# direction, so the Hungarian match between filled markers settles close pairs.
GATE_MM = 50.0
EXPLAINED_PX = 3.0  # the cross-camera matcher's epipolar tolerance: a labeled marker's own view


def fills_on_lone_views(
    filled: Array, occluded: NDArray[np.bool_], labeled: Array, rig: Rig,
    normalised: Sequence[Sequence[Array]], used: Sequence[Sequence[NDArray[np.bool_]]],
) -> Array:
    """``filled`` ``(F, N, 3)`` with each marker seen by one camera's unexplained detection put on its ray.

    Args:
        filled: The fill, NaN where labeled.
        occluded: ``(F, N)`` markers not labeled.
        labeled: ``(F, N, 3)`` labeled positions, NaN where occluded.
        rig: The cameras.
        normalised: ``normalised[f][c]`` ``(D, 2)`` undistorted detections of camera c.
        used: ``used[f][c]`` ``(D,)`` detections a labeled 3D point uses.
    """
    out = filled.copy()
    for f in (int(f) for f in np.flatnonzero((occluded & np.isfinite(filled).all(axis=2)).any(axis=1))):
        markers = np.flatnonzero(occluded[f] & np.isfinite(filled[f]).all(axis=1))
        match = _matches(filled[f, markers], labeled[f], rig, normalised[f], used[f])  # (M, C) detection, -1
        lone = (match >= 0).sum(axis=1) == 1
        for m in np.flatnonzero(lone):
            c = int(np.argmax(match[m] >= 0))
            ray = normalised[f][c][match[m, c]][None]
            out[f, markers[m]] = rig.on_ray(c, ray, filled[f, markers[m]][None])[0]
    return out


def _matches(
    fills: Array, labeled: Array, rig: Rig, normalised: Sequence[Array], used: Sequence[NDArray[np.bool_]],
) -> NDArray[np.int_]:
    """``(M, C)`` the unexplained detection each filled marker takes in each camera, -1 none."""
    image, depth = rig.image_plane(fills)  # (C, M, 2), (C, M)
    known = labeled[np.isfinite(labeled).all(axis=1)]
    known_image = rig.image_plane(known)[0]  # (C, K, 2)
    match = np.full((len(fills), len(rig)), -1)
    for c in range(len(rig)):
        free = _unexplained(normalised[c], used[c], known_image[c], rig.focal[c])
        if not len(free):
            continue
        pixels = np.linalg.norm(image[c][:, None] - normalised[c][free][None], axis=2) * rig.focal[c]
        gate = GATE_MM * rig.focal[c] / np.where(depth[c] > 0, depth[c], np.nan)
        cost = np.where(pixels <= gate[:, None], pixels, np.inf)
        rows = np.flatnonzero(np.isfinite(cost).any(axis=1))
        if not len(rows):
            continue
        finite = np.where(np.isfinite(cost[rows]), cost[rows], 1e12)
        r, k = linear_sum_assignment(finite)
        keep = np.isfinite(cost[rows[r], k])
        match[rows[r[keep]], c] = free[k[keep]]
    return match


def _unexplained(detections: Array, used: NDArray[np.bool_], known: Array, focal: float) -> NDArray[np.int_]:
    """Detections no labeled point uses and no labeled marker's image lies within ``EXPLAINED_PX`` of."""
    free = np.flatnonzero(~used)
    if not len(free) or not len(known):
        return free
    near = np.linalg.norm(detections[free][:, None] - known[None], axis=2) * focal <= EXPLAINED_PX
    explained = np.asarray(np.asarray(near, dtype=bool).any(axis=1), dtype=bool)
    kept: NDArray[np.int_] = free[~explained]
    return kept
