"""3D candidate points per frame by matching 2D detections across calibrated cameras.

Frames are matched independently, but a block of them at a time (``match_frames``): every
step below is one numpy or OpenCV call over the whole block, which is most of the saving
(about 1.5 ms per frame in blocks of 20 against 4 ms one frame at a time, 41 markers x 4
cameras; ``bench/cameras_realtime.py``).

Epipolar gating. With x = (x, y, 1) the undistorted normalised coordinates of a detection
(``Camera.undistort``, so lens distortion is removed first), the relative pose of camera b
with respect to camera a is R_ab = R_b R_a^T, t_ab = t_b - R_ab t_a, and a true
correspondence satisfies the epipolar constraint

    x_b^T E x_a = 0,   E = [t_ab]_x R_ab.

l_b = E x_a is the epipolar line of x_a in b's normalised plane; the distance of x_b to it is
|x_b . l_b| / sqrt(l_b0^2 + l_b1^2), which times the focal length f_b (pixels per normalised
unit) is a distance in pixels. The gate uses the larger of that and the symmetric distance of
x_a to l_a = E^T x_b (times f_a), computed as a (D_a, D_b) matrix per camera pair.

Each gated pair is triangulated (``BlockDetections.triangulate``), kept if in front of both
cameras and its reprojection RMS is <= ``max_reprojection_px``, then grown (twice): it is
projected into every camera it does not use, the nearest detection within
``_GROW_FACTOR * max_reprojection_px`` is added, and the point is re-triangulated; the growth
is undone if the RMS then exceeds ``max_reprojection_px``. The search radius is wider than the
acceptance limit because a point from fewer views projects further from a noisy detection than
the re-triangulated one does (on the real caliscope corners, before merging gave views
back, a 1x radius recovered 89 % of corners with all their views, 2x 98.6 %). The second
growth only revisits the hypotheses the first one grew: the others' points did not move.
Growth may also pick up another marker's detection that lies near the projection;
``merge_hypotheses`` gives such a detection back.

Merging (``merge_hypotheses``): one hypothesis per 3D point, and a detection contested by
two distinct points goes to the one whose other views predict it best.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from formulations.cameras.camera import Camera
from formulations.cameras.cross_camera.block import BlockDetections
from formulations.cameras.cross_camera.hypotheses import Hypotheses
from formulations.cameras.cross_camera.merge import merge_hypotheses

_GROW_FACTOR = 2.0  # growth search radius / max_reprojection_px


@dataclass(frozen=True)
class CrossCameraPoints:
    """Candidate 3D points of one frame.

    Attributes:
        points: (P, 3) world positions (the calibration's unit).
        views: (P, C) int, index of the detection used in camera c, -1 if none.
        reprojection_rms: (P,) pixels, over the views used.
    """

    points: np.ndarray
    views: np.ndarray
    reprojection_rms: np.ndarray

    def resources(self, detection_offsets: np.ndarray, n_detections: int) -> sp.csr_matrix:
        """(P, n_detections) 0/1 matrix of the (camera, detection) pairs each point uses.

        ``detection_offsets[c]`` is the global index of camera c's first detection in the frame.
        """
        offsets = np.asarray(detection_offsets, dtype=int)
        rows, cams = np.nonzero(self.views >= 0)
        cols = offsets[cams] + self.views[rows, cams]
        return sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(self.views), n_detections))


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def epipolar_distances(cam_a: Camera, cam_b: Camera, norm_a: np.ndarray, norm_b: np.ndarray) -> np.ndarray:
    """(..., D_a, D_b) symmetric epipolar distance in pixels between normalised detections (..., D_a, 2), (..., D_b, 2)."""
    r_ab = cam_b.R @ cam_a.R.T
    essential = _skew(cam_b.t - r_ab @ cam_a.t) @ r_ab
    xa = np.concatenate([norm_a, np.ones(norm_a.shape[:-1] + (1,))], axis=-1)
    xb = np.concatenate([norm_b, np.ones(norm_b.shape[:-1] + (1,))], axis=-1)
    lines_b = xa @ essential.T  # (..., D_a, 3): E x_a
    lines_a = xb @ essential  # (..., D_b, 3): E^T x_b
    algebraic = np.abs(lines_b @ np.swapaxes(xb, -1, -2))  # |x_b^T E x_a|, (..., D_a, D_b)
    dist_b = algebraic / np.linalg.norm(lines_b[..., :2], axis=-1)[..., :, None] * cam_b.focal
    dist_a = algebraic / np.linalg.norm(lines_a[..., :2], axis=-1)[..., None, :] * cam_a.focal
    distance: np.ndarray = np.maximum(dist_a, dist_b)
    return distance


def match_frames(cameras: list[Camera], frames: list[list[np.ndarray]], epipolar_px: float = 3.0,
                 max_reprojection_px: float = 2.0) -> list[CrossCameraPoints]:
    """Candidate 3D points of every frame of ``frames`` (``frames[f][c]``: (D, 2) pixels; module doc).

    Frames are independent; matching a block of them at once shares every numpy and OpenCV
    call between them, which is most of the cost of one frame.
    """
    block = BlockDetections.of(cameras, frames)
    views, frame = _epipolar_pairs(block, epipolar_px)
    hypotheses = block.hypotheses(views, frame)
    in_front = ((hypotheses.depth > 0) | (hypotheses.views < 0)).all(axis=1)
    hypotheses = hypotheses.take(np.flatnonzero(in_front & (hypotheses.rms <= max_reprojection_px)))
    grown = np.arange(len(hypotheses))
    for _ in range(2):  # grow, re-triangulate, grow again those whose point moved
        hypotheses, grown = _grow(block, hypotheses, grown, _GROW_FACTOR * max_reprojection_px, max_reprojection_px)
    kept = merge_hypotheses(block, hypotheses.take(_distinct_views(hypotheses.views)), max_reprojection_px)
    local = np.where(kept.views >= 0, block.local[kept.views], -1)
    bounds = np.searchsorted(kept.frame, np.arange(block.n_frames + 1))
    return [CrossCameraPoints(kept.points[s:e], local[s:e], kept.rms[s:e]) for s, e in zip(bounds[:-1], bounds[1:])]


def _distinct_views(views: np.ndarray) -> np.ndarray:
    """Index of one hypothesis per distinct row of ``views`` (pairs grown into the same point)."""
    order = np.lexsort(views.T)
    first = np.ones(len(order), dtype=bool)
    first[1:] = (np.diff(views[order], axis=0) != 0).any(axis=1)
    return order[first]


def _epipolar_pairs(block: BlockDetections, epipolar_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Views (H, C) and frames (H,) of every same-frame detection pair of two cameras within
    ``epipolar_px`` of each other's epipolar line."""
    n_cams = len(block.rig)
    views, frames = [np.empty((0, n_cams), dtype=int)], [np.empty(0, dtype=int)]
    for a in range(n_cams):
        for b in range(a + 1, n_cams):
            index_a, index_b = block.padded[:, a], block.padded[:, b]  # (F, D_max)
            distance = epipolar_distances(
                block.rig.cameras[a], block.rig.cameras[b], block.normalised[index_a], block.normalised[index_b]
            )
            f, i, j = np.nonzero(distance <= epipolar_px)  # padding is NaN: never within
            pair = np.full((len(f), n_cams), -1)
            pair[:, a], pair[:, b] = index_a[f, i], index_b[f, j]
            views.append(pair)
            frames.append(f)
    return np.concatenate(views), np.concatenate(frames)


def _grow(block: BlockDetections, hypotheses: Hypotheses, todo: np.ndarray, radius_px: float,
          max_px: float) -> tuple[Hypotheses, np.ndarray]:
    """Add to each hypothesis ``todo`` the nearest detection within ``radius_px`` in each camera it lacks.

    The grown point is kept where its RMS stays within ``max_px``. Returns the hypotheses and
    which of them were grown.
    """
    grown = hypotheses.views.copy()
    lift = 2.0 * radius_px + 1.0  # a third coordinate frame * lift puts other frames out of reach
    for c in range(len(block.rig)):
        mine = np.flatnonzero(block.camera == c)
        lacking = todo[(grown[todo, c] < 0) & (hypotheses.depth[todo, c] > 0)]
        if len(mine) == 0 or len(lacking) == 0:
            continue
        tree = cKDTree(np.column_stack([block.pixels[mine], block.frame[mine] * lift]))
        query = np.column_stack([hypotheses.projected[lacking, c], hypotheses.frame[lacking] * lift])
        distance, nearest = tree.query(query, distance_upper_bound=radius_px)
        close = np.isfinite(distance)
        grown[lacking[close], c] = mine[nearest[close]]
    changed = np.flatnonzero((grown != hypotheses.views).any(axis=1))
    candidates = block.hypotheses(grown[changed], hypotheses.frame[changed], hypotheses.depth[changed])
    accepted = changed[candidates.rms <= max_px]
    return hypotheses.replaced(accepted, candidates.take(np.flatnonzero(candidates.rms <= max_px))), accepted
