"""A 3D point from its 2D detections: DLT over 2+ views, ray compromise for one, prediction for none.

This is the triangulate step of Ringer & Lasenby (2004, Sec. 2, step 3): a marker seen by
two or more cameras is triangulated; seen by one, it is a compromise between the ray
through the detection and its predicted position; seen by none, it is the prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.cameras.camera import Camera


@dataclass(frozen=True)
class Triangulated:
    """One reconstructed point.

    Attributes:
        point: (3,) world position (the calibration's unit).
        reprojection_error: (C,) pixel distance between detection and projected point per
            camera; NaN where the camera did not see the point.
        n_views: cameras that saw the point.
        filled: True when nothing saw it and ``point`` is the prediction.
    """

    point: np.ndarray
    reprojection_error: np.ndarray
    n_views: int
    filled: bool = False


def reprojection_errors(cameras: list[Camera], points: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """(P, C) pixel distances ||project_c(X_p) - u_pc||; NaN where u_pc or X_p is NaN."""
    projected = np.stack([cam.project(points) for cam in cameras], axis=1)  # (P, C, 2)
    return np.linalg.norm(projected - pixels, axis=2)


def triangulate_many(cameras: list[Camera], pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Linear (DLT) triangulation of P points at once, each from every camera that saw it.

    For camera c with [R_c | t_c] = rows P1, P2, P3 and undistorted normalised detection
    (x, y), the point X_h = (X, 1) satisfies x (P3 . X_h) - P1 . X_h = 0 and
    y (P3 . X_h) - P2 . X_h = 0. Stacking these rows over the cameras that saw the point gives
    A X_h = 0, solved in the least-squares sense by the right singular vector of A with the
    smallest singular value (batched SVD over the (P, 2C, 4) stack; rows of unseen cameras
    are zero and drop out). Two choices keep the algebraic error close to the pixel error:
    each camera's rows are multiplied by its focal length (a row's residual is then
    depth x pixel error rather than depth x pixel error / f), and the world is
    preconditioned (Hartley) by X = s X' + m with m, s the centroid and mean spread of the
    camera centres, so the solve does not depend on the unit (m or mm).

    Args:
        cameras: the C cameras.
        pixels: (P, C, 2) detections in pixels, NaN where camera c did not see point p.

    Returns:
        points (P, 3), NaN for points seen by fewer than 2 cameras; reprojection_rms (P,)
        in pixels over the cameras that saw the point; n_views (P,).
    """
    pixels = np.asarray(pixels, dtype=float).reshape(-1, len(cameras), 2)
    seen = np.isfinite(pixels).all(axis=2)  # (P, C)
    n_views = seen.sum(axis=1)
    normalised = np.zeros_like(pixels)
    for c, cam in enumerate(cameras):
        normalised[seen[:, c], c] = cam.undistort(pixels[seen[:, c], c])

    extrinsic = np.stack([np.column_stack([cam.R, cam.t]) for cam in cameras])  # (C, 3, 4)
    focal = np.array([0.5 * (cam.K[0, 0] + cam.K[1, 1]) for cam in cameras])
    rows = normalised[..., None] * extrinsic[None, :, 2:3, :] - extrinsic[None, :, :2, :]  # (P, C, 2, 4)
    rows *= (focal * seen)[..., None, None]

    centres = np.stack([cam.centre for cam in cameras])
    mean = centres.mean(axis=0)
    spread = np.linalg.norm(centres - mean, axis=1).mean() or 1.0
    precondition = np.eye(4)
    precondition[:3, :3] *= spread
    precondition[:3, 3] = mean

    points = np.full((len(pixels), 3), np.nan)
    solvable = n_views >= 2
    if solvable.any():
        a = rows[solvable].reshape(int(solvable.sum()), -1, 4) @ precondition
        homogeneous = np.linalg.svd(a, full_matrices=False)[2][:, -1, :] @ precondition.T
        points[solvable] = homogeneous[:, :3] / homogeneous[:, 3:]
    squared = np.where(seen, reprojection_errors(cameras, points, pixels), 0.0) ** 2
    rms = np.sqrt(squared.sum(axis=1) / np.maximum(n_views, 1))
    return points, np.where(solvable, rms, np.nan), n_views


def _stack(pixels: list[np.ndarray | None]) -> np.ndarray:
    """(C, 2) array of per-camera detections, NaN for ``None``."""
    return np.array([np.full(2, np.nan) if p is None else np.asarray(p, dtype=float).reshape(2) for p in pixels])


def triangulate(cameras: list[Camera], pixels: list[np.ndarray | None]) -> Triangulated:
    """One point from the cameras that saw it (``None`` for the others); see ``triangulate_many``.

    Raises:
        ValueError: fewer than two cameras saw the point.
    """
    stacked = _stack(pixels)
    points, _, n_views = triangulate_many(cameras, stacked[None])
    if n_views[0] < 2:
        raise ValueError(f"triangulate: needs 2+ views, got {n_views[0]}")
    return Triangulated(points[0], reprojection_errors(cameras, points, stacked[None])[0], int(n_views[0]))


def ray_compromise(camera: Camera, pixel: np.ndarray, prediction: np.ndarray, weight: float = np.inf) -> np.ndarray:
    """Compromise between the ray through a single detection and the prediction (Ringer 2004).

    Minimises  w dist(X, ray)^2 + ||X - p||^2  for the ray o + s d (s >= 0, ||d|| = 1) and
    prediction p. With q = o + max(0, d . (p - o)) d, the point of the ray closest to p, the
    closed form is

        X = q + (p - q) / (1 + w).

    Why: the objective is convex with gradient 2 w (X - foot(X)) + 2 (X - p), foot(X) being
    the nearest ray point. On the segment p -> q, foot(X) = q (p - q is normal to d, or
    q = o when p is behind the camera), and the X above, which lies on that segment,
    zeroes w (X - q) + (X - p). X slides from the prediction (w = 0) to the ray (w = inf, the default).
    Read w as a precision ratio sigma_prediction^2 / sigma_ray^2, where
    sigma_ray ~ depth x pixel noise / focal length.

    Args:
        camera: the one camera that saw the point.
        pixel: (2,) or (N, 2) detections.
        prediction: (3,) or (N, 3) predicted world positions.
        weight: w >= 0.

    Returns:
        (3,) or (N, 3) world points, the shape of ``prediction``.
    """
    if not weight >= 0:
        raise ValueError(f"ray_compromise: weight must be >= 0, got {weight}")
    p = np.asarray(prediction, dtype=float)
    origins, directions = camera.ray(np.asarray(pixel, dtype=float).reshape(-1, 2))
    flat = p.reshape(-1, 3)
    along = np.maximum(np.einsum("nd,nd->n", flat - origins, directions), 0.0)
    foot = origins + along[:, None] * directions
    pull = 0.0 if np.isinf(weight) else 1.0 / (1.0 + weight)
    return (foot + pull * (flat - foot)).reshape(p.shape)


def locate(
    cameras: list[Camera], pixels: list[np.ndarray | None], prediction: np.ndarray, weight: float = np.inf
) -> Triangulated:
    """Ringer & Lasenby's rule: DLT for 2+ views, ``ray_compromise`` for 1, prediction (filled) for 0."""
    views = [c for c, p in enumerate(pixels) if p is not None]
    if len(views) >= 2:
        return triangulate(cameras, pixels)
    stacked = _stack(pixels)
    if not views:
        return Triangulated(np.asarray(prediction, dtype=float).copy(), np.full(len(cameras), np.nan), 0, filled=True)
    point = ray_compromise(cameras[views[0]], stacked[views[0]], prediction, weight)
    return Triangulated(point, reprojection_errors(cameras, point[None], stacked[None])[0], 1)
