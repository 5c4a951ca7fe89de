"""A frame-by-frame track through 2D detections that centres the per-camera gates of a window.

Each frame: predict every marker in 3D (``MarkerState.predict``), project the predictions
into every camera, assign each camera's detections to the markers by
``linear_sum_assignment`` on image-plane distance with a constant miss cost, locate the
markers from those views (``per_camera_locate``: triangulation, dropping the views that
disagree; ``per_camera_reacquire``: a second view for markers left with one), and advance
the state with the markers seen by two or more cameras. As
``formulations.markers.guide`` does for clouds, this decides only *where to look*; the window LP
decides *what to take*.

Image-plane distances are in millimetres at the marker's depth. With (x, y) = (X_c / Z_c,
Y_c / Z_c) the normalised (undistorted) coordinates of camera c and z the depth of the
marker's position, a normalised offset du is z du mm of sideways motion: the gates and
costs of the 3D labeler carry over, and a camera twice as far away does not halve them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import cdist

from formulations.cameras.per_camera.advance import advance_state
from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.locate import FrameViews
from formulations.cameras.per_camera.reacquire import locate_with_reacquisition
from formulations.cameras.rig import Rig
from formulations.markers.guide import assign_within_gates
from formulations.markers.state import MarkerState


@dataclass(frozen=True)
class PerCameraGuide:
    """Per window frame 1..M, what the guide knew before the frame.

    Attributes:
        predicted: ``(M, N, 3)`` prediction into frame m.
        previous: ``(M, N, 3)`` position at frame m-1 (the prediction where unseen).
        radius: ``(M, N)`` gate radius of the window's candidates (``window_gate``), mm.
        unseen: ``(M, N)`` frames unseen before m (0: seen by 2+ cameras in frame m-1).
        motion_known: ``(M, N)`` False while a marker's velocity is unknown (just after the
            labeled first frame): its expected displacement is then left out.
    """

    predicted: np.ndarray
    previous: np.ndarray
    radius: np.ndarray
    unseen: np.ndarray
    motion_known: np.ndarray


def image_distances(image: np.ndarray, depth: np.ndarray, normalised: np.ndarray) -> np.ndarray:
    """``(N, D)`` distance in mm at each point's depth from its image to each detection.

    Args:
        image: ``(N, 2)`` normalised image of the points in one camera (``Rig.image_plane``).
        depth: ``(N,)`` their depth.
        normalised: ``(D, 2)`` undistorted normalised detections (``Camera.undistort``).

    Returns:
        z_n ||x_n - x_d||; inf for points behind the camera.
    """
    distance = cdist(image, normalised) * depth[:, None] if len(normalised) else np.zeros((len(image), 0))
    return np.where(np.isfinite(distance), distance, np.inf)


def per_camera_guide(
    state: MarkerState, rig: Rig, frames: list[FrameViews], gating: PerCameraGating = PerCameraGating(),
) -> PerCameraGuide:
    """Run the frame-by-frame tracker over a window's detections from ``state``.

    Args:
        state: The markers at the template frame.
        rig: The C cameras.
        frames: Detections of window frames 1..M.
        gating: Gate radius (mm at the marker's depth; its base radius is the miss cost)
            and the limits of the cross-camera check.
    """
    m, n = len(frames), len(state.position)
    predicted, previous = np.empty((m, n, 3)), np.empty((m, n, 3))
    radius, unseen, known = np.empty((m, n)), np.empty((m, n), dtype=int), np.empty((m, n), dtype=bool)
    for f, frame in enumerate(frames):
        predicted[f], previous[f], unseen[f] = state.predict(), state.position, state.unseen
        radius[f], known[f] = gating.window_gate.radius(state), ~(state.visible & ~state.velocity_known)
        image, depth = rig.image_plane(predicted[f])
        gate = gating.gate.radius(state)
        views = np.stack([
            assign_within_gates(image_distances(image[c], depth[c], found), gate, gating.gate.radius_mm)
            for c, found in enumerate(frame.normalised)
        ], axis=1)
        located, _ = locate_with_reacquisition(rig, frame, views, state, predicted[f], gating)
        state = advance_state(state, located)
    return PerCameraGuide(predicted=predicted, previous=previous, radius=radius, unseen=unseen, motion_known=known)
