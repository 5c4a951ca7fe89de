"""A camera-mode scenario: real motion through a real calibration, labeled and scored.

The trajectories are placed in the calibrated volume, projected into every camera
(``service.simulate_cameras``), matched across cameras and labeled by the window LP
(``joint-3d``), then scored against the detections behind every labeled point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

from service.calibration import load_calibration
from service.camera_scores import CameraScores, camera_scores
from service.cloud_labeler import CloudLabeler
from service.joint_3d import cross_camera_cloud
from service.recording import Recording
from service.scenario import Scenario
from service.simulate_cameras import CameraRig, place_in_volume, simulate_cameras
from service.window_stats import WindowStats, certificate_figures, finite_or_none


@dataclass
class CameraEvaluation:
    """A scored camera-mode run."""

    scores: CameraScores
    windows: list[WindowStats]
    frames: int
    markers: int
    seconds: float
    formulation: str

    def summary(self) -> dict[str, float | int | str | None]:
        """The ``markerflow eval --json`` figures; swaps and ghosts are cloud-mode only (None)."""
        return {
            "label_accuracy": self.scores.label_accuracy, "swaps": None,
            "ghost_precision": None, "ghost_recall": None,
            **certificate_figures(self.windows),
            "seconds_per_frame": self.seconds / max(self.frames - 1, 1), "frames": self.frames,
            "markers": self.markers, "formulation": self.formulation,
            "rmse_mm": finite_or_none(self.scores.rmse_mm),
            "filled_rmse_mm": finite_or_none(self.scores.filled_rmse_mm),
        }


def evaluate_cameras(
    truth: Recording, scenario: Scenario, labeler: CloudLabeler,
    progress: Callable[[int, int], None] | None = None,
) -> CameraEvaluation:
    """Simulate ``scenario`` (mode "cameras") on ``truth``, label with joint-3d, score."""
    cameras = load_calibration(scenario.calibration, units="mm")
    rig = CameraRig.from_cameras(cameras)
    stop = scenario.start_frame + scenario.frames if scenario.frames else truth.n_frames
    positions = place_in_volume(truth.positions[scenario.start_frame : stop], rig, up_axis=scenario.up_axis)
    capture = simulate_cameras(
        Recording(truth.names, positions, truth.rate), rig, pixel_noise=scenario.pixel_noise,
        merge_radius_px=scenario.merge_radius_px, occlusion_rate=scenario.occlusion_rate,
        occlusion_burst_frames=scenario.occlusion_burst_frames,
        clutter_per_camera=scenario.clutter_per_camera, seed=scenario.seed,
    )
    start = time.perf_counter()
    cloud, matched = cross_camera_cloud(cameras, capture.detections, truth.rate)
    result, windows = labeler.label(cloud, capture.first_frame.names, capture.first_frame.positions[0], progress)
    seconds = time.perf_counter() - start
    scores = camera_scores(capture.marker_detection, capture.truth.positions, result, matched)
    name = labeler.formulation if isinstance(labeler.formulation, str) else labeler.formulation.name
    return CameraEvaluation(scores, windows, len(positions), truth.n_markers, seconds, name)
