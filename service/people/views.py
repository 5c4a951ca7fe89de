"""Each participant's best camera per frame, from OpenPose keypoints in calibrated cameras.

The Pose2Sim step of best view: per camera, every detected person becomes a box
(``keypoint_boxes``), the boxes are tracked by Jiang's window LP
(``service.boxes.track``), the tracks are named after
the participants (``participants``), and each participant's box per camera and frame
is measured by its size and truncation (``formulations.best_view.box_quality``). The
choice is Jiang's sliding-window DP on the relative costs (``select_views``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formulations.best_view import box_quality, relative_costs, select_views
from formulations.cameras.camera import Camera
from service.boxes.track import track_boxes
from service.errors import InputError
from service.people.keypoint_boxes import person_boxes
from service.people.openpose import read_openpose_folder
from service.people.participants import participant_boxes, projected_boxes


@dataclass(frozen=True)
class PeopleViews:
    """Each participant's box in each camera and frame.

    Attributes:
        people: Participant names.
        cameras: The calibrated cameras, in the order of the box axis.
        boxes: ``(F, P, M, 4)`` left, top, width, height in pixels; NaN where the
            camera shows no track of the participant.
        tracks: Per camera, how many tracks its boxes formed.
    """

    people: list[str]
    cameras: list[Camera]
    boxes: np.ndarray
    tracks: list[int]

    def quality(self) -> np.ndarray:
        """``(F, P, M)`` box quality area (1 - truncation)^2, 0 where no box."""
        sizes = np.array([camera.image_size for camera in self.cameras], dtype=float)
        return box_quality(self.boxes, sizes)

    def choose(self, switch_cost: float, window: int) -> np.ndarray:
        """``(F, P)`` camera index per frame and participant by the sliding-window DP."""
        return select_views(relative_costs(self.quality()), switch_cost, window)


def people_views(keypoint_folders: list[Path], cameras: list[Camera], participants: dict[str, np.ndarray]) -> PeopleViews:
    """Box, track and name the people of every camera.

    Args:
        keypoint_folders: One OpenPose JSON folder per camera, in the order of ``cameras``.
        cameras: The calibration, world unit that of ``participants``.
        participants: Name -> ``(F, J, 3)`` world keypoints, NaN where unknown.

    Raises:
        InputError: folders and cameras that do not pair, cameras whose files are numbered
            differently, or frame counts that differ.
    """
    if len(keypoint_folders) != len(cameras):
        raise InputError(f"{len(keypoint_folders)} keypoint folders for {len(cameras)} cameras")
    read = [read_openpose_folder(folder) for folder in keypoint_folders]
    numbers = [numbered for numbered, _ in read]
    if any(n != numbers[0] for n in numbers):  # paired by position, the cameras would be out of step
        shown = ", ".join(f"{folder.name} {n[0]}-{n[-1]} ({len(n)} files)" for folder, n in zip(keypoint_folders, numbers))
        raise InputError(f"the cameras' OpenPose files are numbered differently ({shown}): give each camera the same frames")
    frames = [people for _, people in read]
    counts = {len(f) for f in frames} | {len(points) for points in participants.values()}
    if len(counts) != 1:
        raise InputError(f"cameras and participants cover different frame counts: {sorted(counts)}")
    reference = {name: points for name, points in participants.items()}
    boxes, n_tracks = [], []
    for camera, camera_frames in zip(cameras, frames):
        tracks = track_boxes(person_boxes(camera_frames, camera.image_size)).tracks
        projected = np.stack([projected_boxes(points, camera) for points in reference.values()])
        boxes.append(participant_boxes(tracks, projected))
        n_tracks.append(len(np.unique(tracks.track_id)))
    return PeopleViews(list(reference), cameras, np.stack(boxes, axis=2).transpose(1, 0, 2, 3), n_tracks)


def pose2sim_world(trc_points: np.ndarray) -> np.ndarray:
    """Pose2Sim's TRC axes (Y up) back to its calibration's world (Z up): X_world = (z, x, y)_trc."""
    return trc_points[..., [2, 0, 1]]
