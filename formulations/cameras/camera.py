"""A calibrated pinhole camera with lens distortion, in OpenCV's conventions.

A world point X (3,) maps to camera coordinates x_c = R X + t, to normalised image
coordinates (x, y) = (x_c[0] / x_c[2], x_c[1] / x_c[2]), through the distortion model
(k1, k2, p1, p2[, k3, ...]) and then to pixels u = K (x_d, y_d, 1)^T. Pixel centres sit at
integer coordinates, so the image spans [-0.5, width - 0.5] x [-0.5, height - 0.5].

Units: the world unit is whatever the calibration used for t (caliscope and Pose2Sim use
metres); markerflow's 3D work is in millimetres, so convert once with
``camera.scaled(1000.0)``. Only t carries a length: K is in pixels, R and the distortion
are dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NoReturn

import cv2
import numpy as np
import numpy.typing as npt

# cv2.undistortPoints stops after 5 fixed-point iterations by default: about 1 px off at the
# image edge with webcam-strength distortion (k1 = -0.34). Iterate to convergence instead.
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)
_DISTORTION_LENGTHS = (4, 5, 8, 12, 14)  # what OpenCV accepts
ROTATION_ROUNDING = 1e-4  # |R R^T - I| of a rotation printed to 5 decimals is ~1e-5; a wrong matrix is ~0.01 or more


@dataclass(frozen=True, eq=False)
class Camera:
    """One calibrated camera; arrays are stored as read-only float64.

    Attributes:
        K: (3, 3) intrinsic matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]], fx, fy > 0.
        distortion: OpenCV coefficients (k1, k2, p1, p2[, k3[, ...]]), 4, 5, 8, 12 or 14 long.
        R: (3, 3) rotation world -> camera (orthonormal, det +1).
        t: (3,) translation world -> camera; the camera centre is C = -R^T t.
        image_size: (width, height) in pixels.
        name: label used in messages and files.
    """

    K: npt.NDArray[np.float64]
    distortion: npt.NDArray[np.float64]
    R: npt.NDArray[np.float64]
    t: npt.NDArray[np.float64]
    image_size: tuple[int, int]
    name: str = "camera"

    def __post_init__(self) -> None:
        shapes = {"K": (3, 3), "distortion": None, "R": (3, 3), "t": (3,)}
        for field, shape in shapes.items():
            try:
                value = np.array(getattr(self, field), dtype=float).reshape(-1 if shape is None else shape)
            except (TypeError, ValueError):
                self._fail(f"{field} must be numeric of shape {shape or '(4|5|8|12|14,)'}")
            if not np.isfinite(value).all():
                self._fail(f"{field} has non-finite values")
            value.flags.writeable = False
            object.__setattr__(self, field, value)
        if self.distortion.size not in _DISTORTION_LENGTHS:
            self._fail(f"distortion has {self.distortion.size} coefficients, expected one of {_DISTORTION_LENGTHS}")
        K = self.K
        if not (K[0, 0] > 0 and K[1, 1] > 0) or K[1, 0] or K[2, 0] or K[2, 1] or K[2, 2] != 1:
            self._fail(f"K is singular or not a pinhole matrix (fx={K[0, 0]:g}, fy={K[1, 1]:g}, last row {K[2].tolist()})")
        orthonormality = np.abs(self.R @ self.R.T - np.eye(3)).max()
        if orthonormality > ROTATION_ROUNDING or abs(np.linalg.det(self.R) - 1.0) > ROTATION_ROUNDING:
            self._fail(f"R is not a rotation (|R R^T - I| = {orthonormality:.2g}, det = {np.linalg.det(self.R):.6g}); "
                       "give it to 6 decimals, or as rvec")
        if orthonormality > 1e-12:  # a printed R, off by its rounding: the nearest rotation (a rotation stays bit-equal)
            u, _, vt = np.linalg.svd(self.R)
            rotation = u @ vt
            rotation.flags.writeable = False
            object.__setattr__(self, "R", rotation)
        try:
            size = np.array(self.image_size, dtype=float).reshape(2)
        except (TypeError, ValueError):
            size = np.full(2, np.nan)
        if not (size > 0).all() or (size != np.round(size)).any():
            self._fail(f"image_size must be two positive integers (width, height), got {self.image_size!r}")
        object.__setattr__(self, "image_size", (int(size[0]), int(size[1])))

    def _fail(self, problem: str) -> NoReturn:
        raise ValueError(f"camera {self.name!r}: {problem}")

    @classmethod
    def from_rvec(
        cls, K: npt.ArrayLike, distortion: npt.ArrayLike, rvec: npt.ArrayLike, t: npt.ArrayLike,
        image_size: tuple[int, int], name: str = "camera",
    ) -> Camera:
        """Build from a Rodrigues vector (axis * angle, world -> camera) instead of R."""
        try:
            vector = np.array(rvec, dtype=float).reshape(3)
        except (TypeError, ValueError):
            raise ValueError(f"camera {name!r}: rvec must be 3 numbers, got {rvec!r}") from None
        if not np.isfinite(vector).all():
            raise ValueError(f"camera {name!r}: rvec has non-finite values")
        rotation = np.asarray(cv2.Rodrigues(vector)[0], dtype=float)
        # __post_init__ converts and validates any array-like, with the camera's name in its messages.
        return cls(K, distortion, rotation, t, image_size, name)  # type: ignore[arg-type]

    def __eq__(self, other: object) -> bool:
        """Equal by value; defining ``__eq__`` leaves ``__hash__`` None (arrays are not hashable)."""
        if not isinstance(other, Camera):
            return NotImplemented
        return self.name == other.name and self.image_size == other.image_size and all(
            np.array_equal(getattr(self, f), getattr(other, f)) for f in ("K", "distortion", "R", "t")
        )

    @property
    def rvec(self) -> np.ndarray:
        """(3,) Rodrigues vector of R."""
        return np.asarray(cv2.Rodrigues(self.R)[0], dtype=float).reshape(3)

    @property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in world coordinates, C = -R^T t."""
        return -self.R.T @ self.t

    @property
    def focal(self) -> float:
        """Mean focal length f = (fx + fy) / 2 in pixels: pixels per normalised unit."""
        return 0.5 * float(self.K[0, 0] + self.K[1, 1])

    def scaled(self, factor: float) -> Camera:
        """The same camera in a world unit ``factor`` times smaller (m -> mm: 1000)."""
        return replace(self, t=self.t * factor)

    def project(self, points_world: np.ndarray) -> np.ndarray:
        """(N, 3) world points -> (N, 2) pixels, distortion included (cv2.projectPoints).

        Points behind the camera (z_c <= 0) still get a pixel; check depth if it matters.
        """
        points = np.asarray(points_world, dtype=float).reshape(-1, 3)
        if len(points) == 0:
            return np.empty((0, 2))
        pixels, _ = cv2.projectPoints(points, self.rvec, self.t, self.K, self.distortion)
        return pixels.reshape(-1, 2)

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """(N, 2) pixels -> (N, 2) normalised image coordinates (x_c / z_c, y_c / z_c)."""
        pixels = np.asarray(pixels, dtype=float).reshape(-1, 2)
        if len(pixels) == 0:
            return np.empty((0, 2))
        normalised = cv2.undistortPoints(
            pixels.reshape(-1, 1, 2), self.K, self.distortion, criteria=_UNDISTORT_CRITERIA
        )
        return normalised.reshape(-1, 2)

    def direction(self, normalised: np.ndarray) -> np.ndarray:
        """(N, 3) unit world directions of the rays through (N, 2) normalised coordinates.

        d = R^T (x, y, 1) / ||(x, y, 1)||: every world point X = C + s d with s > 0 has the
        normalised image (x, y) (``undistort`` turns pixels into those).
        """
        directions: np.ndarray = np.column_stack([normalised, np.ones(len(normalised))]) @ self.R  # row-wise R^T v
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        return directions

    def in_image(self, pixels: np.ndarray) -> np.ndarray:
        """(N,) bool: the pixel lies on the sensor ([-0.5, size - 0.5] per axis; NaN -> False)."""
        pixels = np.asarray(pixels, dtype=float).reshape(-1, 2)
        upper = np.asarray(self.image_size, dtype=float) - 0.5
        inside: np.ndarray = np.all((pixels >= -0.5) & (pixels <= upper), axis=1)
        return inside
