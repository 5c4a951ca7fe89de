"""Run a scenario on labeled trajectories and score the labeling (DESIGN: evaluation protocol)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from formulations.methods.formulation import Formulation
from service.evaluation.doubt_scores import doubt_scores
from service.evaluation.scenario import Scenario
from service.evaluation.scores import LabelScores, label_scores
from service.evaluation.simulate_cloud import simulate_cloud
from service.evaluation.simulated import SimulatedCapture
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.loop import Progress
from service.labeling.stats import WindowStats, certificate_figures, finite_or_none


@dataclass
class Evaluation:
    """A scored run: the capture, what markerflow made of it, and the figures."""

    capture: SimulatedCapture
    result: LabeledTrajectories
    windows: list[WindowStats]
    scores: LabelScores
    seconds: float
    formulation: str

    def summary(self) -> dict[str, float | int | str | None]:
        """The stable figures ``markerflow eval --json`` prints.

        Gaps are None where a formulation proves no bound (heuristics): JSON has no inf;
        ``label_accuracy`` is None where no marker-frame was scored (every sample deleted).
        ``doubtful_share`` and ``doubtful_recall`` are those of ``doubt_scores``.
        """
        frames = self.capture.cloud.n_frames
        scored = self.scores.marker_frames
        return {
            "label_accuracy": self.scores.label_accuracy if scored else None,  # nothing scored is no 100 %
            "marker_frames": scored, "correct": self.scores.correct, "missed": self.scores.missed,
            "swaps": self.scores.swaps,
            "ghost_precision": self.scores.ghost_precision,
            "ghost_recall": self.scores.ghost_recall,
            **certificate_figures(self.windows),
            **doubt_scores(self.capture, self.result),
            "seconds_per_frame": self.seconds / max(frames - 1, 1),
            "frames": frames,
            "markers": len(self.capture.first_frame.names),
            "formulation": self.formulation,
            "filled_rmse_mm": finite_or_none(filled_rmse_mm(self.capture, self.result)),
        }


def filled_rmse_mm(capture: SimulatedCapture, result: LabeledTrajectories) -> float:
    """3D error (mm) of the positions filled in where a marker came back unlabeled, against the
    clean truth (frame 0, the user's, not counted), as camera mode's ``filled_rmse_mm``; NaN when none."""
    truth = capture.truth
    true = truth.positions[:, [truth.names.index(name) for name in result.names]]
    error = np.linalg.norm(result.filled - true, axis=2)[1:]
    error = error[result.occluded[1:] & np.isfinite(error)]
    return float(np.sqrt(np.mean(error**2))) if error.size else float("nan")


def evaluate(
    truth: Recording, scenario: Scenario, formulation: str | dict | Formulation | None = None,
    progress: Progress | None = None,
) -> Evaluation:
    """Simulate ``scenario`` on ``truth``, label it, and score the result.

    ``formulation`` replaces the scenario's own.
    """
    simulated = simulate_cloud(truth, scenario)
    start = time.perf_counter()
    labeling = CaptureLabeling(simulated.capture(), scenario.labeling_options(formulation))
    result, windows = labeling.label(progress)
    seconds = time.perf_counter() - start
    scores = label_scores(simulated, result)
    return Evaluation(simulated, result, windows, scores, seconds, labeling.formulation.name)
