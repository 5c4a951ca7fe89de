"""Labeling from a subject model: no labeled frame; markers named when the model finds them.

The capture's frame 0 is identified (``formulations.subject.identify``); its named markers
start the marker state (``model_start_state``). Before each window, markers unseen at the
template frame are looked for there again: a point the model names for such a marker, that
no seen marker holds, becomes its position (``acquire``). So a marker absent at the start
is named when it appears, within one window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from formulations.markers.reacquire import REACQUISITION
from formulations.markers.state import MarkerState
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify
from formulations.subject.model import SubjectModel
from formulations.subject.start_state import acquire, model_start_state
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.io.recording import LabeledTrajectories
from service.labeling.loop import WindowLabels
from service.labeling.outcome import WindowOutcome

HELD_MM = 1e-6  # a seen marker's state position is the point it took, exactly


def model_first_frame(model: SubjectModel, points: np.ndarray) -> tuple[MarkerState, np.ndarray]:
    """The first marker state and ``(N, 3)`` the named markers' points (NaN where unnamed).

    Raises:
        InputError: The model names no point of the first frame.
    """
    geometry = ModelGeometry.of(model)
    found = identify(geometry, points)
    try:
        state = model_start_state(geometry, found, points, REACQUISITION.lost_after)
    except ValueError as error:
        raise InputError(f"first frame ({len(points)} points): {error}") from None
    first = np.full((len(geometry.names), 3), np.nan)
    first[found.named] = points[found.point[found.named]]
    return state, first


@dataclass
class ModelChain:
    """A 3D-point chain whose unseen markers the model looks for at every template frame."""

    inner: Any  # CloudChain or Joint3dChain: pose, invert, assemble, views
    model: SubjectModel
    points: list[np.ndarray]

    def __post_init__(self) -> None:
        self._geometry = ModelGeometry.of(self.model)

    def pose(self, state: MarkerState, template: int, last: int) -> tuple[WindowProblem, Any]:
        return self.inner.pose(self._acquired(state, self.points[template]), template, last)

    def invert(self, solution: WindowSolution, inverse: Any) -> WindowLabels:
        labels: WindowLabels = self.inner.invert(solution, inverse)
        return labels

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        result: LabeledTrajectories = self.inner.assemble(outcomes)
        return result

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        views: np.ndarray = self.inner.views(outcomes)
        return views

    def _acquired(self, state: MarkerState, points: np.ndarray) -> MarkerState:
        unseen = ~state.visible
        if not unseen.any() or len(points) == 0:
            return state
        found = identify(self._geometry, points)
        held = np.zeros(len(points), bool)
        if state.visible.any():
            gap = np.linalg.norm(points[:, None] - state.position[state.visible][None], axis=2)
            held = (gap <= HELD_MM).any(axis=1)
        new = np.flatnonzero(unseen & found.named)
        new = new[~held[found.point[new]]]
        if not len(new):
            return state
        return acquire(state, new, points[found.point[new]])
