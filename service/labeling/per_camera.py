"""``per-camera`` association: track each marker in each camera's image, then triangulate.

Per window (the same windows as ``CloudLabeler``, overlapping by their template frame):

    detections --per_camera_guide--> 3D guide track (where to look)
               --per_camera_candidates--> one 2D object per (camera, marker)
               --build_window / formulation--> a detection per object and frame (Jiang)
               --locate_markers--> triangulated markers, views that disagree dropped,
                                   a second view searched for markers left with one

and the located markers advance the 3D marker state frame by frame to the next template.
A marker seen by two or more agreeing cameras is triangulated; by one, it lies on that
camera's ray nearest its prediction; by none, it is the prediction, flagged as filled.

The first frame has no prediction: the user labels it (names + 3D positions, as in
Ringer & Lasenby 2004), and its positions are the labeled ones.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from formulations.cameras.per_camera.advance import advance_state
from formulations.cameras.per_camera.candidates import per_camera_candidates
from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.guide import per_camera_guide
from formulations.cameras.per_camera.locate import FrameViews
from formulations.cameras.per_camera.reacquire import locate_with_reacquisition
from formulations.cameras.rig import Rig
from formulations.errors import FormulationError
from formulations.markers.state import MarkerState
from formulations.methods.formulation import Formulation
from formulations.methods.registry import get_formulation
from formulations.window.build import build_window
from formulations.window.costs import ArcCostWeights
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.capture.capture import Capture
from service.errors import InputError
from service.io.recording import LabeledTrajectories
from service.labeling.cloud import MARKER_COSTS, first_marker_state
from service.labeling.outcome import WindowOutcome
from service.labeling.spans import window_spans
from service.labeling.stats import WindowStats


@dataclass
class PerCameraLabeler:
    """Names every marker of a camera capture from its labeled first frame, camera by camera.

    Attributes:
        formulation: Name or instance of the window formulation.
        window: Frames per window, template included.
        gating: Gates, template-term weights and the cross-camera reprojection limit.
        weights: Arc cost weights, per mm of image-plane motion at the marker's depth:
            the 3D labeler's (``MARKER_COSTS``), since the image-plane locations are mm.
    """

    formulation: str | Formulation = "lp-l1"
    window: int = 20
    gating: PerCameraGating = field(default_factory=PerCameraGating)
    weights: ArcCostWeights = MARKER_COSTS

    def windows(self, capture: Capture, after: WindowOutcome | None = None) -> Iterator[WindowOutcome]:
        """Label window by window, yielding each outcome as it is finished.

        Args:
            capture: A camera capture.
            after: The last finished window of an interrupted run: labeling resumes with
                the next window from its marker state, as an uninterrupted run would.
        """
        formulation = self._formulation()
        rig, detections = Rig.of(capture.cameras), capture.detections
        state = first_marker_state(capture.names, capture.first_frame) if after is None else after.state
        spans = window_spans(capture.n_frames, self.window)
        for k in range(0 if after is None else after.index + 1, len(spans)):
            start, last = spans[k]
            began = time.perf_counter()
            frames = _undistorted(rig, detections[start + 1 : last + 1])
            guide = per_camera_guide(state, rig, frames, self.gating)
            gated = per_camera_candidates(state, rig, guide, frames, self.gating)
            problem, node_candidate = build_window(gated.candidates, self.weights)
            prepared = time.perf_counter() - began
            solution = _solve(formulation, problem, start)
            views = gated.views(node_candidate, solution.path)
            state, views, positions, filled = _advance(state, rig, frames, views, self.gating)
            stats = WindowStats.of(start, last, solution, prepared, time.perf_counter() - began)
            yield WindowOutcome(
                index=k, point_index=np.zeros((len(frames), 0), dtype=int), filled=filled, stats=stats,
                state=state, views=views, positions=positions,
            )

    def assemble(self, capture: Capture, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        """The labeled trajectories from every window's outcome, in order (no point identities)."""
        positions = np.full((capture.n_frames, len(capture.names), 3), np.nan)
        positions[0] = capture.first_frame
        filled = np.full_like(positions, np.nan)
        for outcome in outcomes:
            rows = slice(outcome.stats.template + 1, outcome.stats.last + 1)
            positions[rows], filled[rows] = outcome.positions, outcome.filled
        return LabeledTrajectories(
            names=list(capture.names), positions=positions, occluded=np.isnan(positions).any(axis=2),
            rate=capture.rate, filled=filled,
        )

    def views(self, capture: Capture, outcomes: list[WindowOutcome]) -> np.ndarray:
        """``(F, N, C)`` detection each marker took in each camera, -1 for none (frame 0: none)."""
        views = np.full((capture.n_frames, len(capture.names), len(capture.cameras)), -1)
        for outcome in outcomes:
            views[outcome.stats.template + 1 : outcome.stats.last + 1] = outcome.views
        return views

    def _formulation(self) -> Formulation:
        try:
            return get_formulation(self.formulation)
        except FormulationError as error:
            raise InputError(str(error)) from None


def _solve(formulation: Formulation, problem: WindowProblem, template: int) -> WindowSolution:
    """A formulation that cannot take this window is the user's choice to revisit: one line."""
    try:
        return formulation.solve(problem)
    except FormulationError as error:
        raise InputError(f"window from frame {template}: {error}") from None


def _undistorted(rig: Rig, pixels: list[list[np.ndarray]]) -> list[FrameViews]:
    """The window's detections with their normalised coordinates, one undistortion per camera."""
    pixels = [[np.asarray(found, dtype=float).reshape(-1, 2) for found in frame] for frame in pixels]
    counts = np.array([[len(found) for found in frame] for frame in pixels], dtype=int).reshape(len(pixels), len(rig))
    normalised = [
        np.split(camera.undistort(np.concatenate([frame[c] for frame in pixels]).reshape(-1, 2)), np.cumsum(counts[:-1, c]))
        for c, camera in enumerate(rig.cameras)
    ]
    return [
        FrameViews(pixels=list(frame), normalised=[normalised[c][m] for c in range(len(rig))])
        for m, frame in enumerate(pixels)
    ]


def _advance(
    state: MarkerState, rig: Rig, frames: list[FrameViews], views: np.ndarray, gating: PerCameraGating,
) -> tuple[MarkerState, np.ndarray, np.ndarray, np.ndarray]:
    """Locate the markers frame by frame from the chosen views and carry the state along.

    A marker counts as seen by the state only when two or more cameras agree on it: one
    view fixes two of its three coordinates, and a velocity measured along the unseen
    one would drift; the rigid motion of its neighbours carries it instead.

    Returns:
        The state at the last frame; ``(M, N, C)`` the views kept; ``(M, N, 3)`` the
        located positions (NaN where no view); ``(M, N, 3)`` the prediction where no view
        (the fill, NaN elsewhere).
    """
    kept = np.full_like(views, -1)
    positions, filled = np.full(views.shape[:2] + (3,), np.nan), np.full(views.shape[:2] + (3,), np.nan)
    for m, frame in enumerate(frames):
        located, kept[m] = locate_with_reacquisition(rig, frame, views[m], state, state.predict(), gating)
        seen = located.n_views > 0
        positions[m, seen], filled[m, ~seen] = located.point[seen], located.point[~seen]
        state = advance_state(state, located)
    return state, kept, positions, filled
