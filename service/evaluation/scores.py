"""Scores of a labeling against the truth of a simulated capture."""

from dataclasses import dataclass
from typing import NamedTuple, TypedDict

import numpy as np

from service.evaluation.simulated import SimulatedCapture
from service.io.recording import LabeledTrajectories


@dataclass(frozen=True)
class LabelScores:
    """How well a labeling matches a simulated capture; frame 0 (given) is not scored.

    Attributes:
        label_accuracy: ``correct / marker_frames`` (1.0 when ``marker_frames == 0``).
        swaps: Runs of consecutive frames in which a marker holds a point of another true
            marker, counted once per run and per marker (a two-marker swap counts 2).
        ghost_precision: ``true ghosts declared / points declared ghosts``, where a point
            no marker took is declared a ghost (1.0 when none is declared).
        ghost_recall: ``true ghosts declared / true ghosts`` (1.0 when there are none).
        marker_frames: Marker-frames whose marker has a point in the input.
        correct: Of those, the ones where the marker took its own point.
        missed: Of those, the ones the labeling left occluded.
        took_ghost: Marker-frames (visible or not) where the marker took a ghost.
        ghosts: True ghost points.
        declared_ghosts: Points no marker took.
    """

    label_accuracy: float
    swaps: int
    ghost_precision: float
    ghost_recall: float
    marker_frames: int
    correct: int
    missed: int
    took_ghost: int
    ghosts: int
    declared_ghosts: int


def label_scores(capture: SimulatedCapture, result: LabeledTrajectories, first_given: bool = True) -> LabelScores:
    """Score ``result.point_index`` against the true marker of every input point.

    With ``t[f, n]`` the index of marker ``n``'s point in frame ``f`` (-1 if it has none)
    and ``p[f, n] = result.point_index[f, n]``, over frames ``f >= 1`` (``f >= 0`` when the
    labeler was not given frame 0: ``first_given`` False, a start from a subject model):
    ``marker_frames = #{t >= 0}``, ``correct = #{t >= 0, p == t}``; a swap starts at
    ``(f, n)`` when ``n`` holds another marker's point in ``f`` but not in ``f - 1``.

    Raises:
        ValueError: If ``point_index`` is not ``(frames, markers)`` or names a point that
            the frame does not have.
    """
    marker, frame, offsets, taken, scored, visible, correct = _marked(capture, result, first_given)
    rows, cols = np.nonzero((taken >= 0) & scored[:, None])
    flat_taken = offsets[rows] + taken[rows, cols]
    held = np.full(taken.shape, -2)  # -2: holds no point, -1: holds a ghost
    held[rows, cols] = marker[flat_taken]
    return LabelScores(
        label_accuracy=_ratio(correct.sum(), visible.sum()),
        swaps=run_onsets((held >= 0) & (held != np.arange(taken.shape[1]))),
        **_ghost_scores(marker, scored[frame], flat_taken),
        marker_frames=int(visible.sum()),
        correct=int(correct.sum()),
        missed=int(np.sum(visible & (taken < 0))),
        took_ghost=int(np.sum(held == -1)),
    )


def block_counts(
    capture: SimulatedCapture, result: LabeledTrajectories, block_frames: int = 1000
) -> list[tuple[int, int]]:
    """``(marker_frames, correct)`` per block of ``block_frames`` consecutive frames.

    Block ``k`` holds frames ``[k B, (k + 1) B)`` with ``B = block_frames``; a tail
    shorter than ``B / 2`` joins the block before it, so no block is a noisy sliver.
    Counts are those of ``label_scores`` (frame 0 unscored), so summed over the blocks
    they give its ``marker_frames`` and ``correct``; block accuracy is ``correct /
    marker_frames``.

    Raises:
        ValueError: As ``label_scores``, or if ``block_frames < 1``.
    """
    if block_frames < 1:
        raise ValueError(f"block_frames must be >= 1, got {block_frames}")
    *_, visible, correct = _marked(capture, result)
    n_frames = visible.shape[0]
    starts = list(range(0, n_frames, block_frames)) or [0]
    if len(starts) > 1 and n_frames - starts[-1] < block_frames / 2:
        starts.pop()
    bounds = [*starts, n_frames]
    return [(int(visible[a:b].sum()), int(correct[a:b].sum())) for a, b in zip(bounds, bounds[1:])]


def counts_within(capture: SimulatedCapture, result: LabeledTrajectories, within: np.ndarray) -> tuple[int, int]:
    """``(marker_frames, correct)`` as ``label_scores`` counts them, inside the ``(frames, markers)``
    mask ``within`` (the marker-frames where the file's own label jumped: ``label_jumps``)."""
    *_, visible, correct = _marked(capture, result)
    return int((visible & within).sum()), int((correct & within).sum())


class _Marked(NamedTuple):
    marker: np.ndarray
    frame: np.ndarray
    offsets: np.ndarray
    taken: np.ndarray
    scored: np.ndarray
    visible: np.ndarray
    correct: np.ndarray


def _marked(capture: SimulatedCapture, result: LabeledTrajectories, first_given: bool = True) -> _Marked:
    """The flat points (``flat_points``), the labeling, and per marker-frame masks.

    ``scored[f]``: frame ``f >= 1``; ``visible[f, n]``: scored and ``n`` has a point;
    ``correct[f, n]``: visible and ``n`` took its own point.
    """
    marker, frame, offsets = flat_points(capture.point_marker)
    taken = _checked_point_index(capture, result, offsets)
    # Frame 0 is given by the user, so nothing in it is scored (unless a model named it).
    scored = np.arange(taken.shape[0]) >= (1 if first_given else 0)
    true_index = _true_index(marker, frame, offsets, taken.shape)
    visible = (true_index >= 0) & scored[:, None]
    correct = visible & (taken == true_index)
    return _Marked(marker, frame, offsets, taken, scored, visible, correct)


def flat_points(point_marker: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All frames' points in one array: their marker, their frame, and frame offsets.

    Frame ``f`` owns flat indices ``offsets[f] : offsets[f + 1]``.
    """
    counts = np.array([len(pm) for pm in point_marker], dtype=int)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    # The empty tail keeps concatenate working, and the dtype int, for a capture of no frames.
    marker = np.concatenate([np.asarray(pm, dtype=int) for pm in point_marker] + [np.zeros(0, int)])
    return marker, np.repeat(np.arange(len(counts)), counts), offsets


def _true_index(
    marker: np.ndarray, frame: np.ndarray, offsets: np.ndarray, shape: tuple[int, int]
) -> np.ndarray:
    """``(frames, markers)``: the index of each marker's point in its frame, -1 if none."""
    true_index = np.full(shape, -1)
    own = marker >= 0
    true_index[frame[own], marker[own]] = np.flatnonzero(own) - offsets[frame[own]]
    return true_index


def _checked_point_index(
    capture: SimulatedCapture, result: LabeledTrajectories, offsets: np.ndarray
) -> np.ndarray:
    """``result.point_index`` as ints, after checking it fits the capture."""
    taken = np.asarray(result.point_index, dtype=int)
    expected = capture.truth.positions.shape[:2]
    if taken.shape != expected:
        raise ValueError(f"point_index has shape {taken.shape}, the capture is {expected}")
    in_frame = np.diff(offsets)[:, None]
    if np.any((taken < -1) | (taken >= in_frame)):
        raise ValueError("point_index names a point the frame does not have")
    return taken


class _GhostScores(TypedDict):
    ghost_precision: float
    ghost_recall: float
    ghosts: int
    declared_ghosts: int


def _ghost_scores(marker: np.ndarray, in_scope: np.ndarray, flat_taken: np.ndarray) -> _GhostScores:
    """Ghost precision, recall and counts over the points flagged ``in_scope``."""
    declared = in_scope.copy()
    declared[flat_taken] = False
    ghost = in_scope & (marker < 0)
    hits = int(np.sum(declared & ghost))
    return {
        "ghost_precision": _ratio(hits, int(declared.sum())),
        "ghost_recall": _ratio(hits, int(ghost.sum())),
        "ghosts": int(ghost.sum()),
        "declared_ghosts": int(declared.sum()),
    }


def run_onsets(wrong: np.ndarray) -> int:
    """Number of runs of True along axis 0, summed over columns."""
    before = np.vstack([np.zeros((1, wrong.shape[1]), dtype=bool), wrong[:-1]])
    return int(np.sum(wrong & ~before))


def _ratio(numerator: int, denominator: int) -> float:
    """``numerator / denominator``, defined as 1.0 when there is nothing to count."""
    return float(numerator / denominator) if denominator else 1.0
