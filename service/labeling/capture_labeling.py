"""Label a capture in any input mode, window by window, resumably.

This is the one entry point the CLI (``track``, ``eval``, ``demo``), the HTTP jobs and the
Dask workers share:

    labeling = CaptureLabeling(capture, LabelingOptions(formulation="ilp"))
    outcomes = []
    for outcome in labeling.windows(after=outcomes[-1] if outcomes else None):
        outcomes.append(outcome)  # persist it here to survive a crash
    result = labeling.result(labeling.refine(outcomes))  # refine: the second pass, as label() runs it

3D points are labeled by the window LP directly. Camera detections are either matched
across cameras first (``joint-3d``) into 3D points whose resources are their detections,
or tracked by the window LP in each camera's image and then triangulated (``per-camera``).
Each association is a chain (``service.labeling.loop``) with its own assembly; the window
loop, the formulation and the first marker state are the same for all.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from functools import partial

import numpy as np

from formulations.markers.gap_ends import tie_gap_ends
from formulations.markers.rigid_fill import rigid_fill, rigid_refill
from formulations.markers.shape_breaks import ShapeBreak
from formulations.markers.take_handover import Handover
from formulations.subject.contradiction import SegmentMisfit, labeled_misfits
from formulations.subject.geometry import ModelGeometry
from formulations.subject.joint_tracks import joint_tracks
from formulations.subject.pose_fill import pose_fill
from formulations.subject.take_learning import learn_from_take
from service.best_view.markers import MarkerViewChoice
from service.capture.capture import Capture, LabelingOptions
from service.capture.fingerprint import capture_fingerprint
from service.capture.formulation_spec import resolve_formulation
from service.errors import InputError
from service.io.recording import LabeledTrajectories
from service.labeling.associations import Association, association_chain
from service.labeling.camera_usage import detections_taken, unused_camera_warning
from service.labeling.exchanged import GivenBack, exchanged_back, handed_back
from service.labeling.extension import extended
from service.labeling.hypothesis_reading import hypothesis_reading, merged_with_hypotheses
from service.labeling.joint_3d import Joint3dChain
from service.labeling.leftover_points import with_leftover_points
from service.labeling.loop import Observer, Progress, first_marker_state, label_windows, progress_after
from service.labeling.model_start import model_chains, model_first_frame
from service.labeling.outcome import WindowOutcome, take_confidence
from service.labeling.outcome_fit import check_outcomes, check_resumable, stamped
from service.labeling.reported import as_reported
from service.labeling.result_warnings import result_warnings, time_limit_warning
from service.labeling.rival_process import READINGS, Beside, EarlyStart, runs_beside, started
from service.labeling.rival_reading import RivalChoice, RivalReading, merged_with_rival, read_frame_by_frame, rival_unread_reason
from service.labeling.second_pass import PassChoice, Stop, judged_part, second_pass, second_pass_runs
from service.labeling.spans import window_spans
from service.labeling.stats import WindowStats
from service.labeling.take_warnings import model_misfit_warning, refuse_wrong_scale, spacing_frame


class CaptureLabeling:
    """One capture's labeling: its windows, and the trajectories they assemble into.

    Args:
        capture: What to label.
        options: Formulation (name, table or instance), window size, association.

    Raises:
        InputError: Unknown formulation or parameter, bad window size, a first frame
            without a position for every marker, or an association that does not apply.
    """

    def __init__(self, capture: Capture, options: LabelingOptions = LabelingOptions()) -> None:
        if not capture.names:  # a capture may be built unnamed (``with_model`` then names it), not labeled so
            raise InputError("a capture to label needs at least one named marker (names is empty)")
        refuse_wrong_scale(spacing_frame(capture.first_frame, capture.points))
        self.formulation = resolve_formulation(options.formulation)
        self._spans = window_spans(capture.n_frames, options.window)
        self.n_windows = len(self._spans)
        self._capture, self._options, self._window = capture, options, options.window
        self.fingerprint = capture_fingerprint(capture)  # what its outcomes carry, so they resume only this take
        labeled = bool(np.isfinite(capture.first_frame).any())  # kept labels: the model only names (``ModelChain.steer``)
        self._second_pass = options.second_pass and capture.points is not None
        self.rival: RivalChoice | None = None  # what the frame-by-frame reading changed, when ``refine`` ran it
        self.hypotheses: RivalChoice | None = None  # what the ``mht`` reading changed after it, likewise
        self._points = capture.points  # a cloud's points, for the tracks' extension over those left free
        self.choice: PassChoice | None = None  # which pass ``refine`` kept
        self.exchanges: list[GivenBack] = []  # given back in the last labels assembled (``exchanged``)
        self.handovers: list[Handover] = []  # tracks given back to their owners, likewise
        self._view_choice = None if capture.cameras is None or capture.points is not None else MarkerViewChoice(
            capture.cameras, options.best_view_switch_cost, options.best_view_window)
        self.shape_breaks: list[ShapeBreak] = []  # labels off their rigid neighbours in the last result (``shape_doubt``)
        self.model_misfits: list[SegmentMisfit] = []  # segments the user's labels say the model gets wrong
        self.detections_taken: np.ndarray | None = None  # camera mode: per camera, the share a marker took
        self._association: Association
        model = capture.model
        if model is not None and capture.points is not None:
            # Identified, nothing labeled: the take may correct the model. Labels already place their
            # segments (relearning beside them cost 03_rolling's second half 10 points, docs/subject-model.md).
            model = model if labeled else learn_from_take(model, capture.points[: options.window])
            self.model_misfits = labeled_misfits(ModelGeometry.of(model), np.asarray(capture.first_frame, dtype=float))
            self._first, first_frame = model_first_frame(model, capture.points[0], capture.first_frame,
                                                         frozenset(m.segment for m in self.model_misfits))
            self._association, rival = model_chains(capture, model, first_frame, options, self.formulation.look_ahead,
                                                    labeled)
        else:
            self._first = first_marker_state(capture.names, capture.first_frame)
            self._association = association_chain(capture, options, self.formulation.look_ahead)
            rival = association_chain(capture, options, look_ahead=False)
        unrepaired = partial(self._labeled, repaired=False)
        self._rival = RivalReading(rival, resolve_formulation("nn-hungarian"), unrepaired) \
            if rival_unread_reason(capture, options, self.formulation) is None else None
        self._hypotheses = None if self._rival is None else hypothesis_reading(capture, options, self.formulation, unrepaired)
        self._readings = READINGS[: 1 + (self._hypotheses is not None)]  # what runs beside, in child processes
        self._early = None if self._rival is None else EarlyStart(capture, options, self._readings, self.n_windows)
        self._geometry = None if model is None else ModelGeometry.of(model)  # the model as the take corrected it

    def windows(
        self, after: WindowOutcome | None = None, progress: Progress | None = None, observer: Observer | None = None,
    ) -> Iterator[WindowOutcome]:
        """Each window's outcome as it finishes; ``after`` resumes after a finished window.

        ``progress`` is called with (windows done, windows), ``observer`` with (template
        frame, problem, solution), after each window.

        Raises:
            InputError: ``after`` is not a window of this labeling (another window size or capture).
        """
        if after is not None:
            check_resumable(after, self._spans, len(self._first.position), self.fingerprint)
        windows = stamped(label_windows(
            self._association, self.formulation, self._first, self._capture.n_frames, self._window, after, progress, observer
        ), self.fingerprint)
        return windows if self._early is None else self._early.watched(windows)

    def refine(
        self, outcomes: list[WindowOutcome], progress: Progress | None = None, stop: Stop | None = None,
    ) -> list[WindowOutcome] | None:
        """The windows to keep once every window is labeled: ``outcomes``, or a second pass's
        (``second_pass``) when on and closer to the first frame, with the marker groups a
        frame-by-frame reading (``rival_reading``), then an ``mht`` one (``hypothesis_reading``),
        label better taken from them when the second pass ran (read in child processes meanwhile
        on a large take, ``rival_process``); None when ``stop`` abandoned any. Sets ``choice``,
        ``rival`` and ``hypotheses``."""
        if not self._second_pass:
            return outcomes
        rival = self._rival is not None and second_pass_runs(outcomes)  # a doubtful take: read frame by frame too
        beside = self._early.taken(rival) if self._early is not None else Beside({})  # started during the first pass
        if not beside.children and rival and runs_beside(sum(o.stats.total_seconds for o in outcomes), len(self._readings)):
            beside = started(self._capture, self._options, self._readings)
        # The merges take window columns: judged unrepaired (repairs put racing's GloveR2, R3 on one point)
        unrepaired = partial(self._labeled, repaired=False)
        with beside:
            kept = second_pass(self._association, self.formulation, self._first, self._capture.n_frames, self._window,
                               outcomes, unrepaired, progress, stop, learned=self._labeled)
            if kept is None:
                return None
            kept_outcomes, self.choice = kept
            if rival:
                labels = judged_part(unrepaired(kept_outcomes))
                read = beside.read(READINGS[0], self.read_beside, progress_after(progress, self.n_windows), stop)
                if read is None:
                    return None
                assert self._rival is not None
                kept_outcomes, self.rival = merged_with_rival(self._rival, self._first, kept_outcomes, labels, read)
                if self._hypotheses is not None:
                    read = beside.read(READINGS[1], self.read_beside, progress_after(progress, 3 * self.n_windows), stop)
                    if read is None:
                        return None
                    kept_outcomes, self.hypotheses = merged_with_hypotheses(self._hypotheses, self._first,
                                                                            kept_outcomes, read)
        return outcomes if kept_outcomes is outcomes else list(stamped(kept_outcomes, self.fingerprint))  # ``is``: kept as stored

    def read_beside(self, reading: str, progress: Progress | None = None, stop: Stop | None = None,
                    ) -> list[WindowOutcome] | None:
        """The take's windows as ``reading`` (``rival_process.READINGS``) reads them: frame by frame
        (``rival_reading``) or by ``mht`` (``hypothesis_reading``), with its own second pass; None
        when ``stop`` abandoned them. Only when that reading is on for this take."""
        chosen = self._rival if reading == READINGS[0] else self._hypotheses
        assert chosen is not None
        return read_frame_by_frame(chosen, self._first, self._capture.n_frames, self._window, progress, stop)

    def result(self, outcomes: list[WindowOutcome], calibrated: bool = True) -> LabeledTrajectories:
        """The labeled trajectories from all windows' outcomes, their tracks extended over the
        points no marker took (``extension``); each closed gap's fill tied to
        both sightings (``gap_ends``) and refilled from rigid donors where both sides have
        three (``rigid_fill``; with a model also ``joint_tracks`` and ``pose_fill``); in camera
        mode with each marker's best view per frame (``service.best_view.markers``); with every
        label's confidence, ``calibrated`` as reported (else the windows' raw ones), and then
        doubtful where a label left its rigid neighbours (``shape_doubt``); 3D points no marker
        took kept as unlabeled trajectories (``leftover_points``).

        Raises:
            InputError: ``outcomes`` are not this labeling's windows 0, 1, ... in order.
        """
        check_outcomes(outcomes, self._spans, len(self._first.position), self.fingerprint)
        return self._finished(self._labeled(outcomes), outcomes, calibrated)

    def assembled(self, outcomes: list[WindowOutcome], repaired: bool = True) -> LabeledTrajectories:
        """The windows' labels as ``result`` starts from (confidences, tracks extended, when ``repaired``
        the take-wide repairs; no fill, calibration or shape doubt): ``bench/real_stages.py``."""
        return self._labeled(outcomes, repaired=repaired)

    def _finished(self, labels: LabeledTrajectories, outcomes: list[WindowOutcome], calibrated: bool) -> LabeledTrajectories:
        """``result`` of the repaired labels; ``outcomes`` are read again in camera mode only (views, lone views)."""
        if labels.filled.size:
            labels.filled = self._fill(labels)
            if isinstance(self._association, Joint3dChain):
                labels.filled = self._association.fills_on_lone_views(labels, outcomes)
        if self._view_choice is None:
            labels = with_leftover_points(labels, self._points)
        else:
            views = self._association.views(outcomes)
            self.detections_taken = detections_taken(views, self._capture.camera_frames()[1])
            labels = self._view_choice.attach(labels, views)
        if not calibrated:
            return labels
        labels, self.shape_breaks = as_reported(labels)
        return labels

    def _labeled(self, outcomes: list[WindowOutcome], keep: bool = True, repaired: bool = True) -> LabeledTrajectories:
        """The windows' labels with their confidence, tracks extended over free points and
        exchanges the first frame finds over the take given back (3D points: ``exchanged``;
        not when ``repaired`` is False: the frame-by-frame reading's labels, as it would give them);
        ``keep`` False empties ``outcomes`` once assembled (``label``'s own list: its marker
        states, 3 kB a frame at 41 markers, are then not held through the take-wide repairs)."""
        labels = self._association.assemble(outcomes)
        labels.confidence = take_confidence(labels.n_frames, len(labels.names), outcomes)
        frames = max((o.stats.last + 1 for o in outcomes), default=1)
        if not keep:
            outcomes.clear()
        if self._points is None:
            return labels
        labels = extended(labels, self._points, frames)
        if not (repaired and self.formulation.look_ahead):  # a frame-by-frame reading sees no later frame: no take-wide repair
            return labels
        labels, self.exchanges = exchanged_back(labels, self._first)
        labels, self.handovers = handed_back(labels, self._first)
        return labels

    def _fill(self, labels: LabeledTrajectories) -> np.ndarray:
        """The windows' fill tied to both sightings, refilled from rigid donors; with a model
        its joint centres are donors too, and the segment's pose fills where they disagree."""
        tied = tie_gap_ends(labels.positions, labels.filled)
        if self._geometry is None:
            return rigid_fill(labels.positions, tied)
        guides = joint_tracks(self._geometry, labels.names, labels.positions)
        filled, doubt = rigid_refill(labels.positions, tied, guides)
        return pose_fill(self._geometry, labels.names, labels.positions, filled, doubt)

    def warnings(self, result: LabeledTrajectories, windows: list[WindowStats], unit: str = "mm", start: int = 0,
                 spacing_judged: bool = False) -> list[str]:
        """The lines ``markerflow track`` prints after its summary, for what ``label`` returned
        (the input in ``unit``, its frame ``start`` labeled first): many doubtful labels, labels
        off their rigid neighbours, markers faster than their spacing, a spacing not human-sized
        in ``unit`` (unless ``spacing_judged`` before labeling), copied columns, points with no
        marker named, a frame 0 off the calibration, windows stopped at the time limit, segments
        the labeled frame says the model gets wrong. Empty when none applies: an optimal window
        is optimal under the model, and these say where the labels are likely wrong anyway."""
        lines = result_warnings(self._capture, result, self.shape_breaks, unit, start, spacing_judged)
        more = (time_limit_warning([w.status for w in windows]), model_misfit_warning(self.model_misfits, start),
                None if self.detections_taken is None else unused_camera_warning(
                    [camera.name for camera in self._capture.camera_frames()[0]], self.detections_taken))
        return lines + [line for line in more if line is not None]

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray:
        """``(F, N, C)`` detection each marker took in each camera, -1 for none (camera mode).

        Raises:
            InputError: A capture of 3D points.
        """
        return self._association.views(outcomes)

    def label(
        self, progress: Progress | None = None, observer: Observer | None = None,
        stage: Callable[[str], None] | None = None,
    ) -> tuple[LabeledTrajectories, list[WindowStats]]:
        """Label every window in one go, and again if ``refine`` says so; ``progress``
        counts the first pass's windows, then both passes' once a second pass runs (43/43,
        then 44/86 ...), then on through the frame-by-frame and mht readings' two each (87/129 ... 215/258);
        ``observer`` sees the first pass; ``stage`` is told when the windows
        are done and the labels are assembled (35 s after the last window at 50,000 frames)."""
        outcomes = self.refine(list(self.windows(progress=progress, observer=observer)), progress_after(progress, self.n_windows))
        assert outcomes is not None  # only a stop abandons the second pass
        if stage is not None:
            stage("windows done; assembling the labels (take-wide repairs, fill, confidence)")
        windows = [o.stats for o in outcomes]
        labels = self._labeled(outcomes, keep=self._view_choice is not None)  # camera mode reads them again
        return self._finished(labels, outcomes, True), windows
