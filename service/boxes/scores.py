"""MOT scores by TrackEval (Luiten et al. 2021): HOTA, MOTA, IDF1, identity switches.

TrackEval reads a MOTChallenge folder tree, so one result and one ground truth are laid out
in a temporary one (copies with ids renumbered 1, 2, ...: ``mot_files.dense_ids``) and its dataset class does the reading and the
MOTChallenge preprocessing; its metric classes are then called on that one sequence,
without the Evaluator (which prints and writes summary files). TrackEval 1.3 runs on
numpy 2 as is (no ``np.float``/``np.int`` left in it).

A ground truth with classes (MOT16/17/20: a class column of 1..13) is scored as MOT17,
which drops the non-pedestrian ground truth and the results matched to distractors; one
without (MOT15, e.g. TUD-Campus, class -1) as MOT15, without that step
(``mot_checks.benchmark``). A result's columns past the confidence (world x, y, z) are not
passed on: TrackEval would read the 8th as a class.
"""

from __future__ import annotations

import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from service.boxes.mot_checks import (
    benchmark,
    check_consider_flags,
    check_unique_ids,
    matched_share,
    short_truth_warning,
)
from service.boxes.mot_files import MotTable, dense_ids, read_seqinfo, read_table
from service.errors import InputError

SEQUENCE, TRACKER = "sequence", "tracker"


@dataclass(frozen=True)
class MotScores:
    """Scores of one result against one ground truth.

    Attributes:
        hota: HOTA, mean over the IoU thresholds 0.05..0.95.
        deta, assa: Its detection and association parts.
        mota: CLEAR MOT accuracy.
        idf1: Identity F1.
        id_switches: CLEAR identity switches.
        gt_ids, result_ids: Distinct identities scored on each side.
        frames: Frames scored: seqLength of the seqinfo.ini, else the last frame of either file.
        matched: Share of the result's boxes on a ground-truth box of their frame (IoU >= 0.5),
            whatever the ids: near 0 when the two are not of one sequence; None for an empty
            result (no box to place: 1.0 read as a perfect overlap).
        warnings: Lines for stderr about the inputs (``mot_checks.short_truth_warning``);
            not a score, so not in ``as_dict``.
    """

    hota: float
    deta: float
    assa: float
    mota: float
    idf1: float
    id_switches: int
    gt_ids: int
    result_ids: int
    frames: int
    matched: float | None
    warnings: tuple[str, ...] = ()

    def as_dict(self) -> dict[str, float | int | None]:
        """The scores, as ``mot-eval --json`` prints them (``matched`` null for an empty result)."""
        scores: dict[str, float | int | None] = asdict(self)
        del scores["warnings"]
        return scores


def mot_scores(result: Path, gt: Path, seqinfo: Path | None = None) -> MotScores:
    """Score ``result`` against ``gt``; the length comes from ``seqinfo`` (or a ``seqinfo.ini`` beside the gt folder)."""
    from trackeval.datasets import MotChallenge2DBox
    from trackeval.metrics import CLEAR, HOTA, Identity
    from trackeval.utils import TrackEvalException

    truth_table, result_table = read_table(gt), read_table(result, empty_ok=True)
    check_consider_flags(truth_table)
    for table in (truth_table, result_table):
        check_unique_ids(table)
    truth, rows = truth_table.rows, result_table.rows
    length, warning = _length(gt, seqinfo, truth, rows)
    chosen = benchmark(truth_table)
    with tempfile.TemporaryDirectory(prefix="markerflow-mot-") as folder:
        root = Path(folder)
        (root / "gt" / SEQUENCE / "gt").mkdir(parents=True)
        (root / "trackers" / TRACKER / "data").mkdir(parents=True)
        # %.17g writes every float64 back exactly.
        np.savetxt(root / "gt" / SEQUENCE / "gt" / "gt.txt", _as_gt(truth_table), fmt="%.17g", delimiter=",")
        np.savetxt(root / "trackers" / TRACKER / "data" / f"{SEQUENCE}.txt", dense_ids(result_table)[:, :7], fmt="%.17g",
                   delimiter=",")
        config = {
            "GT_FOLDER": str(root / "gt"), "TRACKERS_FOLDER": str(root / "trackers"), "SKIP_SPLIT_FOL": True,
            # Frames after the last box add nothing to any score: TrackEval need not step through them.
            "SEQ_INFO": {SEQUENCE: _last_frame(truth, rows)}, "BENCHMARK": chosen,
            "TRACKERS_TO_EVAL": [TRACKER], "PRINT_CONFIG": False,
        }
        try:
            dataset = MotChallenge2DBox(config)
            data = dataset.get_preprocessed_seq_data(dataset.get_raw_seq_data(TRACKER, SEQUENCE), "pedestrian")
        except TrackEvalException as error:
            raise InputError(f"{result} against {gt}: {error}") from None
    if not data["num_gt_ids"]:  # every score would read 0 and say nothing of the tracker
        raise InputError(f"{gt}: TrackEval counts none of its boxes as ground truth (none marked to be "
                         "considered, or none a pedestrian); is it a result file?")
    quiet = {"PRINT_CONFIG": False}
    hota = HOTA().eval_sequence(data)
    clear = CLEAR(quiet).eval_sequence(data)
    identity = Identity(quiet).eval_sequence(data)
    return MotScores(
        hota=float(np.mean(hota["HOTA"])), deta=float(np.mean(hota["DetA"])), assa=float(np.mean(hota["AssA"])),
        mota=float(clear["MOTA"]), idf1=float(identity["IDF1"]), id_switches=int(clear["IDSW"]),
        gt_ids=int(data["num_gt_ids"]), result_ids=int(data["num_tracker_ids"]), frames=length,
        matched=matched_share(rows, truth), warnings=(warning,) if warning else (),
    )


def _as_gt(truth: MotTable) -> np.ndarray:
    """The ground truth as TrackEval reads it: a 7-column one (no class) gets a class column
    of 1 (pedestrian), which MOT15 scoring does not read but TrackEval requires."""
    dense = dense_ids(truth)
    if dense.shape[1] > 7:
        return dense
    return np.column_stack([dense, np.ones(len(dense))])


def _length(gt: Path, seqinfo: Path | None, truth: np.ndarray, rows: np.ndarray) -> tuple[int, str | None]:
    """The sequence's length, and a warning when its seqinfo.ini runs on past the ground truth.

    Raises:
        InputError: a frame of either file past seqLength.
    """
    beside = gt.parent.parent / "seqinfo.ini"
    source = seqinfo if seqinfo is not None else (beside if beside.is_file() else None)
    if source is None:
        return _last_frame(truth, rows), None
    length = read_seqinfo(source).length
    last = _last_frame(truth, rows)
    if last > length:
        side = "the ground truth" if truth[:, 0].max() >= last else "the result"
        raise InputError(f"frame {last} of {side} is past the sequence's {length} frames ({source})")
    return length, short_truth_warning(int(truth[:, 0].max()), length, source)


def _last_frame(truth: np.ndarray, rows: np.ndarray) -> int:
    return int(max(truth[:, 0].max(), rows[:, 0].max(initial=1)))
