"""``joint-3d`` association: label triangulated cross-camera points with the window LP.

Each frame's detections are matched across cameras (``formulations.cameras.cross_camera.matching``); the
resulting 3D points become an unlabeled cloud whose resources are the (camera, detection)
pairs each point uses, so two candidates sharing a detection conflict in the window LP.
Frames are matched in blocks (``match_frames``): one block shares its numpy and OpenCV calls,
and a block no longer than a window adds no latency the window LP does not already have.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.cross_camera.matching import CrossCameraPoints, match_frames
from formulations.cameras.lone_views import fills_on_lone_views
from formulations.cameras.rig import Rig
from service.io.recording import LabeledTrajectories, UnlabeledCloud
from service.labeling.cloud import CloudChain
from service.labeling.outcome import WindowOutcome


class LazyFrames(Sequence[Any]):
    """A per-frame sequence whose items are computed when first asked for, then kept."""

    def __init__(self, n_frames: int, compute: Callable[[int], Any]) -> None:
        self._n, self._compute = n_frames, compute
        self._done: dict[int, Any] = {}

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, f: int | slice) -> Any:
        if isinstance(f, slice):
            return [self[k] for k in range(*f.indices(self._n))]
        if not -self._n <= f < self._n:
            raise IndexError(f)
        f %= self._n
        if f not in self._done:
            self._done[f] = self._compute(f)
        return self._done[f]


@dataclass
class Joint3dChain(CloudChain):
    """The cloud chain on cross-camera points, which knows the detections behind each point.

    Attributes:
        matched: Per frame, the cross-camera points the cloud holds.
    """

    matched: Sequence[CrossCameraPoints] = ()
    rig: Rig | None = None
    detections: Sequence[list[np.ndarray]] = ()

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        """The cloud's trajectories with frame 0 as the user labeled it.

        Frame 0's cross-camera points are the labeled markers' detections triangulated again:
        up to 2.3 mm off the given positions on 0.3 px noise, and none for a marker only one
        camera sees, which came out occluded in the frame the user labeled. ``per-camera``
        returns the labeled positions; so does this now. The point each marker was matched to
        in frame 0 stays its ``point_index`` there, so its views are still the detections behind it.
        """
        labels = super().assemble(outcomes)
        first = np.asarray(self.first_frame, dtype=float)
        given = np.isfinite(first).all(axis=1)
        labels.positions[0, given], labels.occluded[0, given] = first[given], False
        return labels

    def fills_on_lone_views(self, result: LabeledTrajectories, outcomes: list[WindowOutcome]) -> np.ndarray:
        """The result's fill with each marker one camera still sees put on that ray (``lone_views``).
        Detections are undistorted only in the frames that have a fill to place."""
        if self.rig is None:
            return result.filled
        rig, views = self.rig, self.views(outcomes)  # (F, N, C)

        def pixels(f: int) -> list[np.ndarray]:
            return [np.asarray(found, dtype=float).reshape(-1, 2) for found in self.detections[f]]

        def normalised(f: int) -> list[np.ndarray]:
            return [camera.undistort(p) if len(p) else p for camera, p in zip(rig.cameras, pixels(f))]

        def used(f: int) -> list[np.ndarray]:
            taken = views[f].T  # (C, N)
            return [np.isin(np.arange(len(p)), taken[c][taken[c] >= 0]) for c, p in enumerate(pixels(f))]

        n = len(self.detections)
        return fills_on_lone_views(result.filled, result.occluded, result.positions, rig,
                                   LazyFrames(n, normalised), LazyFrames(n, used))

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        """``(F, N, C)`` detections behind the cross-camera point each marker took, -1 none."""
        point_index = self.assemble(outcomes).point_index
        n_cameras = self.matched[0].views.shape[1]
        views = np.full(point_index.shape + (n_cameras,), -1)
        for f, points in enumerate(self.matched):
            took = np.flatnonzero(point_index[f] >= 0)
            views[f, took] = points.views[point_index[f, took]]
        return views


# The matcher's gates (px) are the larger of these defaults, chosen on 0.5 px simulated noise,
# and GATE_SIGMAS times the detections' sd about frame 0's projections: real ChArUco corners
# through caliscope's calibration sit 1.2 px (median) off, and at 2 / 3 px joint-3d labeled
# every corner two corners over (RMSE 107 mm; 2.6 mm at 4 / 6 px).
REPROJECTION_PX, EPIPOLAR_PX = 2.0, 3.0
GATE_SIGMAS = (4.0, 6.0)  # reprojection RMS, epipolar distance: as the defaults' 2 : 3


def matcher_gates(sigma_px: float | None) -> tuple[float, float]:
    """``(epipolar_px, max_reprojection_px)`` for detections of per-axis sd ``sigma_px``
    (``service.capture.reprojection.frame0_pixel_sigma``; None: the defaults)."""
    sigma = sigma_px or 0.0
    return max(EPIPOLAR_PX, GATE_SIGMAS[1] * sigma), max(REPROJECTION_PX, GATE_SIGMAS[0] * sigma)


def cross_camera_cloud(
    cameras: list[Camera], detections: list[list[np.ndarray]], rate: float,
    epipolar_px: float = EPIPOLAR_PX, max_reprojection_px: float = REPROJECTION_PX, block_frames: int = 20,
) -> tuple[UnlabeledCloud, Sequence[CrossCameraPoints]]:
    """The cross-camera points of every frame as a cloud with detection resources.

    Frames are matched on demand, ``block_frames`` at a time: a long job labels (and reports)
    its first window without matching every frame first, and a resumed job matches only the
    blocks it still needs.
    """
    blocks: dict[int, list[CrossCameraPoints]] = {}

    def match(f: int) -> CrossCameraPoints:
        start = f - f % block_frames
        if start not in blocks:
            blocks[start] = match_frames(cameras, detections[start : start + block_frames], epipolar_px, max_reprojection_px)
        return blocks[start][f - start]

    def resources(f: int) -> Any:
        offsets = np.cumsum([0] + [len(d) for d in detections[f]])
        return matched[f].resources(offsets[:-1], int(offsets[-1]))

    n = len(detections)
    matched = LazyFrames(n, match)
    points = LazyFrames(n, lambda f: matched[f].points)
    # The cloud only indexes, slices and counts its frames: lazy sequences serve as lists.
    lazy_points, lazy_resources = cast(list[np.ndarray], points), cast(list[Any], LazyFrames(n, resources))
    return UnlabeledCloud(points=lazy_points, rate=rate, resources=lazy_resources), matched
