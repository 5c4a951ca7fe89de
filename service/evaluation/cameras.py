"""A camera-mode scenario: real motion through a real calibration, labeled and scored.

The trajectories are placed in the calibrated volume, projected into every camera
(``service.evaluation.simulate_cameras``), labeled with the scenario's association (``joint-3d``:
cross-camera points labeled by the window LP; ``per-camera``: the window LP in each
camera's image, then triangulation), and scored by the detections each marker used.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from formulations.cameras.rig import Rig
from formulations.methods.formulation import Formulation
from service.capture.capture import Capture
from service.evaluation.camera_scores import CameraScores, camera_scores
from service.evaluation.scenario import Scenario
from service.evaluation.simulate_cameras import place_in_volume, simulate_cameras
from service.io.calibration import load_calibration
from service.io.recording import Recording
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.loop import Progress
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
            "label_accuracy": self.scores.label_accuracy if self.scores.marker_frames else None,
            "marker_frames": self.scores.marker_frames, "swaps": self.scores.swaps,
            "ghost_precision": None, "ghost_recall": None,
            **certificate_figures(self.windows),
            "seconds_per_frame": self.seconds / max(self.frames - 1, 1), "frames": self.frames,
            "markers": self.markers, "formulation": self.formulation,
            "rmse_mm": finite_or_none(self.scores.rmse_mm),
            "filled_rmse_mm": finite_or_none(self.scores.filled_rmse_mm),
            "single_view_rmse_mm": finite_or_none(self.scores.single_view_rmse_mm),
        }


def evaluate_cameras(
    truth: Recording, scenario: Scenario, formulation: str | dict | Formulation | None = None,
    progress: Progress | None = None,
) -> CameraEvaluation:
    """Simulate ``scenario`` (mode "cameras") on ``truth``, label with its association, score.

    ``formulation`` replaces the scenario's own.
    """
    cameras = load_calibration(Path(scenario.calibration), units="mm")
    rig = Rig.of(cameras)
    first_used, stop = scenario.frame_span(truth.n_frames)
    positions = place_in_volume(truth.positions[first_used:stop], rig, up_axis=scenario.up_axis)
    simulated = simulate_cameras(
        Recording(truth.names, positions, truth.rate), rig, pixel_noise=scenario.pixel_noise,
        merge_radius_px=scenario.merge_radius_px, occlusion_rate=scenario.occlusion_rate,
        occlusion_burst_frames=scenario.occlusion_burst_frames,
        clutter_per_camera=scenario.clutter_per_camera, seed=scenario.seed,
    )
    first = simulated.first_frame
    capture = Capture(list(first.names), first.positions[0], first.rate, cameras=cameras, detections=simulated.detections)
    start = time.perf_counter()
    labeling = CaptureLabeling(capture, scenario.labeling_options(formulation))
    outcomes = list(labeling.windows(progress=progress))
    result, views = labeling.result(outcomes), labeling.views(outcomes)
    seconds = time.perf_counter() - start
    scores = camera_scores(simulated.marker_detection, simulated.truth.positions, result, views)
    windows = [o.stats for o in outcomes]
    return CameraEvaluation(scores, windows, len(positions), truth.n_markers, seconds, labeling.formulation.name)
