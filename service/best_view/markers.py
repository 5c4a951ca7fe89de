"""Camera mode: the camera that shows each marker best, per frame, attached to the labels.

Each marker is an object of Jiang's best-view DP (``formulations.best_view``). Its view
quality in camera b (``marker_quality``) is the projected size f_b / z_b, times its
visibility in camera b, times the viewing-angle factor (1 + cos theta_b) / 2; positions
are the labeled ones, or the fill where a marker was occluded; where it has neither, no
camera is chosen (-1).

Visibility: 1 where camera b detected the marker (the detection it took there,
``CaptureLabeling.views``), else the occlusion-aware P_D of eq. 8 of Ringer & Lasenby
(``formulations.cameras.visibility``): lambda_D where the ray from the marker to the camera
clears the body, 0 through it, blurred at the edges. The body is the marker-based one
(``marker_capsules`` around each marker's rigid neighbours, found on the labeled
trajectories): camera mode has no subject model (a capture refuses one there), so the
model's segment capsules do not apply. So an occluded marker's best view is a camera that
would see it past the body, not an arbitrary one of its all-zero qualities; and a
detection still beats a clear ray (lambda_D < 1) at equal size and angle.

A camera that took no marker in a frame is ruled out there (``select_views``' ``allowed``)
whenever another camera took one: its cost of 1 tied with a switch at lambda = 1, so a
camera that went blind stayed the best view while the tie lasted.

The costs are relative (``relative_costs``: 0 for the frame's best camera, 1 for one
that does not show the marker), so the switch cost is counted in frames of the
best view. Defaults (``LabelingOptions``): lambda = 1 (a switch must win back one whole
frame of the best view) and N = 30 frames (a quarter second at 120 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from formulations.best_view import marker_quality, relative_costs, select_views
from formulations.cameras.camera import Camera
from formulations.cameras.visibility import Body, blur, detection_probability
from formulations.cameras.visibility_body import marker_capsules, rigid_neighbours
from formulations.subject.model import MARKER_RADIUS_MM
from service.errors import InputError
from service.io.recording import LabeledTrajectories

DETECTION_RATE = 0.9  # lambda_D, a visible marker's detection rate: below 1, a detection outranks a clear ray
RIGID_NEIGHBOURS = 3  # capsules per marker of the marker-based body
RIGID_SD_MM = 10.0  # sd of a rigid neighbour's distance: noise and skin motion (as ``subject.fit``)
RIGIDITY_FRAMES = 300  # frames, evenly spread, that judge which neighbours are rigid


@dataclass(frozen=True)
class MarkerViewChoice:
    """Best view of every marker for a capture's cameras.

    Raises:
        InputError: a switch cost that is negative or not finite, or a window under one frame.
    """

    cameras: list[Camera]
    switch_cost: float
    window: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.switch_cost) and self.switch_cost >= 0):
            raise InputError(f"best_view_switch_cost must be a finite number >= 0, got {self.switch_cost}")
        if self.window < 1:
            raise InputError(f"best_view_window must be at least 1 frame, got {self.window}")

    def attach(self, labels: LabeledTrajectories, views: np.ndarray) -> LabeledTrajectories:
        """``labels`` with ``best_view`` and ``view_names`` set.

        Args:
            labels: The assembled labels (positions, and the fill where occluded).
            views: ``(F, N, C)`` detection each marker took in each camera, -1 none.
        """
        positions = labels.positions
        if labels.filled.shape == positions.shape:
            positions = np.where(np.isnan(positions), labels.filled, positions)
        detected = np.asarray(views >= 0)
        visibility = self._visibility(labels.positions, positions, detected)
        # a camera that took no marker in a frame is blind there (off, covered, its detections
        # filed elsewhere): no clear ray makes it a view of any marker
        seeing: np.ndarray = np.asarray(detected.any(axis=1))  # (F, C)
        visibility = np.where(seeing[:, None, :], visibility, 0.0)
        quality = marker_quality(positions, visibility, self.cameras)
        # and it is ruled out, not merely priced at 1: that ties with a switch at lambda = 1,
        # and the tie kept a camera blind since the frame before (a frame no camera sees rules none out)
        allowed = np.broadcast_to((seeing | ~seeing.any(axis=1, keepdims=True))[:, None, :], quality.shape)
        chosen = select_views(relative_costs(quality), self.switch_cost, self.window, allowed)
        chosen[~np.isfinite(positions).all(axis=2)] = -1  # no position: no view of it to choose
        return replace(labels, best_view=chosen, view_names=[camera.name for camera in self.cameras])

    def _visibility(self, measured: np.ndarray, positions: np.ndarray, detected: np.ndarray) -> np.ndarray:
        """``(F, N, C)``: 1 where detected, else P_D past the marker-based body of each frame (module doc)."""
        visibility = detected.astype(float)
        frames, markers = positions.shape[:2]
        if markers < 2:  # nothing else to hide a lone marker
            return np.where(detected, 1.0, DETECTION_RATE)
        step = max(1, frames // RIGIDITY_FRAMES)
        neighbours = rigid_neighbours(measured[::step], min(RIGID_NEIGHBOURS, markers - 1), RIGID_SD_MM)
        centres = np.array([camera.centre for camera in self.cameras])
        edge = blur(MARKER_RADIUS_MM)
        for f in np.flatnonzero((~detected).any(axis=(1, 2))):
            missed = np.flatnonzero((~detected[f]).any(axis=1) & np.isfinite(positions[f]).all(axis=1))
            if len(missed) == 0:
                continue
            body: Body = marker_capsules(positions[f], neighbours, MARKER_RADIUS_MM)
            p_d = detection_probability(body, positions[f, missed], centres, DETECTION_RATE, edge)
            visibility[f, missed] = np.where(detected[f, missed], 1.0, p_d)
        return visibility
