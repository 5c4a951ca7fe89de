"""Which cross-camera hypotheses survive: one per 3D point, detections shared out.

Within each frame, hypotheses are ranked by views (most first), then reprojection RMS.

Same point. A hypothesis within the 3D size of ``max_px`` at its depth (max_px z / f over
the cameras it uses) of a better-ranked one is the same point seen through fewer or other
detections, and is dropped (whether or not that better one survives: both are the same point).

Shared detections. Two distinct points that use the same detection cannot both be right,
unless the detection is two markers' blobs merged. Markers occluded in some cameras make this
common: a point seen by three cameras is grown into a fourth with the detection of another
marker that happens to lie near its projection there. Ranking by views alone then hands that
detection to the wrong, four-view point and drops the other marker's own three-view point:
on CMU 85_02 in the Pose2Sim rig, 263 of the 427 marker-frames the old rule missed. So:

- between points of three or more views, taken in rank order, a detection already owned goes
  to the challenger if its *other* views predict it ``_CLOSER_BY`` times closer than the
  owner's do (``BlockDetections.leave_one_out``: how far the detection lies from the point
  triangulated without it); the loser gives up that view. A detection grown onto a
  neighbour's point lies pixels away from what its other views predict; its own marker's
  views predict it within the noise. A merged blob goes to one of its markers, and the
  other keeps its remaining views, so neither is lost to a conflict in the LP;
- a two-view point (a coincidence on an epipolar line as often as a marker) that shares a
  detection with a point still of three or more views after that is dropped;
- two-view points sharing a detection with each other are all kept: nothing here tells them
  apart, the window LP does (candidates sharing a detection conflict there).

Points that gave up a view are triangulated again from the views they keep.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from formulations.cameras.cross_camera.block import BlockDetections
from formulations.cameras.cross_camera.hypotheses import Hypotheses

# A contested detection changes hands when the challenger's other views predict it this many
# times closer than the owner's: 1 would also move views between correct points on a noisy
# calibration (real caliscope corners: 96.0 % keep all their views at 1, 97.4 % at 2).
_CLOSER_BY = 2.0


def merge_hypotheses(block: BlockDetections, hypotheses: Hypotheses, max_px: float) -> Hypotheses:
    """The kept points of ``hypotheses``, ordered by frame (see module doc)."""
    order = np.lexsort((hypotheses.rms, -hypotheses.n_views, hypotheses.frame))
    ranked = hypotheses.take(order[_distinct_points(hypotheses.take(order), block.rig.focal, max_px)])
    views = ranked.views.copy()
    keep = _share_detections(block, ranked, views)
    changed = np.flatnonzero(keep & (views != ranked.views).any(axis=1))
    kept = ranked.replaced(changed, block.hypotheses(views[changed], ranked.frame[changed], ranked.depth[changed]))
    return kept.take(np.flatnonzero(keep))


def _distinct_points(ranked: Hypotheses, focal: np.ndarray, max_px: float) -> np.ndarray:
    """Indices of ranked hypotheses not within tolerance of a better-ranked one of their frame."""
    depth = np.where(ranked.views >= 0, ranked.depth, np.inf)
    tolerance = max_px * (depth / focal).min(axis=1)
    reach = float(tolerance.max(initial=0.0))
    # A fourth coordinate frame * (2 reach + 1) keeps points of different frames out of reach.
    lifted = np.column_stack([ranked.points, ranked.frame * (2.0 * reach + 1.0)])
    pairs = cKDTree(lifted).query_pairs(reach, output_type="ndarray")  # i < j: i ranked before j
    near = np.linalg.norm(ranked.points[pairs[:, 0]] - ranked.points[pairs[:, 1]], axis=1) <= tolerance[pairs[:, 1]]
    suppressed = np.zeros(len(ranked), dtype=bool)
    suppressed[pairs[near, 1]] = True
    return np.flatnonzero(~suppressed)


def _share_detections(block: BlockDetections, ranked: Hypotheses, views: np.ndarray) -> np.ndarray:
    """Resolve contested detections; edits ``views``, returns which points are kept (see module doc).

    ``views`` hold global detection indices, so one owner table serves every frame of the block.
    """
    n_views = ranked.n_views.copy()
    strong = n_views > 2
    users = _users(views, strong, len(block.pixels))
    contested = strong[:, None] & (views >= 0) & (users[views] > 1)
    loo = _contested_leave_one_out(block, ranked, contested)
    owner: dict[int, int] = {}
    for h in np.flatnonzero(contested.any(axis=1)).tolist():  # in rank order
        for c in np.flatnonzero(views[h] >= 0):
            detection = int(views[h, c])
            k = owner.get(detection)
            if k is not None:
                loser, owner[detection] = (k, h) if _CLOSER_BY * loo[h, c] < loo[k, c] and n_views[k] > 2 else (h, k)
                views[loser, c] = -1
                n_views[loser] -= 1
        if n_views[h] >= 2:
            for detection in views[h][views[h] >= 0].tolist():
                owner.setdefault(detection, h)
    # Two-view points yield to the points of three or more views that still use a detection of theirs.
    stronger = _users(views, n_views > 2, len(block.pixels))
    yields = ~strong & ((views >= 0) & (stronger[views] > 0)).any(axis=1)
    kept: np.ndarray = ~yields & (n_views >= 2)
    return kept


def _users(views: np.ndarray, which: np.ndarray, n_detections: int) -> np.ndarray:
    """(D + 1,) how many of the hypotheses ``which`` use each detection (last entry: none)."""
    used = views[which]
    return np.bincount(used[used >= 0], minlength=n_detections)


def _contested_leave_one_out(block: BlockDetections, ranked: Hypotheses, which: np.ndarray) -> np.ndarray:
    """(H, C) leave-one-out distance of the views ``which`` (``BlockDetections.leave_one_out``), inf elsewhere."""
    distance = np.full(which.shape, np.inf)
    h, c = np.nonzero(which)
    if len(h):
        distance[h, c] = block.leave_one_out(ranked.views[h], c, ranked.depth[h])
    return distance
