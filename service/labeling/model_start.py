"""Labeling with a subject model: identification at the start, the model's segments throughout.

The capture's frame 0 is identified (``formulations.subject.identify``), or, when the user
labeled it, taken as labeled with the model naming only what the labels leave out; either
start builds the marker state of ``model_start_state`` (segment-mates as neighbours).
Before each window, at its template frame:

- acquisition: markers unseen there are looked for again; a point the model names for such a
  marker, that no seen marker holds, becomes its position (``acquire``), so a marker absent
  at the start is named when it appears, within one window; not from a segment whose
  reading moves one of its seen markers (``agreeing``);
- recovery: segments whose labels contradict their constellation are re-read from the model
  (``recover``) instead of carrying the error forward;
- prediction: unseen markers are anchored to their segments' poses (``follow_segments``),
  so the window's gates are centred where the segment puts them;
- layout: with a layout weight, the pairs are segment-mates (``segment_layout``).

After each window, an occluded marker's fill is where its segment's pose in that frame puts
it (``segment_poses``: three labeled markers on the segment, else the joint chain); the
inner chain's fill stays where the model poses nothing (single markers, unposed segments).

With the user's labels kept (``steer`` False) only acquisition runs, and the take is labeled
as without a model otherwise (``CaptureLabeling``: its second pass too; the start state keeps
segment-mates as neighbours where the labels fit the segment): the labels already name what
they name, and a model fitted where the subject barely moved lumps segments whose recovery
and following carry labeled markers wrongly (03_rolling from frame 562, a model of frames
0-561: 59.50 % steered, 82.88 % acquiring only; docs/subject-model.md).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cache, partial
from typing import Any

import numpy as np

from formulations.markers.guide import assign_nearest
from formulations.markers.reacquire import REACQUISITION
from formulations.markers.state import MarkerState
from formulations.relaxation.components import coupled_components
from formulations.subject.agreement import agreeing
from formulations.subject.follow import follow_segments
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import Identification, identify
from formulations.subject.labeled_reading import labeled_readings
from formulations.subject.model import SubjectModel
from formulations.subject.recover import point_holders, recover
from formulations.subject.segment_fill import segment_fill
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses
from formulations.subject.start_state import acquire, model_start_state
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.capture.capture import Capture, LabelingOptions
from service.errors import InputError
from service.io.recording import LabeledTrajectories
from service.labeling.associations import Association, association_chain
from service.labeling.loop import WindowLabels
from service.labeling.outcome import WindowOutcome

LABEL_GATE_MM = 60.0  # a labeled first-frame position takes the point within this of it


def model_first_frame(
    model: SubjectModel, points: np.ndarray, labeled: np.ndarray | None = None, misfit: frozenset[str] = frozenset(),
) -> tuple[MarkerState, np.ndarray]:
    """The first marker state and ``(N, 3)`` the named markers' points (NaN where unnamed).

    ``labeled`` ``(N, 3)`` (model order, NaN where not labeled) are the user's labels of this
    frame: they are kept, and the model names only the markers they leave out; ``misfit`` the
    segments they contradict (``model_start_state``).

    Raises:
        InputError: The model names no point of the first frame.
    """
    geometry = ModelGeometry.of(model)
    found = identify(geometry, points)
    if labeled is not None and np.isfinite(labeled).all(axis=1).any():
        found = _with_labels(geometry, found, points, np.asarray(labeled, dtype=float))
    try:
        state = model_start_state(geometry, found, points, REACQUISITION.lost_after, misfit=misfit)
    except ValueError as error:
        hint = "; start where the subject is in view (track --start, or an upload's start=)" if len(points) < 3 else ""
        raise InputError(f"the start frame ({len(points)} points): {error}{hint}") from None
    first = np.full((len(geometry.names), 3), np.nan)
    first[found.named] = points[found.point[found.named]]
    return state, first


def model_chains(
    capture: Capture, model: SubjectModel, first_frame: np.ndarray, options: LabelingOptions, look_ahead: bool,
    labeled: bool,
) -> tuple[Association, Association]:
    """The window chain of a 3D-point ``capture`` with a model, named at its start as in
    ``first_frame``, and the chain its frame-by-frame reading (``rival_reading``) takes.

    With the user's labels kept (``labeled``) the model only names (``steer`` False) and the reading is one
    without a model. Identified, both are steered: read without the model, a take the model
    started is read from a state it cannot follow (second halves from a model of the first,
    ``bench/model_start.py``: 03_rolling 44.81 against 60.87 % steered, BTS 93.74 against 99.41).
    """
    points = list(capture.points or [])
    named = replace(capture, first_frame=first_frame)
    windows = ModelChain(association_chain(named, options, look_ahead), model, points, steer=not labeled)
    if labeled:
        return windows, association_chain(capture, options, look_ahead=False)
    return windows, ModelChain(association_chain(named, options, look_ahead=False), model, points)


def _with_labels(geometry: ModelGeometry, found: Identification, points: np.ndarray, labeled: np.ndarray) -> Identification:
    """The user's labels, and the identification's names for the markers they leave out."""
    given = np.isfinite(labeled).all(axis=1)
    point = np.full(len(given), -1, dtype=np.int64)
    point[given] = assign_nearest(labeled[given], points, np.full(int(given.sum()), LABEL_GATE_MM), LABEL_GATE_MM)
    free = ~given & found.named & ~np.isin(found.point, point[point >= 0])
    point[free] = found.point[free]
    positions = np.where((point >= 0)[:, None], points[np.maximum(point, 0)], np.nan)
    placed = segment_poses(geometry, positions[None]).place(geometry)[0]
    residual = np.linalg.norm(placed - positions, axis=1)
    return Identification(point, np.where(point >= 0, residual, np.nan), placed)


@dataclass
class ModelChain:
    """A 3D-point chain that the subject model steers at every template frame (see the module)."""

    inner: Any  # CloudChain or Joint3dChain: pose, invert, assemble, views
    model: SubjectModel
    points: list[np.ndarray]
    steer: bool = True  # recovery, segment-following, layout and fill; False: acquisition only

    def __post_init__(self) -> None:
        self._geometry = ModelGeometry.of(self.model)
        self.repaired: list[tuple[int, int]] = []  # (template frame, segment) re-read by recovery

    def pose(
        self, state: MarkerState, template: int, last: int, confidence: np.ndarray | None = None,
    ) -> tuple[WindowProblem, Any]:
        """As ``WindowChain.pose``, the model steering first (module doc). The inner chain's
        exchange repair keeps its full bar, ``confidence`` left out: the model's recovery
        re-reads contradicted segments, and lowering the bar for doubtful labels as well cost
        the refused real takes' model starts (``bench/model_start.py``): basket sprint 83.4 ->
        62.0 % (its arm, forearm and wheel carry identical marker plates, which fit each
        other's places), 03_rolling 40.3 -> 37.8 %, racing 80.3 -> 80.1 %."""
        points = self.points[template]
        found = cache(partial(identify, self._geometry, points))  # recovery's, only when a segment contradicts
        state = self._acquired(state, points)
        if not self.steer:
            return self.inner.pose(state, template, last)
        state, repaired = recover(self._geometry, state, points, found)
        self.repaired.extend((template, s) for s in repaired)
        problem, inverse = self.inner.pose(follow_segments(self._geometry, state), template, last)
        mu = float(getattr(self.inner, "layout_weight", 0.0))
        if mu > 0:
            problem = segment_layout(problem, self._geometry.segment_of, mu)
        return problem, (inverse, state, template)

    def invert(self, solution: WindowSolution, inverse: Any) -> WindowLabels:
        if not self.steer:
            return self.inner.invert(solution, inverse)
        inner, state, template = inverse
        labels: WindowLabels = self.inner.invert(solution, inner)
        return replace(labels, filled=self._filled(labels, state, template))

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        result: LabeledTrajectories = self.inner.assemble(outcomes)
        return result

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        views: np.ndarray = self.inner.views(outcomes)
        return views

    def _filled(self, labels: WindowLabels, state: MarkerState, template: int) -> np.ndarray:
        """The inner fill, replaced wherever the segment carries the marker (``segment_fill``)."""
        taken = labels.point_index  # (M, N)
        positions = np.full(taken.shape + (3,), np.nan)
        for m, row in enumerate(taken):
            seen = row >= 0
            positions[m, seen] = self.points[template + 1 + m][row[seen]]
        template_positions = np.where(state.visible[:, None], state.position, np.nan)[None]
        placed = segment_fill(self._geometry, state, np.concatenate([template_positions, positions]), RIGID_WITHIN)
        return np.where(np.isfinite(placed[1:]), placed[1:], labels.filled)

    def _acquired(self, state: MarkerState, points: np.ndarray, found: Identification | None = None) -> MarkerState:
        """Unseen markers named in the template's cloud by ``found``: by default an identification
        that searches only for the segments with a marker unseen, the others read from their
        labels where those fit (``labeled_reading``), and none at all when seen markers hold
        every point (a marker is acquired only on a free point; 03_rolling with labels kept:
        half its windows' template frames, the search most of the labeling's time)."""
        unseen = ~state.visible
        if not unseen.any() or len(points) == 0:
            return state
        holder = point_holders(state, points)  # (P,) the seen marker on each point, -1 none
        held = holder >= 0
        if held.all():  # a marker is acquired only on a point no seen marker holds
            return state
        point_of = np.full(len(unseen), -1, dtype=np.int64)  # (N,) the point each seen marker holds
        point_of[holder[held]] = np.flatnonzero(held)
        if found is None:
            found = identify(self._geometry, points, labeled_readings(self._geometry, point_of, points))
        new = np.flatnonzero(unseen & found.named & agreeing(self._geometry, state, points, found))
        new = new[~held[found.point[new]]]
        if not len(new):
            return state
        return acquire(state, new, points[found.point[new]])


def segment_layout(problem: WindowProblem, segment_of: np.ndarray, mu: float) -> WindowProblem:
    """The problem with layout pairs between markers of one segment that shared candidates couple.

    A rigid segment keeps its markers' layout; two markers of different segments need not,
    however close (Ringer & Lasenby's grouping, in place of the nearest neighbours).
    """
    n = len(segment_of)
    first, second = np.triu_indices(n, k=1)
    pairs = np.column_stack([first, second])
    pairs = pairs[(segment_of[first] == segment_of[second]) & (segment_of[first] >= 0)]
    problem = replace(problem, layout_pairs=np.zeros((0, 2), dtype=int), layout_weight=np.zeros(0))
    component = coupled_components(problem)
    pairs = pairs[component[pairs[:, 0]] == component[pairs[:, 1]]]
    return replace(problem, layout_pairs=pairs, layout_weight=np.full(len(pairs), mu))
