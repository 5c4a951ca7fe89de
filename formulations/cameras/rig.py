"""The cameras of a rig, stacked once for the per-frame geometry of ``per-camera`` association.

``per-camera`` locates every marker in every frame, twice (guide and final pass), from
detections that are undistorted once per frame. ``triangulation.triangulate_many`` takes
pixels and undistorts them again on every call (an iterative solve per point), and
``Camera.project`` rebuilds its Rodrigues vector per call; at 41 markers x 4 cameras x
2 passes per frame those repeats cost more than the geometry. ``Rig`` keeps what does not
change (extrinsics, focal lengths, the Hartley preconditioning, Rodrigues vectors) and
triangulates from normalised coordinates, with the same DLT as ``triangulate_many``:

    rows of camera c:  f_c (x P3_c - P1_c),  f_c (y P3_c - P2_c),  P_c = [R_c | t_c],

X_h the right singular vector of the stacked rows (world preconditioned by the centroid
and mean spread of the camera centres) with the smallest singular value.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from formulations.cameras.camera import Camera


@dataclass(frozen=True, eq=False)
class Rig:
    """C calibrated cameras and the stacked quantities the per-frame geometry uses.

    Attributes:
        cameras: The C cameras.
        extrinsic: ``(C, 3, 4)`` [R_c | t_c].
        focal: ``(C,)`` mean focal length in pixels, the DLT row weight.
        precondition: ``(4, 4)`` X_h = H X_h' (Hartley: centroid and spread of the centres).
        rvec: ``(C, 3)`` Rodrigues vectors for ``cv2.projectPoints``.
    """

    cameras: list[Camera]
    extrinsic: np.ndarray
    focal: np.ndarray
    precondition: np.ndarray
    rvec: np.ndarray

    @classmethod
    def of(cls, cameras: list[Camera]) -> Rig:
        """Stack a list of cameras."""
        centres = np.stack([camera.centre for camera in cameras])
        mean = centres.mean(axis=0)
        precondition = np.eye(4)
        precondition[:3, :3] *= np.linalg.norm(centres - mean, axis=1).mean() or 1.0
        precondition[:3, 3] = mean
        return cls(
            cameras=list(cameras),
            extrinsic=np.stack([np.column_stack([camera.R, camera.t]) for camera in cameras]),
            focal=np.array([0.5 * (camera.K[0, 0] + camera.K[1, 1]) for camera in cameras]),
            precondition=precondition, rvec=np.stack([camera.rvec for camera in cameras]),
        )

    def __len__(self) -> int:
        return len(self.cameras)

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """``(P, C, 2)`` pixels -> normalised coordinates, NaN kept where a view is missing."""
        normalised = np.full(pixels.shape, np.nan)
        for c, camera in enumerate(self.cameras):
            seen = np.isfinite(pixels[:, c]).all(axis=1)
            normalised[seen, c] = camera.undistort(pixels[seen, c])
        return normalised

    def triangulate(self, normalised: np.ndarray) -> np.ndarray:
        """``(P, 3)`` DLT points from ``(P, C, 2)`` normalised views (NaN: none; 2+ per point)."""
        seen = np.isfinite(normalised).all(axis=2)
        rows = np.nan_to_num(normalised)[..., None] * self.extrinsic[None, :, 2:3, :] - self.extrinsic[None, :, :2, :]
        rows *= (self.focal * seen)[..., None, None]
        if len(rows) == 0:
            return np.zeros((0, 3))
        homogeneous = np.linalg.svd(rows.reshape(len(rows), -1, 4) @ self.precondition, full_matrices=False)[2][:, -1]
        homogeneous = homogeneous @ self.precondition.T
        return homogeneous[:, :3] / homogeneous[:, 3:]

    def project(self, points: np.ndarray) -> np.ndarray:
        """``(P, C, 2)`` pixels of ``(P, 3)`` world points, distortion included."""
        projected = np.empty((len(points), len(self.cameras), 2))
        if len(points) == 0:
            return projected
        for c, camera in enumerate(self.cameras):
            image, _ = cv2.projectPoints(points, self.rvec[c], camera.t, camera.K, camera.distortion)
            projected[:, c] = image.reshape(-1, 2)
        return projected

    def errors(self, points: np.ndarray, pixels: np.ndarray) -> np.ndarray:
        """``(P, C)`` reprojection errors ||project_c(X_p) - u_pc||, NaN where no view."""
        return np.linalg.norm(self.project(points) - pixels, axis=2)

    def depth(self, points: np.ndarray) -> np.ndarray:
        """``(P, C)`` depth z_c of each point in each camera."""
        return points @ self.extrinsic[:, 2, :3].T + self.extrinsic[:, 2, 3]

    def on_ray(self, camera: int, normalised: np.ndarray, prediction: np.ndarray) -> np.ndarray:
        """``(K, 3)`` points of camera c's rays through ``(K, 2)`` normalised views nearest ``prediction``.

        ``triangulation.ray_compromise`` with w = inf: q = o + max(0, d . (p - o)) d for the
        centre o and the unit direction d = R^T (x, y, 1) / ||(x, y, 1)||.
        """
        rotation, centre = self.extrinsic[camera, :, :3], self.cameras[camera].centre
        direction = np.column_stack([normalised, np.ones(len(normalised))]) @ rotation
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        along = np.maximum(np.einsum("kd,kd->k", prediction - centre, direction), 0.0)
        return centre + along[:, None] * direction

    def image_plane(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normalised coordinates ``(C, ..., 2)`` of ``(..., 3)`` world points and their depth ``(C, ...)``.

        (x, y) = (X_c / Z_c, Y_c / Z_c) with X_c = R_c X + t_c; NaN behind the camera
        (Z_c <= 0), where a point has no image.
        """
        shift = self.extrinsic[:, :, 3].reshape((len(self),) + (1,) * (points.ndim - 1) + (3,))
        local = np.einsum("cij,...j->c...i", self.extrinsic[:, :, :3], points) + shift
        depth = local[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            normalised = np.where(depth[..., None] > 0, local[..., :2] / depth[..., None], np.nan)
        return normalised, depth
