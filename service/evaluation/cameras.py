"""A camera-mode scenario: real motion through a real calibration, labeled and scored.

The trajectories are placed in the calibrated volume, projected into every camera
(``service.evaluation.simulate_cameras``), labeled with the scenario's association (``joint-3d``:
cross-camera points labeled by the window LP; ``per-camera``: the window LP in each
camera's image, then triangulation), and scored by the detections each marker used.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from formulations.cameras.camera import Camera
from service.capture.capture import Capture
from service.evaluation.camera_scores import CameraScores, camera_scores, joint_3d_views
from service.evaluation.scenario import Scenario
from service.evaluation.simulate_cameras import CameraCapture, CameraRig, place_in_volume, simulate_cameras
from service.io.calibration import load_calibration
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.cloud import CloudLabeler
from service.labeling.joint_3d import cross_camera_cloud
from service.labeling.per_camera import PerCameraLabeler
from service.labeling.spans import window_spans
from service.labeling.stats import WindowStats, certificate_figures, finite_or_none


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
        """The ``markerflow eval --json`` figures; ghosts are cloud-mode only (None)."""
        return {
            "label_accuracy": self.scores.label_accuracy, "swaps": self.scores.swaps,
            "ghost_precision": None, "ghost_recall": None,
            **certificate_figures(self.windows),
            "seconds_per_frame": self.seconds / max(self.frames - 1, 1), "frames": self.frames,
            "markers": self.markers, "formulation": self.formulation,
            "rmse_mm": finite_or_none(self.scores.rmse_mm),
            "filled_rmse_mm": finite_or_none(self.scores.filled_rmse_mm),
            "single_view_rmse_mm": finite_or_none(self.scores.single_view_rmse_mm),
        }


def evaluate_cameras(
    truth: Recording, scenario: Scenario, labeler: CloudLabeler,
    progress: Callable[[int, int], None] | None = None,
) -> CameraEvaluation:
    """Simulate ``scenario`` (mode "cameras") on ``truth``, label with its association, score.

    ``labeler`` gives the formulation and window of either association.
    """
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
    if scenario.association == "per-camera":
        result, windows, views = _per_camera(cameras, capture, labeler, progress)
    else:
        cloud, matched = cross_camera_cloud(cameras, capture.detections, truth.rate)
        result, windows = labeler.label(cloud, capture.first_frame.names, capture.first_frame.positions[0], progress)
        views = joint_3d_views(result, matched)
    seconds = time.perf_counter() - start
    scores = camera_scores(capture.marker_detection, capture.truth.positions, result, views)
    name = labeler.formulation if isinstance(labeler.formulation, str) else labeler.formulation.name
    return CameraEvaluation(scores, windows, len(positions), truth.n_markers, seconds, name)


def _per_camera(
    cameras: list[Camera], simulated: CameraCapture, labeler: CloudLabeler,
    progress: Callable[[int, int], None] | None,
) -> tuple[LabeledTrajectories, list[WindowStats], np.ndarray]:
    """Label the simulated detections camera by camera: trajectories, window stats, views."""
    first = simulated.first_frame
    capture = Capture(
        list(first.names), first.positions[0], first.rate, cameras=cameras, detections=simulated.detections,
    )
    per_camera = PerCameraLabeler(formulation=labeler.formulation, window=labeler.window)
    n_windows, outcomes = len(window_spans(capture.n_frames, labeler.window)), []
    for outcome in per_camera.windows(capture):
        outcomes.append(outcome)
        if progress:
            progress(outcome.index + 1, n_windows)
    return per_camera.assemble(capture, outcomes), [o.stats for o in outcomes], per_camera.views(capture, outcomes)
