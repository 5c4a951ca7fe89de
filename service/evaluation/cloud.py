"""Run a scenario on labeled trajectories and score the labeling (DESIGN: evaluation protocol)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from service.capture.formulation_spec import formulation_from_table
from service.evaluation.scenario import Scenario
from service.evaluation.scores import LabelScores, label_scores
from service.evaluation.simulate_cloud import simulate_cloud
from service.evaluation.simulated import SimulatedCapture
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.cloud import CloudLabeler
from service.labeling.stats import WindowStats, certificate_figures


@dataclass
class Evaluation:
    """A scored run: the capture, what markerflow made of it, and the figures."""

    capture: SimulatedCapture
    result: LabeledTrajectories
    windows: list[WindowStats]
    scores: LabelScores
    seconds: float
    formulation: str

    def summary(self) -> dict[str, float | int | str]:
        """The stable figures ``markerflow eval --json`` prints.

        Gaps are None where a formulation proves no bound (heuristics): JSON has no inf.
        """
        frames = self.capture.cloud.n_frames
        return {
            "label_accuracy": self.scores.label_accuracy,
            "swaps": self.scores.swaps,
            "ghost_precision": self.scores.ghost_precision,
            "ghost_recall": self.scores.ghost_recall,
            **certificate_figures(self.windows),
            "seconds_per_frame": self.seconds / max(frames - 1, 1),
            "frames": frames,
            "markers": len(self.capture.first_frame.names),
            "formulation": self.formulation,
        }


def evaluate(
    truth: Recording, scenario: Scenario, labeler: CloudLabeler | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Evaluation:
    """Simulate ``scenario`` on ``truth``, label it, and score the result."""
    if labeler is None:
        table = {"name": scenario.formulation, **scenario.formulation_parameters}
        labeler = CloudLabeler(formulation=formulation_from_table(table, "scenario"), window=scenario.window)
    capture = simulate_cloud(truth, scenario)
    start = time.perf_counter()
    result, windows = labeler.label(capture.cloud, capture.first_frame.names, capture.first_frame.positions[0], progress)
    seconds = time.perf_counter() - start
    name = labeler.formulation if isinstance(labeler.formulation, str) else labeler.formulation.name
    return Evaluation(capture, result, windows, label_scores(capture, result), seconds, name)
