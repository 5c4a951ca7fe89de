"""How well the doubtful labels point at the wrong ones, against a simulated capture's truth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from service.evaluation.scores import flat_points
from service.evaluation.simulated import SimulatedCapture
from service.io.recording import LabeledTrajectories
from service.labeling.stats import reported_doubtful


@dataclass(frozen=True)
class DoubtCounts:
    """Labels (markers holding a point, frame 0 not scored), the doubtful ones, the wrong
    ones (a ghost or another marker's point), and the wrong ones that are doubtful."""

    labels: int
    doubtful: int
    wrong: int
    flagged: int

    def scores(self) -> dict[str, float | None]:
        """``doubtful_share`` = doubtful / labels (0 with no label); ``doubtful_recall`` =
        flagged / wrong (None with no wrong label)."""
        return {
            "doubtful_share": self.doubtful / self.labels if self.labels else 0.0,
            "doubtful_recall": self.flagged / self.wrong if self.wrong else None,
        }


def doubt_counts(
    capture: SimulatedCapture, result: LabeledTrajectories, unknown: np.ndarray | None = None,
) -> DoubtCounts:
    """Count a labeling's labels against the truth; doubtful = confidence below
    ``REPORTED_DOUBTFUL_BELOW`` (``service.labeling.stats.reported_doubtful``).

    ``unknown``: ``(frames, markers)`` marker-frames whose truth is not known (a recording's
    own label jumps there, ``label_jumps``): their labels are left out of every count, and so
    is a label of a marker the file does not see in that frame on a point the file names
    there as such a marker: what that point is, is not known. (A marker the file does see,
    on another's point, is wrong whatever that point is.) On 03_rolling the file's LL_HME
    comes back from a gap on another marker for 53 frames, 85 mm off its upper-arm partners;
    the labeler calls that point LL_TH1, absent from the file there, and was counted wrong
    on every frame.

    Raises:
        ValueError: ``result`` has no confidences, or names a point a frame does not have.
    """
    if result.confidence.shape != result.point_index.shape:
        raise ValueError("the labeling has no confidence for every label")
    labeled = result.point_index >= 0
    labeled[0] = False
    if unknown is not None:
        labeled &= ~unknown
    owner = np.full(result.point_index.shape, -2)  # the true marker of each point taken, -1 a ghost
    for f in np.flatnonzero(labeled.any(axis=1)):
        taken = result.point_index[f, labeled[f]]
        if taken.max() >= len(capture.point_marker[f]):
            raise ValueError(f"frame {f}: the labeling names point {taken.max()} of {len(capture.point_marker[f])}")
        owner[f, labeled[f]] = capture.point_marker[f][taken]
    if unknown is not None:
        labeled &= ~_on_unknown_points(capture, owner, unknown)
    wrong = labeled & (owner != np.arange(result.point_index.shape[1]))
    doubtful = reported_doubtful(result.confidence, ~labeled)
    return DoubtCounts(int(labeled.sum()), int(doubtful.sum()), int(wrong.sum()), int((doubtful & wrong).sum()))


def _on_unknown_points(capture: SimulatedCapture, owner: np.ndarray, unknown: np.ndarray) -> np.ndarray:
    """``(frames, markers)`` labels of markers the file does not see in their frame, on a point
    whose file label is ``unknown`` there (``doubt_counts``)."""
    frames, markers = owner.shape
    marker, frame, _ = flat_points(capture.point_marker[:frames])
    seen = np.zeros((frames, markers), bool)
    real = marker >= 0
    seen[frame[real], marker[real]] = True
    rows = np.arange(frames)[:, None]
    owner_unknown = (owner >= 0) & unknown[rows, np.clip(owner, 0, markers - 1)]
    return owner_unknown & ~seen


def doubt_scores(capture: SimulatedCapture, result: LabeledTrajectories) -> dict[str, float | None]:
    """``doubtful_share`` and ``doubtful_recall`` of a labeling (``DoubtCounts.scores``)."""
    return doubt_counts(capture, result).scores()
