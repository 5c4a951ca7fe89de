"""``per-camera`` association: track each marker in each camera's image, then triangulate.

The per-window chain (run by ``service.labeling.loop``, on the same windows as the cloud's):

    pose:    detections --per_camera_guide--> 3D guide track (where to look)
                        --per_camera_candidates--> one 2D object per (camera, marker)
                        --build_window--> WindowProblem
    invert:  WindowSolution --views--> a detection per object and frame (Jiang)
                            --locate_markers--> triangulated markers, views that disagree
                                dropped, a second view searched for markers left with one

and the located markers advance the 3D marker state frame by frame to the next template.
A marker seen by two or more agreeing cameras is triangulated; by one, it lies on that
camera's ray nearest its prediction; by none, it is the prediction, flagged as filled.

The first frame has no prediction: the user labels it (names + 3D positions, as in
Ringer & Lasenby 2004), and its positions are the labeled ones. Its views are the
detections nearest the labeled markers' projections (``first_frame_views``, within the
window gate of a marker seen the frame before): without them every camera looked blind in
frame 0, and the best view there was the first camera listed, carried into later frames.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from formulations.cameras.per_camera.advance import advance_state
from formulations.cameras.per_camera.candidates import PerCameraWindow, per_camera_candidates
from formulations.cameras.per_camera.first_frame import first_frame_views
from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.guide import per_camera_guide
from formulations.cameras.per_camera.locate import FrameViews
from formulations.cameras.per_camera.reacquire import locate_with_reacquisition
from formulations.cameras.per_camera.single_view import single_views_on_rays
from formulations.cameras.rig import Rig
from formulations.markers.state import MarkerState
from formulations.window.build import build_window
from formulations.window.costs import ArcCostWeights
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.io.recording import LabeledTrajectories
from service.labeling.cloud import MARKER_COSTS
from service.labeling.loop import WindowLabels
from service.labeling.outcome import WindowOutcome


@dataclass(frozen=True)
class PerCameraInverse:
    """What inverting a per-camera window needs: the state it was posed from, its views, its candidates."""

    state: MarkerState
    frames: list[FrameViews]
    gated: PerCameraWindow
    node_candidate: np.ndarray


@dataclass
class PerCameraChain:
    """Names every marker of a camera capture from its labeled first frame, camera by camera.

    Attributes:
        names: Marker names.
        first_frame: ``(N, 3)`` labeled positions of frame 0, mm.
        rate: Frames per second.
        rig: The calibrated cameras.
        detections: ``detections[f][c]``: ``(D, 2)`` pixels.
        gating: Gates, template-term weights and the cross-camera reprojection limit.
        weights: Arc cost weights, per mm of image-plane motion at the marker's depth:
            the 3D labeler's (``MARKER_COSTS``), since the image-plane locations are mm.
    """

    names: list[str]
    first_frame: np.ndarray
    rate: float
    rig: Rig
    detections: list[list[np.ndarray]]
    gating: PerCameraGating = field(default_factory=PerCameraGating)
    weights: ArcCostWeights = MARKER_COSTS

    def pose(
        self, state: MarkerState, template: int, last: int, confidence: np.ndarray | None = None,
    ) -> tuple[WindowProblem, PerCameraInverse]:
        """As ``WindowChain.pose``; ``confidence`` is not used: a camera's views carry no exchange repair."""
        frames = _undistorted(self.rig, self.detections[template + 1 : last + 1])
        guide = per_camera_guide(state, self.rig, frames, self.gating)
        gated = per_camera_candidates(state, self.rig, guide, frames, self.gating)
        problem, node_candidate = build_window(gated.candidates, self.weights)
        return problem, PerCameraInverse(state, frames, gated, node_candidate)

    def invert(self, solution: WindowSolution, inverse: PerCameraInverse) -> WindowLabels:
        views = inverse.gated.views(inverse.node_candidate, solution.path)
        state, views, positions, filled = _advance(inverse.state, self.rig, inverse.frames, views, self.gating)
        return WindowLabels(
            state=state, point_index=np.zeros((len(inverse.frames), 0), dtype=int), filled=filled, views=views,
            positions=positions,
        )

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        """The labeled trajectories from every window's outcome, in order (no point identities)."""
        positions = np.full((len(self.detections), len(self.names), 3), np.nan)
        positions[0] = self.first_frame
        filled = np.full_like(positions, np.nan)
        for outcome in outcomes:
            rows = slice(outcome.stats.template + 1, outcome.stats.last + 1)
            positions[rows], filled[rows] = outcome.positions, outcome.filled
        positions = self._single_views_placed(positions, filled, self.views(outcomes))
        return LabeledTrajectories(
            names=list(self.names), positions=positions, occluded=np.isnan(positions).any(axis=2),
            rate=self.rate, filled=filled,
        )

    def _single_views_placed(self, positions: np.ndarray, filled: np.ndarray, views: np.ndarray) -> np.ndarray:
        """Each marker-frame located from one view moved along its ray to where its rigid
        donors put it (``single_view``)."""
        single = ((views >= 0).sum(axis=2) == 1) & np.isfinite(positions).all(axis=2)
        single[:1] = False  # frame 0 is the user's, where it was labeled
        frame, marker = np.nonzero(single)
        camera = np.argmax(views[frame, marker] >= 0, axis=1)
        detection = views[frame, marker, camera]
        origin, direction = np.zeros((len(frame), 3)), np.zeros((len(frame), 3))
        for c, lens in enumerate(self.rig.cameras):
            rows = np.flatnonzero(camera == c)
            if len(rows):
                pixels = np.array([self.detections[frame[r]][c][detection[r]] for r in rows], dtype=float).reshape(-1, 2)
                origin[rows], direction[rows] = self.rig.centres[c], lens.direction(lens.undistort(pixels))
        return single_views_on_rays(positions, filled, single, origin, direction)

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        """``(F, N, C)`` detection each marker took in each camera, -1 for none (frame 0: the
        detections nearest the labeled markers' projections, module doc)."""
        views = np.full((len(self.detections), len(self.names), len(self.rig.cameras)), -1)
        if len(self.detections):
            first = _undistorted(self.rig, self.detections[:1])[0]
            views[0] = first_frame_views(self.rig, self.first_frame, first, self.gating.window_gate.radius_mm)
        for outcome in outcomes:
            views[outcome.stats.template + 1 : outcome.stats.last + 1] = outcome.views
        return views


def _undistorted(rig: Rig, window: list[list[np.ndarray]]) -> list[FrameViews]:
    """The window's detections with their normalised coordinates, one undistortion per camera."""
    pixels = [[np.asarray(found, dtype=float).reshape(-1, 2) for found in frame] for frame in window]
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
