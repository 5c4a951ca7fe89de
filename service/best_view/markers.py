"""Camera mode: the camera that shows each marker best, per frame, attached to the labels.

Each marker is an object of Jiang's best-view DP (``formulations.best_view``). Its view
quality in camera b (``marker_quality``) is the projected size f_b / z_b, times whether
camera b detected it (the detection it took there, ``CaptureLabeling.views``; the
occlusion-aware P_D will replace this 0/1 once it exists), times the viewing-angle factor
(1 + cos theta_b) / 2; positions are the labeled ones, or the fill where a marker was
occluded. The costs are relative (``relative_costs``: 0 for the frame's best camera, 1
for one that does not show the marker), so the switch cost is counted in frames of the
best view. Defaults (``LabelingOptions``): lambda = 1 (a switch must win back one whole
frame of the best view) and N = 30 frames (a quarter second at 120 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from formulations.best_view import marker_quality, relative_costs, select_views
from formulations.cameras.camera import Camera
from service.errors import InputError
from service.io.recording import LabeledTrajectories


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
        quality = marker_quality(positions, (views >= 0).astype(float), self.cameras)
        chosen = select_views(relative_costs(quality), self.switch_cost, self.window)
        return replace(labels, best_view=chosen, view_names=[camera.name for camera in self.cameras])
