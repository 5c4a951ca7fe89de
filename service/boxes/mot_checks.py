"""Checks of a result and a ground truth before TrackEval scores them.

TrackEval's own errors name a placeholder sequence and the renumbered ids, and some
inputs it scores without a word although the figures mean nothing; these say what is
wrong, in which file and on which line:

- which benchmark's rules apply: a ground truth of 9 columns (MOT16/17/20: consider,
  class, visibility) is scored as MOT17, and then every class must be one of MOTChallenge's
  1..13 (a stray class used to switch the whole file to MOT15's rules, which count boxes
  on distractors as false positives);
- an id given twice in one frame;
- a result that hardly overlaps the ground truth (another sequence's file, or boxes in
  other units), which TrackEval scores near 0 as if the tracker were bad;
- a seqinfo.ini longer than the ground truth (another sequence's), which changes the
  frames counted and no score.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formulations.boxes.geometry import corners, iou
from service.boxes.mot_files import MotTable
from service.errors import InputError

MOT17_COLUMNS = 9
CLASSES = np.arange(1, 14)  # pedestrian .. reflection, MOTChallenge's class numbers
MATCH_IOU = 0.5
FEW_MATCHED = 0.1  # share of result boxes on a ground-truth box below which the pair is suspect


def benchmark(truth: MotTable) -> str:
    """"MOT17" (classes: distractors are dropped before scoring) or "MOT15" (no classes).

    Raises:
        InputError: A 9-column ground truth with a class outside 1..13, naming its line.
    """
    rows = truth.rows
    if rows.shape[1] < 8:
        return "MOT15"
    valid = np.isin(rows[:, 7], CLASSES)
    if rows.shape[1] == MOT17_COLUMNS and not valid.all():
        row = int(np.argmin(valid))
        raise InputError(f"{truth.at(row)}: class {rows[row, 7]:g}; a 9-column ground truth (MOT16/17/20) has a "
                         "MOTChallenge class from 1 (pedestrian) to 13 in column 8 on every line")
    return "MOT17" if valid.all() else "MOT15"


def check_consider_flags(truth: MotTable) -> None:
    """A ground truth's 7th column is a consider flag, 0 or 1 (-1 in some MOT15 files); a
    detector's confidence there (0.986) is a result file given as the ground truth, which
    scored (HOTA 0.240 for MPNTrack against Lif_T) instead of being refused.

    Raises:
        InputError: The first line whose flag is another number.
    """
    flags = truth.rows[:, 6]
    bad = ~np.isin(flags, (0.0, 1.0, -1.0))
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{truth.at(row)}: {flags[row]:g} in column 7, where a ground truth has its consider flag "
                         "(0 or 1): is it a result file, with confidences there?")


def check_unique_ids(table: MotTable) -> None:
    """Refuse an id that appears twice in one frame, naming both lines."""
    keys = table.rows[:, :2]
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    same = (np.diff(keys[order], axis=0) == 0).all(axis=1)
    if same.any():
        first, second = sorted(order[np.argmax(same) + np.array([0, 1])])
        frame, ident = keys[first]
        raise InputError(f"{table.at(second)}: id {ident:g} appears twice in frame {frame:g} "
                         f"(also line {int(table.lines[first])}); an id names one box per frame")


def matched_share(result: np.ndarray, truth: np.ndarray) -> float | None:
    """Share of the result's boxes that overlap a ground-truth box of their frame by IoU >= 0.5;
    None for a result without boxes: a share of none is no figure, and the 1.0 it was read as
    "every box on the ground truth" beside a HOTA of 0."""
    if not len(result):
        return None
    matched = 0
    for frame in np.unique(result[:, 0]):
        mine, theirs = result[result[:, 0] == frame, 2:6], truth[truth[:, 0] == frame, 2:6]
        if len(theirs):
            matched += int((iou(corners(mine), corners(theirs)) >= MATCH_IOU).any(axis=1).sum())
    return matched / len(result)


def few_matched_warning(share: float | None, result: Path, truth: Path) -> str | None:
    """A line when hardly any result box lies on a ground-truth box (none when there is no box)."""
    if share is None or share >= FEW_MATCHED:
        return None
    return (f"warning: only {share:.0%} of the boxes of {result} overlap a box of {truth} in their frame "
            f"(IoU >= {MATCH_IOU}); are they the same sequence, in the same pixels?")


def short_truth_warning(truth_last: int, length: int, source: Path) -> str | None:
    """A line when the ground truth ends before ``seqLength``: a seqinfo.ini of another, longer
    sequence (MOT17-05's 837 frames for MOT17-02's 600) changes no score, as frames past the
    last box add nothing, but ``frames`` then counts the other sequence's length. A ground
    truth may end early (nobody in the last frames), so this warns and does not refuse; one
    with frames past ``seqLength`` is refused (``scores._length``)."""
    if truth_last >= length:
        return None
    return (f"warning: the ground truth ends at frame {truth_last} of the sequence's {length} ({source}); "
            "is that seqinfo.ini of another sequence?")
