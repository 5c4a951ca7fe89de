"""The cameras of a rig, stacked once: the one place for the rig's projection and triangulation.

The simulator, ``per-camera`` association and the cross-camera matcher all work on whole
rigs. ``Rig`` keeps what does not change (extrinsics, centres, focal lengths, the Hartley
preconditioning, Rodrigues vectors) and works on normalised coordinates, undistorted once
per detection (an iterative solve per point): ``per-camera`` locates 41 markers x 4
cameras x 2 passes per frame, where repeating those costs more than the geometry.

Triangulation is the DLT. For camera c with P_c = [R_c | t_c] (rows P1, P2, P3) and
undistorted normalised detection (x, y), the point X_h = (X, 1) satisfies

    f_c (x P3_c - P1_c) . X_h = 0,    f_c (y P3_c - P2_c) . X_h = 0.

Stacking these rows over the cameras that saw the point gives A X_h = 0, solved in the
least-squares sense by the right singular vector of A with the smallest singular value
(batched SVD over the (P, 2C, 4) stack; rows of unseen cameras are zero and drop out). Two
choices keep the algebraic error close to the pixel error: each camera's rows carry its
focal length f_c (a row's residual is then depth x pixel error rather than depth x pixel
error / f_c), and the world is preconditioned (Hartley) by X = s X' + m with m, s the
centroid and mean spread of the camera centres, so the solve does not depend on the unit
(m or mm).
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
        centres: ``(C, 3)`` camera centres C_c = -R_c^T t_c.
        focal: ``(C,)`` mean focal length in pixels (``Camera.focal``), the DLT row weight.
        precondition: ``(4, 4)`` X_h = H X_h' (Hartley: centroid and spread of the centres).
        rvec: ``(C, 3)`` Rodrigues vectors for ``cv2.projectPoints``.
    """

    cameras: list[Camera]
    extrinsic: np.ndarray
    centres: np.ndarray
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
            centres=centres, focal=np.array([camera.focal for camera in cameras]),
            precondition=precondition, rvec=np.stack([camera.rvec for camera in cameras]),
        )

    def __len__(self) -> int:
        return len(self.cameras)

    @property
    def rotation(self) -> np.ndarray:
        """``(C, 3, 3)`` world -> camera rotations R_c; row i is camera axis i in the world."""
        return self.extrinsic[:, :, :3]

    @property
    def image_size(self) -> np.ndarray:
        """``(C, 2)`` image width and height in pixels."""
        return np.array([camera.image_size for camera in self.cameras], dtype=float)

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """``(P, C, 2)`` pixels -> normalised coordinates, NaN kept where a view is missing."""
        normalised = np.full(pixels.shape, np.nan)
        for c, camera in enumerate(self.cameras):
            seen = np.isfinite(pixels[:, c]).all(axis=1)
            normalised[seen, c] = camera.undistort(pixels[seen, c])
        return normalised

    def triangulate(self, normalised: np.ndarray) -> np.ndarray:
        """``(P, 3)`` DLT points (module doc) from ``(P, C, 2)`` normalised views, NaN where unseen.

        NaN for the points seen by fewer than two cameras.
        """
        seen = np.isfinite(normalised).all(axis=2)
        solvable = seen.sum(axis=1) >= 2
        rows = np.nan_to_num(normalised[solvable])[..., None] * self.extrinsic[None, :, 2:3, :] - self.extrinsic[None, :, :2, :]
        rows *= (self.focal * seen[solvable])[..., None, None]
        points = np.full((len(normalised), 3), np.nan)
        if len(rows):
            homogeneous = np.linalg.svd(rows.reshape(len(rows), -1, 4) @ self.precondition, full_matrices=False)[2][:, -1]
            homogeneous = homogeneous @ self.precondition.T
            points[solvable] = homogeneous[:, :3] / homogeneous[:, 3:]
        return points

    def project(self, points: np.ndarray) -> np.ndarray:
        """``(P, C, 2)`` pixels of ``(P, 3)`` world points, distortion included (``Camera.project``).

        Points behind a camera still get a pixel there; ``depth`` tells them apart.
        """
        projected = np.empty((len(points), len(self.cameras), 2))
        if len(points) == 0:
            return projected
        for c, camera in enumerate(self.cameras):
            image, _ = cv2.projectPoints(points, self.rvec[c], camera.t, camera.K, camera.distortion)
            projected[:, c] = image.reshape(-1, 2)
        return projected

    def errors(self, points: np.ndarray, pixels: np.ndarray) -> np.ndarray:
        """``(P, C)`` reprojection errors ||project_c(X_p) - u_pc||, NaN where no view."""
        errors: np.ndarray = np.linalg.norm(self.project(points) - pixels, axis=2)
        return errors

    def depth(self, points: np.ndarray) -> np.ndarray:
        """``(P, C)`` depth z_c = P3_c . X_h of each point in each camera."""
        depth: np.ndarray = points @ self.extrinsic[:, 2, :3].T + self.extrinsic[:, 2, 3]
        return depth

    def on_ray(self, camera: int, normalised: np.ndarray, prediction: np.ndarray) -> np.ndarray:
        """``(K, 3)`` points of camera c's rays through ``(K, 2)`` normalised views nearest ``prediction``.

        For the centre o and the unit direction d (``Camera.direction``), the point of the
        ray o + s d (s >= 0) nearest p is q = o + max(0, d . (p - o)) d: the foot of the
        perpendicular from p, or the centre when p lies behind the camera. One view fixes
        two coordinates; the prediction supplies only the depth along the ray (Ringer &
        Lasenby 2004, Sec. 2, step 3, trusting the ray fully).
        """
        centre, direction = self.centres[camera], self.cameras[camera].direction(normalised)
        along = np.maximum(np.einsum("kd,kd->k", prediction - centre, direction), 0.0)
        on_ray: np.ndarray = centre + along[:, None] * direction
        return on_ray

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
