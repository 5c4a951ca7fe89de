"""A simulated capture: labeler input together with the truth it was made from."""

from dataclasses import dataclass

import numpy as np

from service.capture.capture import Capture
from service.evaluation.scenario import Scenario
from service.io.recording import Recording, UnlabeledCloud


@dataclass
class SimulatedCapture:
    """What the simulator hands the labeler, plus the answers the scorer needs.

    Attributes:
        cloud: Unlabeled, shuffled points per frame: the labeler's input.
        point_marker: Per frame, one entry per point of ``cloud.points[f]``: the index of
            the true marker it measures, or -1 for a ghost.
        truth: The clean (noise-free) trajectories of the simulated frames; NaN where the
            source recording had no sample.
        first_frame: Marker names and their measured positions in the first frame, one
            frame long: the labeled frame the user supplies.
        scenario: The settings that produced this capture.
    """

    cloud: UnlabeledCloud
    point_marker: list[np.ndarray]
    truth: Recording
    first_frame: Recording
    scenario: Scenario

    def capture(self) -> Capture:
        """What a user would hand markerflow: the points and the labeled first frame (which
        leaves the scenario's ``unnamed_markers`` out, as ``track --start`` leaves markers
        absent there)."""
        first = self.first_frame
        return Capture(list(first.names), first.positions[0], self.cloud.rate, points=self.cloud.points,
                       unnamed_markers=self.scenario.unnamed_markers)
