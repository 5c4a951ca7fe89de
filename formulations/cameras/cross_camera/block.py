"""Triangulation of many cross-camera hypotheses, over a block of frames at once.

A hypothesis is one frame's choice of at most one detection per camera. The matcher
triangulates a few hundred per frame; the DLT (``Rig.triangulate``) would solve one small SVD
per hypothesis, which dominated the matcher's time. Here every detection of the block is
undistorted once (``BlockDetections.of``), its two linear equations are summed once, and each
hypothesis is a closed-form 3x3 solve; a block of frames shares every numpy and OpenCV call.

For camera c with rows r_1, r_2, r_3 of R_c and translation t_c, a detection with undistorted
normalised coordinates (x, y) of the point X gives two linear equations a_k . X = b_k:

    (x r_3 - r_1) . X = t_1 - x t_3,    (y r_3 - r_2) . X = t_2 - y t_3,

whose residuals are z_c (x - x') and z_c (y - y'), with (x', y') the projection of X and z_c
its depth in camera c. Weighting camera c's rows by w_c = f_c / z_c (f_c its focal length in
pixels) makes the residuals pixel-sized, f_c (x - x'); the weighted normal equations

    M X = g,    M = sum_c w_c^2 A_c,    g = sum_c w_c^2 B_c,    A = sum_k a_k a_k^T,  B = sum_k a_k b_k,

are solved with the depths of a first solution (weights f_c^2, as the DLT's) or of a
nearby earlier point. Leaving camera c out is dropping its term. Residuals are measured in
pixels through the cameras' own projection, distortion included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.cross_camera.hypotheses import Hypotheses
from formulations.cameras.rig import Rig


@dataclass(frozen=True)
class BlockDetections:
    """The detections of a block of F frames in C cameras, prepared for triangulation.

    Detections have one global index over the block (camera by camera, frame by frame within
    a camera); a hypothesis's ``views`` (H, C) hold global indices, -1 for none. Index -1 is a
    last row of zeros (NaN pixels), so a camera a hypothesis does not use adds nothing.

    Attributes:
        rig: The C cameras.
        frame: (D,) frame of each detection; ``camera`` (D,) its camera; ``local`` (D,) its
            index among that frame's detections in that camera.
        offsets: (F, C) global index of the first detection of frame f in camera c.
        padded: (F, C, D_max) global indices of frame f's detections in camera c, -1 padding.
        pixels: (D + 1, 2) pixels of every detection, then NaN.
        normalised: (D + 1, 2) undistorted normalised coordinates, then NaN.
        normal: (D + 1, 3, 3) A of every detection, then zeros; ``right`` (D + 1, 3) B, then zeros.
    """

    rig: Rig
    frame: np.ndarray
    camera: np.ndarray
    local: np.ndarray
    offsets: np.ndarray
    padded: np.ndarray
    pixels: np.ndarray
    normalised: np.ndarray
    normal: np.ndarray
    right: np.ndarray

    @classmethod
    def of(cls, cameras: list[Camera], frames: list[list[np.ndarray]]) -> BlockDetections:
        """From ``frames[f][c]``, the (D, 2) pixel detections of frame f in camera c."""
        n_frames, n_cams = len(frames), len(cameras)
        counts = np.array(
            [[len(np.reshape(frames[f][c], (-1, 2))) for c in range(n_cams)] for f in range(n_frames)], dtype=int
        ).reshape(n_frames, n_cams)
        offsets = (np.cumsum(counts.T.ravel()) - counts.T.ravel()).reshape(n_cams, n_frames).T
        pixels, normalised, a_rows, b_rows = [], [], [], []
        for c, cam in enumerate(cameras):
            per_frame = [np.asarray(frames[f][c], dtype=float).reshape(-1, 2) for f in range(n_frames)]
            pix = np.concatenate(per_frame + [np.empty((0, 2))])
            xy = cam.undistort(pix)
            pixels.append(pix)
            normalised.append(xy)
            a_rows.append(xy[:, :, None] * cam.R[2] - cam.R[:2])  # x r_3 - r_1, y r_3 - r_2
            b_rows.append(cam.t[:2] - xy * cam.t[2])
        a = np.concatenate(a_rows + [np.zeros((1, 2, 3))])
        b = np.concatenate(b_rows + [np.zeros((1, 2))])
        total = int(counts.sum())
        frame = np.repeat(np.tile(np.arange(n_frames), n_cams), counts.T.ravel())
        camera = np.repeat(np.arange(n_cams), counts.sum(axis=0))
        local = np.arange(total) - offsets[frame, camera]
        padded = np.full((n_frames, n_cams, int(counts.max(initial=0))), -1)
        padded[frame, camera, local] = np.arange(total)
        return cls(
            Rig.of(cameras), frame, camera, local, offsets, padded,
            np.concatenate(pixels + [np.full((1, 2), np.nan)]), np.concatenate(normalised + [np.full((1, 2), np.nan)]),
            np.einsum("dki,dkj->dij", a, a), np.einsum("dki,dk->di", a, b),
        )

    @property
    def n_frames(self) -> int:
        return len(self.offsets)

    def triangulate(self, views: np.ndarray, depth: np.ndarray | None = None) -> np.ndarray:
        """(H, 3) points of hypotheses ``views`` (H, C) with two or more views (see module doc).

        ``depth`` (H, C): depths to weight by, from a nearby earlier estimate; None: two passes.
        """
        normal, right = self.normal[views], self.right[views]  # (H, C, 3, 3), (H, C, 3)
        focal2 = self.rig.focal**2
        if depth is None:
            depth = self.rig.depth(_solve(normal, right, np.broadcast_to(focal2, views.shape)))
        return _solve(normal, right, focal2 / np.maximum(np.abs(depth), 1e-9) ** 2)

    def hypotheses(self, views: np.ndarray, frame: np.ndarray, depth: np.ndarray | None = None) -> Hypotheses:
        """Triangulate (``triangulate``) and measure hypotheses ``views`` (H, C) of frames ``frame`` (H,)."""
        points = self.triangulate(views, depth)
        projected = self.rig.project(points)
        residual = np.linalg.norm(projected - self.pixels[views], axis=2)
        return Hypotheses(views, frame, points, projected, residual, self.rig.depth(points))

    def leave_one_out(self, views: np.ndarray, camera: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """(H,) pixel distance of view ``camera[h]`` of hypothesis h to the point from its other views.

        How well the other views predict that detection; inf where fewer than two remain.
        ``depth`` (H, C) are the depths of the points from all their views.
        """
        others = views.copy()
        others[np.arange(len(views)), camera] = -1
        enough = np.flatnonzero((others >= 0).sum(axis=1) >= 2)
        points = self.triangulate(others[enough], depth[enough])
        distance = np.full(len(views), np.inf)
        for c in np.unique(camera[enough]):
            mine = camera[enough] == c
            pixel = self.pixels[views[enough[mine], c]]
            distance[enough[mine]] = np.linalg.norm(self.rig.cameras[c].project(points[mine]) - pixel, axis=1)
        return distance


def _solve(normal: np.ndarray, right: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Solve sum_c w_hc A_hc X_h = sum_c w_hc B_hc for every h; NaN where the rays are (near) parallel.

    Closed form by cofactors (M is symmetric): numpy's batched solve pays a LAPACK call per
    3x3 system.
    """
    m = np.einsum("hc,hcij->hij", weight, normal).reshape(-1, 9)
    g = np.einsum("hc,hci->hi", weight, right)
    a, b, c, e, f, i = m[:, 0], m[:, 1], m[:, 2], m[:, 4], m[:, 5], m[:, 8]  # [[a b c] [b e f] [c f i]]
    cofactor = np.stack([e * i - f * f, c * f - b * i, b * f - c * e, a * i - c * c, b * c - a * f, a * e - b * b], axis=1)
    det = a * cofactor[:, 0] + b * cofactor[:, 1] + c * cofactor[:, 2]
    inverse = cofactor[:, [0, 1, 2, 1, 3, 4, 2, 4, 5]].reshape(-1, 3, 3)
    scale = (a + e + i) / 3.0
    solvable = np.abs(det) > 1e-12 * np.maximum(scale, 1e-300) ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        points: np.ndarray = (inverse @ g[..., None])[..., 0] / det[:, None]
    points[~solvable] = np.nan
    return points
