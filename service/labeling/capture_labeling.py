"""Label a capture in any input mode, window by window, resumably.

This is the one entry point the CLI, the HTTP jobs and the Dask workers share:

    labeling = CaptureLabeling(capture, LabelingOptions(formulation="ilp"))
    outcomes = []
    for outcome in labeling.windows(after=outcomes[-1] if outcomes else None):
        outcomes.append(outcome)  # persist it here to survive a crash
    result = labeling.result(outcomes)

3D points are labeled by the window LP directly. Camera detections are either matched
across cameras first (``joint-3d``) into 3D points whose resources are their detections,
or tracked by the window LP in each camera's image and then triangulated (``per-camera``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from functools import partial

from service.capture.capture import Capture, LabelingOptions
from service.capture.formulation_spec import formulation_from_table
from service.errors import InputError
from service.io.recording import LabeledTrajectories, UnlabeledCloud
from service.labeling.cloud import CloudLabeler
from service.labeling.joint_3d import cross_camera_cloud
from service.labeling.outcome import WindowOutcome
from service.labeling.per_camera import PerCameraLabeler
from service.labeling.spans import window_spans
from service.labeling.stats import WindowStats


class CaptureLabeling:
    """One capture's labeling: its windows, and the trajectories they assemble into.

    Args:
        capture: What to label.
        options: Formulation, window size, association.

    Raises:
        InputError: Unknown formulation or parameter, bad window size, or an
            association that does not apply.
    """

    def __init__(self, capture: Capture, options: LabelingOptions = LabelingOptions()) -> None:
        table = {"name": options.formulation} if isinstance(options.formulation, str) else options.formulation
        formulation = formulation_from_table(table, "formulation")
        self.n_windows = len(window_spans(capture.n_frames, options.window))
        if capture.mode == "cameras" and options.association == "per-camera":
            labeler = PerCameraLabeler(formulation=formulation, window=options.window)
            self._windows = partial(labeler.windows, capture)
            self._assemble = partial(labeler.assemble, capture)
            return
        labeler = CloudLabeler(formulation=formulation, window=options.window)
        given = (_cloud(capture, options.association), capture.names, capture.first_frame)
        self._windows = partial(labeler.windows, *given)
        self._assemble = partial(labeler.assemble, *given)

    def windows(self, after: WindowOutcome | None = None) -> Iterator[WindowOutcome]:
        """Each window's outcome as it finishes; ``after`` resumes after a finished window."""
        return self._windows(after=after)

    def result(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
        """The labeled trajectories from all windows' outcomes."""
        return self._assemble(outcomes)

    def label(self, progress: Callable[[int, int], None] | None = None) -> tuple[LabeledTrajectories, list[WindowStats]]:
        """Label every window in one go."""
        outcomes = []
        for outcome in self.windows():
            outcomes.append(outcome)
            if progress:
                progress(len(outcomes), self.n_windows)
        return self.result(outcomes), [o.stats for o in outcomes]


def _cloud(capture: Capture, association: str) -> UnlabeledCloud:
    """The points the window LP labels: the capture's own, or the cross-camera points."""
    if capture.mode == "points":
        return UnlabeledCloud(points=capture.points, rate=capture.rate)
    if association != "joint-3d":
        raise InputError(f"association {association!r} is not available; use joint-3d or per-camera")
    return cross_camera_cloud(capture.cameras, capture.detections, capture.rate)[0]
