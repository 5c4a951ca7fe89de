"""Label an unlabeled 3D point cloud window by window: the cloud association's chain.

The per-window chain (run by ``service.labeling.loop``):

    pose:    points --cloud_candidates--> WindowCandidates --build_window--> WindowProblem
    invert:  WindowSolution --node -> candidate -> point--> point index per marker and frame,
             and the marker state carried through the labeled frames to the next template.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from formulations.confidence.lone import lone_labels
from formulations.markers.cloud_candidates import CloudGating, CloudWindow, cloud_candidates
from formulations.markers.coexistence import BackLinks, coexisted
from formulations.markers.exchange import continued_points, repair_exchanges
from formulations.markers.guide import assign_nearest
from formulations.markers.lengths import lengths
from formulations.markers.mirror import repair_mirrors
from formulations.markers.pair_evidence import repair_pair_evidence
from formulations.markers.state import MarkerState
from formulations.markers.turns import repair_turns, rigid_triples
from formulations.markers.unnamed import MIN_BIRTH_POINTS, WindowSurround, chain_radii
from formulations.relaxation.components import coupled_components
from formulations.window.build import build_window, taken_candidates
from formulations.window.costs import ArcCostWeights
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.io.recording import LabeledTrajectories, UnlabeledCloud
from service.labeling.loop import WindowLabels
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import DOUBTFUL_BELOW

# Jiang's weighted costs for markers: the per-camera chain prices its arcs with them. Cloud
# candidates carry negative log-likelihoods (``formulations.markers.likelihood``), which
# replace every weight here but ``template_on_track`` (the shape term's factor on a step).
# 0.3 was set by hand; 0.1 loses (2026-12-07): seed-0 matrix 98.194 / 99.352 -> 98.034 / 99.047 %
# (tuning / validation), 6 rows up and 15 down, and every real take it changes (03_rolling
# 89.74 -> 77.69 %, the basket sprint 93.27 -> 87.56 %); 0.6 lost the real 03_rolling on
# 2026-11-28 (79.54 -> 74.32 %). docs/how-a-window-is-solved.md.
MARKER_COSTS = ArcCostWeights(
    appearance_change=0.0, displacement=1.0, reappear=15.0, disappear=15.0, template_on_track=0.3
)


@dataclass(frozen=True)
class CloudInverse:
    """What inverting a cloud window needs: the state it was posed from, its points, its candidates."""

    state: MarkerState
    frames: list[np.ndarray]
    gated: CloudWindow
    node_candidate: np.ndarray
    doubtful: np.ndarray


@dataclass
class CloudChain:
    """Names every marker of an unlabeled cloud, given the labeled first frame.

    Attributes:
        cloud: The unlabeled points.
        names: Marker names.
        first_frame: ``(markers, 3)`` labeled positions of frame 0.
        gating: Gates and the template term of the candidates.
        weights: Arc cost weights (mm-based for markers).
        layout_weight: mu of the L1 layout term (0 disables it).
        layout_neighbours: Layout pairs join each marker to this many of its most rigid
            neighbours (lowest distance variance), and only where the two markers are
            already coupled by shared candidates: the term then breaks ties between
            markers that compete for points without merging independent components.
        unnamed_markers: Markers of the take not named (absent from the labeled frame): an
            unnamed track may be born before any is seen (``markers.unnamed``).
    """

    cloud: UnlabeledCloud
    names: list[str]
    first_frame: np.ndarray
    gating: CloudGating = field(default_factory=CloudGating)
    weights: ArcCostWeights = MARKER_COSTS
    layout_weight: float = 0.0
    layout_neighbours: int = 2
    unnamed_markers: int = 0

    def pose(
        self, state: MarkerState, template: int, last: int, confidence: np.ndarray | None = None,
    ) -> tuple[WindowProblem, CloudInverse]:
        state, coexisting = self._exchanges_repaired(state, template, confidence)
        state, _ = repair_mirrors(state, np.asarray(self.first_frame, dtype=float))
        frames = self.cloud.points[template + 1 : last + 1]
        resources = self.cloud.resources[template + 1 : last + 1] if self.cloud.resources is not None else None
        # the repair's judgement of the free points serves the window's unnamed tracks: a
        # marker it moved is seen now, and those are barred from a seeded track anyway
        around = replace(self._around(template, last), coexisting=coexisting)
        gated = cloud_candidates(state, frames, self.gating, resources, around)
        problem, node_candidate = build_window(gated.candidates, self.weights)
        if self.layout_weight > 0:
            problem = _with_layout(problem, state, self.layout_neighbours, self.layout_weight)
        doubtful = np.zeros(len(state.position), bool) if confidence is None else confidence < DOUBTFUL_BELOW
        return problem, CloudInverse(state, frames, gated, node_candidate, doubtful)

    def invert(self, solution: WindowSolution, inverse: CloudInverse) -> WindowLabels:
        taken = taken_candidates(inverse.node_candidate, solution.path, inverse.gated.point)  # (N + U, M), -1 occluded
        taken = taken[: len(inverse.state.position)]  # the unnamed tracks' points stay unlabeled
        triples, symmetric = rigid_triples(inverse.state)
        taken, _, plates = repair_turns(inverse.state, inverse.frames, taken, triples, symmetric)
        taken, _ = repair_pair_evidence(inverse.state, inverse.frames, taken, inverse.doubtful)
        state, filled = _advance(inverse.state, inverse.frames, taken)
        state = plates.remembered(state, triples, len(inverse.frames))
        return WindowLabels(state=state, point_index=taken.T, filled=filled)

    def _exchanges_repaired(self, state: MarkerState, template: int, confidence: np.ndarray | None,
                            ) -> tuple[MarkerState, np.ndarray]:
        """``repair_exchanges`` at the template, an unseen marker taking only free points the
        next frame continues within the unnamed tracks' one-frame reach (``chain_radii``)
        and none whose track it was seen apart from; and that ``(N, K)`` judgement over the
        template's points (False on the points seen markers hold)."""
        points = self.cloud.points[template]
        free = _unclaimed(points, state)
        continued = None
        if template + 1 < self.cloud.n_frames:
            continued = continued_points(points[free], self.cloud.points[template + 1], chain_radii(state, self.gating.gate)[0])
        coexisting = np.zeros((len(state.position), len(points)), bool)
        coexisting[:, free] = self._coexisting(state, template, points[free], confidence)
        repaired, _ = repair_exchanges(state, points[free], confidence, continued, coexisting[:, free])
        return repaired, coexisting

    def _coexisting(self, state: MarkerState, template: int, points: np.ndarray, confidence: np.ndarray | None,
                    ) -> np.ndarray:
        """``(N, P)``: marker n, unseen, was last seen apart from the track of point p of the
        template frame (``coexistence``), its label then not doubtful."""
        # a doubtful marker's last point may not have been its own
        judged = np.isfinite(state.seen_at).all(axis=1) & (True if confidence is None else confidence >= DOUBTFUL_BELOW)
        lost_for = int(state.unseen[judged].max(initial=0))
        if lost_for == 0 or not len(points):
            return np.zeros((len(state.position), len(points)), bool)
        reach, link_radius = chain_radii(state, self.gating.gate)
        tracks = self._back_links.back_tracks(points, template, min(lost_for, template), reach, link_radius)
        return coexisted(state.unseen, state.seen_at, tracks) & judged[:, None]

    @cached_property
    def _back_links(self) -> BackLinks:
        """The take's points followed back, kept from window to window (``_coexisting``)."""
        return BackLinks(self.cloud.points)

    def _around(self, template: int, last: int) -> WindowSurround:
        """The points next to the window, for its unnamed tracks (``markers.unnamed``)."""
        before = self.cloud.points[template - 1] if template > 0 else np.zeros((0, 3))
        after = self.cloud.points[last + 1 : last + MIN_BIRTH_POINTS]
        return WindowSurround(self.cloud.points[template], before, after, self.unnamed_markers)

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        """The labeled trajectories from every window's outcome, in order."""
        n, frames = len(self.names), self.cloud.n_frames
        point_index = np.full((frames, n), -1)
        point_index[0] = self._match_first_frame(self.cloud.points[0], np.asarray(self.first_frame, dtype=float))
        filled = np.full((frames, n, 3), np.nan)
        for outcome in outcomes:
            rows = slice(outcome.stats.template + 1, outcome.stats.last + 1)
            point_index[rows], filled[rows] = outcome.point_index, outcome.filled
        return _trajectories(self.cloud, self.names, point_index, filled)

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        """3D points come from no camera (``Joint3dChain`` has the views of matched points)."""
        raise InputError("a capture of 3D points has no camera views")

    def _match_first_frame(self, points: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """The first frame's point of each labeled marker (the user labeled frame 0)."""
        radius = self.gating.gate.radius_mm
        return assign_nearest(positions, points, np.full(len(positions), radius), miss_cost=radius)


def _unclaimed(points: np.ndarray, state: MarkerState) -> np.ndarray:
    """``(K,)`` True for the template frame's points that no visible marker holds."""
    held = state.position[state.visible]
    if len(points) == 0 or len(held) == 0:
        return np.ones(len(points), bool)
    nearest = np.min(lengths(points[:, None] - held[None]), axis=1)
    return np.asarray(nearest > 1e-6)


def _lone_sightings(taken: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """``(N, M)`` the labels of ``taken`` with none the frame before (``visible`` before the
    first) nor after (``lone_labels``); the window's last frame is never lone, as the next
    window may go on from it."""
    labeled = np.vstack([visible, (taken >= 0).T, np.ones(len(visible), bool)])
    lone: np.ndarray = lone_labels(labeled)[1:-1].T
    return lone


def _advance(state: MarkerState, frames: list[np.ndarray], taken: np.ndarray) -> tuple[MarkerState, np.ndarray]:
    """Carry the marker state through the labeled frames to the next template.

    A lone sighting (``_lone_sightings``) is kept as a label but carried as unseen: one point
    gives no step, and taken by a lost marker it is most often a ghost that would move the
    prediction later frames are gated by (CMU 135_02 with deletions: RSHN predicted 612 mm off
    its point after two such ghosts) and teach the drift and distances from it.

    Returns:
        The state at the last frame, and ``(M, N, 3)`` the predicted position of every
        marker in every frame where it was unlabeled (NaN where it was labeled): the fill.
    """
    lone = _lone_sightings(taken, state.visible)
    filled = np.full((len(frames),) + state.position.shape, np.nan)
    for m, points in enumerate(frames):
        seen = (taken[:, m] >= 0) & ~lone[:, m]
        observed = np.zeros((len(seen), 3))
        observed[seen] = points[taken[seen, m]]
        state = state.advance(observed, seen)
        unlabeled = taken[:, m] < 0
        filled[m, unlabeled] = state.position[unlabeled]
    if (taken >= 0).all():  # nothing to fill: a NaN seen as the window's shape, not 1 kB a frame kept per window
        filled = np.broadcast_to(np.nan, filled.shape)
    return state, filled


def _with_layout(problem: WindowProblem, state: MarkerState, per_marker: int, mu: float) -> WindowProblem:
    """The problem with layout pairs between rigid neighbours already coupled by conflicts."""
    rigid = np.take_along_axis(state.neighbours, np.argsort(state.distance_var, axis=1)[:, :per_marker], axis=1)
    pairs = np.column_stack([np.repeat(np.arange(len(rigid)), rigid.shape[1]), rigid.ravel()])
    pairs = np.unique(np.sort(pairs, axis=1), axis=0)
    component = coupled_components(problem)
    pairs = pairs[component[pairs[:, 0]] == component[pairs[:, 1]]]
    return replace(problem, layout_pairs=pairs, layout_weight=np.full(len(pairs), mu))


def _trajectories(
    cloud: UnlabeledCloud, names: list[str], point_index: np.ndarray, filled: np.ndarray
) -> LabeledTrajectories:
    positions = np.full(point_index.shape + (3,), np.nan)
    for f, points in enumerate(cloud.points):
        seen = point_index[f] >= 0
        positions[f, seen] = points[point_index[f, seen]]
    return LabeledTrajectories(
        names=list(names), positions=positions, occluded=point_index < 0, rate=cloud.rate, point_index=point_index,
        filled=filled,
    )
