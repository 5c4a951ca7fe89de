"""Label an unlabeled 3D point cloud recording window by window.

The per-window chain: points --cloud_candidates--> WindowCandidates --build_window-->
WindowProblem --formulation--> WindowSolution --invert--> point index per marker and
frame; the labeled last frame becomes the next window's template.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from formulations.errors import FormulationError
from formulations.markers.cloud_candidates import CloudGating, CloudWindow, cloud_candidates
from formulations.markers.guide import assign_nearest
from formulations.markers.state import MarkerState
from formulations.methods.formulation import Formulation
from formulations.methods.registry import get_formulation
from formulations.relaxation.components import coupled_components
from formulations.window.build import build_window
from formulations.window.costs import ArcCostWeights
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.io.recording import LabeledTrajectories, UnlabeledCloud
from service.labeling.outcome import WindowOutcome
from service.labeling.spans import window_spans
from service.labeling.stats import WindowStats

MARKER_COSTS = ArcCostWeights(
    appearance_change=0.0, displacement=1.0, reappear=15.0, disappear=15.0, template_on_track=0.3
)


@dataclass
class CloudLabeler:
    """Names every marker of an unlabeled cloud, given the labeled first frame.

    Attributes:
        formulation: Name or instance of the window formulation.
        window: Frames per window, template included (Jiang II-E).
        gating: Gates and the template term of the candidates.
        weights: Arc cost weights (mm-based for markers).
        layout_weight: mu of the L1 layout term (0 disables it).
        layout_neighbours: Layout pairs join each marker to this many of its most rigid
            neighbours (lowest distance variance), and only where the two markers are
            already coupled by shared candidates: the term then breaks ties between
            markers that compete for points without merging independent components.
    """

    formulation: str | Formulation = "lp-l1"
    window: int = 20
    gating: CloudGating = field(default_factory=CloudGating)
    weights: ArcCostWeights = MARKER_COSTS
    layout_weight: float = 0.0
    layout_neighbours: int = 2

    def label(
        self, cloud: UnlabeledCloud, names: list[str], first_frame: np.ndarray,
        progress: Callable[[int, int], None] | None = None,
        observer: Callable[[int, WindowProblem, WindowSolution], None] | None = None,
    ) -> tuple[LabeledTrajectories, list[WindowStats]]:
        """Label ``cloud``; ``first_frame`` is ``(markers, 3)``, the labeled frame 0.

        Args:
            cloud: The unlabeled points.
            names: Marker names.
            first_frame: ``(markers, 3)`` labeled positions of frame 0.
            progress: Called with (windows done, windows) after each window.
            observer: Called with (template frame, problem, solution) after each window.
        """
        outcomes = []
        n_windows = len(window_spans(cloud.n_frames, self.window))
        for outcome in self.windows(cloud, names, first_frame, observer=observer):
            outcomes.append(outcome)
            if progress:
                progress(outcome.index + 1, n_windows)
        return self.assemble(cloud, names, first_frame, outcomes), [o.stats for o in outcomes]

    def windows(
        self, cloud: UnlabeledCloud, names: list[str], first_frame: np.ndarray,
        after: WindowOutcome | None = None,
        observer: Callable[[int, WindowProblem, WindowSolution], None] | None = None,
    ) -> Iterator[WindowOutcome]:
        """Label window by window, yielding each outcome as it is finished.

        Args:
            after: The last finished window of an interrupted run: labeling resumes with
                the next window from its marker state, and gives exactly what an
                uninterrupted run would.
        """
        formulation = self._formulation()
        state = first_marker_state(names, first_frame) if after is None else after.state
        spans = window_spans(cloud.n_frames, self.window)
        for k in range(0 if after is None else after.index + 1, len(spans)):
            start, last = spans[k]
            window_points = cloud.points[start + 1 : last + 1]
            began = time.perf_counter()
            window_resources = cloud.resources[start + 1 : last + 1] if cloud.resources is not None else None
            gated = cloud_candidates(state, window_points, self.gating, window_resources)
            problem, node_candidate = build_window(gated.candidates, self.weights)
            if self.layout_weight > 0:
                problem = _with_layout(problem, state, self.layout_neighbours, self.layout_weight)
            prepared = time.perf_counter() - began
            solution = _solve(formulation, problem, start)
            taken = _taken_points(gated, node_candidate, solution)
            state, filled = _advance(state, window_points, taken)
            stats = WindowStats.of(start, last, solution, prepared, time.perf_counter() - began)
            if observer:
                observer(start, problem, solution)
            yield WindowOutcome(index=k, point_index=taken.T, filled=filled, stats=stats, state=state)

    def assemble(
        self, cloud: UnlabeledCloud, names: list[str], first_frame: np.ndarray, outcomes: list[WindowOutcome]
    ) -> LabeledTrajectories:
        """The labeled trajectories from every window's outcome, in order."""
        n, frames = len(names), cloud.n_frames
        point_index = np.full((frames, n), -1)
        point_index[0] = self._match_first_frame(cloud.points[0], np.asarray(first_frame, dtype=float))
        filled = np.full((frames, n, 3), np.nan)
        for outcome in outcomes:
            rows = slice(outcome.stats.template + 1, outcome.stats.last + 1)
            point_index[rows], filled[rows] = outcome.point_index, outcome.filled
        return _trajectories(cloud, names, point_index, filled)

    def _formulation(self) -> Formulation:
        try:
            return get_formulation(self.formulation)
        except FormulationError as error:
            raise InputError(str(error)) from None

    def _match_first_frame(self, points: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """The first frame's point of each labeled marker (the user labeled frame 0)."""
        radius = self.gating.gate.radius_mm
        return assign_nearest(positions, points, np.full(len(positions), radius), miss_cost=radius)


def first_marker_state(names: list[str], first_frame: np.ndarray) -> MarkerState:
    """The marker state of the user's labeled first frame.

    Raises:
        InputError: Wrong shape, or a marker without a position.
    """
    first_frame = np.asarray(first_frame, dtype=float)
    if first_frame.shape != (len(names), 3):
        raise InputError(f"first frame must give (x, y, z) for each of the {len(names)} markers")
    bad = np.flatnonzero(~np.isfinite(first_frame).all(axis=1))
    if len(bad):
        raise InputError(f"marker '{names[bad[0]]}' has no position in the first frame")
    return MarkerState.from_first_frame(first_frame)


def _solve(formulation: Formulation, problem: WindowProblem, template: int) -> WindowSolution:
    """A formulation that cannot take this window is the user's choice to revisit: one line."""
    try:
        return formulation.solve(problem)
    except FormulationError as error:
        raise InputError(f"window from frame {template}: {error}") from None


def _taken_points(gated: CloudWindow, node_candidate: np.ndarray, solution: WindowSolution) -> np.ndarray:
    """``(N, M)`` point index taken by each marker in each window frame, -1 if occluded."""
    candidate = node_candidate[solution.path]
    return np.where(candidate >= 0, gated.point[np.maximum(candidate, 0)], -1)


def _advance(state: MarkerState, frames: list[np.ndarray], taken: np.ndarray) -> tuple[MarkerState, np.ndarray]:
    """Carry the marker state through the labeled frames to the next template.

    Returns:
        The state at the last frame, and ``(M, N, 3)`` the predicted position of every
        marker in every frame where it was occluded (NaN where it was seen): the fill.
    """
    filled = np.full((len(frames),) + state.position.shape, np.nan)
    for m, points in enumerate(frames):
        seen = taken[:, m] >= 0
        observed = np.zeros((len(seen), 3))
        observed[seen] = points[taken[seen, m]]
        state = state.advance(observed, seen)
        filled[m, ~seen] = state.position[~seen]
    return state, filled


def _with_layout(problem: WindowProblem, state: MarkerState, per_marker: int, mu: float) -> WindowProblem:
    """The problem with layout pairs between rigid neighbours already coupled by conflicts."""
    rigid = np.take_along_axis(state.neighbours, np.argsort(state.distance_var, axis=1)[:, :per_marker], axis=1)
    pairs = np.column_stack([np.repeat(np.arange(len(rigid)), rigid.shape[1]), rigid.ravel()])
    pairs = np.unique(np.sort(pairs, axis=1), axis=0)
    component = coupled_components(problem)
    pairs = pairs[component[pairs[:, 0]] == component[pairs[:, 1]]]
    return replace(problem, layout_pairs=pairs, layout_weight=np.full(len(pairs), mu))


def _trajectories(cloud: UnlabeledCloud, names: list[str], point_index: np.ndarray, filled: np.ndarray) -> LabeledTrajectories:
    positions = np.full(point_index.shape + (3,), np.nan)
    for f, points in enumerate(cloud.points):
        seen = point_index[f] >= 0
        positions[f, seen] = points[point_index[f, seen]]
    return LabeledTrajectories(
        names=list(names), positions=positions, occluded=point_index < 0, rate=cloud.rate, point_index=point_index,
        filled=filled,
    )
