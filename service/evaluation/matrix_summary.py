"""Accuracy-matrix rows: cells pooled over seeds, and issue 11's goals checked on them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from service.evaluation.matrix import BASELINE, CONDITIONS, RECORDINGS, Cell


@dataclass(frozen=True)
class Row:
    """One (recording, condition, formulation) over its seeds.

    Counts are summed over the seeds; accuracies pool them, ``sum correct / sum
    marker_frames``, overall and per block; ``seconds_per_frame`` is the seeds' mean.
    ``known_accuracy`` pools them without the ``file_jumps`` marker-frames, where the file's
    own label jumped to another marker (``label_jumps``) and its truth is not known.
    """

    recording: str
    condition: str
    formulation: str
    half: str
    frames: int
    seeds: int
    accuracy: float
    swaps: int
    missed: int
    took_ghost: int
    seconds_per_frame: float
    block_accuracy: tuple[float, ...]
    file_jumps: int = 0
    known_accuracy: float = 1.0


def aggregate(cells: list[Cell]) -> list[Row]:
    """Rows in the order of ``RECORDINGS``, then ``CONDITIONS``, then first-seen formulation."""
    groups: dict[tuple[str, str, str], list[Cell]] = {}
    for cell in cells:
        groups.setdefault((cell.key.recording, cell.key.condition, cell.key.formulation), []).append(cell)
    order = {r.name: i for i, r in enumerate(RECORDINGS)}
    conditions, formulations = list(CONDITIONS), list(dict.fromkeys(c.key.formulation for c in cells))
    keys = sorted(groups, key=lambda k: (order[k[0]], conditions.index(k[1]), formulations.index(k[2])))
    return [_row(groups[k]) for k in keys]


def _row(cells: list[Cell]) -> Row:
    first = cells[0]
    blocks = np.sum([c.blocks for c in cells], axis=0)  # (blocks, 2): marker_frames, correct
    return Row(
        first.key.recording, first.key.condition, first.key.formulation, first.half, first.frames, len(cells),
        _pooled(sum(c.correct for c in cells), sum(c.marker_frames for c in cells)),
        sum(c.swaps for c in cells), sum(c.missed for c in cells), sum(c.took_ghost for c in cells),
        float(np.mean([c.seconds_per_frame for c in cells])),
        tuple(_pooled(int(correct), int(seen)) for seen, correct in blocks),
        sum(c.file_jumps for c in cells),
        _pooled(sum(c.correct - c.correct_on_jumps for c in cells), sum(c.marker_frames - c.file_jumps for c in cells)),
    )


def _pooled(correct: int, marker_frames: int) -> float:
    """``correct / marker_frames``, 1.0 when nothing is scored (as ``label_scores``)."""
    return correct / marker_frames if marker_frames else 1.0


@dataclass(frozen=True)
class Goal:
    """One of issue 11's goals checked on one validation row."""

    recording: str
    condition: str
    formulation: str
    goal: str
    passed: bool
    detail: str


def accuracy_goal(noise_mm: float) -> float | None:
    """The issue's accuracy floor: 99.5 % at noise <= 2 mm, 97 % at 4 mm, none between."""
    if noise_mm <= 2.0:
        return 0.995
    return 0.97 if noise_mm >= 4.0 else None


def goals(rows: list[Row], baseline: str = BASELINE, long_take: int = 3000) -> list[Goal]:
    """Issue 11's goals on every validation row of a formulation other than ``baseline``.

    ``beats-baseline``: accuracy >= the baseline's with no more swaps; ``accuracy``: the
    floor of ``accuracy_goal``, and where the file's own labels jump (``file_jumps``) also
    ``accuracy-known``: that floor on ``known_accuracy``; ``drift``: on takes over
    ``long_take`` frames, the last block within 1 point of the first, ``|a_last - a_first| <= 0.01``.
    """
    by_key = {(r.recording, r.condition, r.formulation): r for r in rows}
    return [
        goal
        for r in rows if r.half == "validation" and r.formulation != baseline
        for goal in _row_goals(r, by_key.get((r.recording, r.condition, baseline)), long_take)
    ]


def _row_goals(r: Row, base: Row | None, long_take: int) -> list[Goal]:
    found: list[tuple[str, bool, str]] = []
    if base is not None:
        found.append(("beats-baseline", r.accuracy >= base.accuracy and r.swaps <= base.swaps,
                      f"{r.accuracy:.2%} / {r.swaps} swaps vs {base.accuracy:.2%} / {base.swaps}"))
    floor = accuracy_goal(CONDITIONS[r.condition].noise_mm)
    if floor is not None:
        found.append(("accuracy", r.accuracy >= floor, f"{r.accuracy:.2%} vs >= {floor:.1%}"))
        if r.file_jumps:
            found.append(("accuracy-known", r.known_accuracy >= floor,
                          f"{r.known_accuracy:.2%} vs >= {floor:.1%} without {r.file_jumps} marker-frames of file jumps"))
    if r.frames > long_take and len(r.block_accuracy) >= 2:
        first, last = r.block_accuracy[0], r.block_accuracy[-1]
        found.append(("drift", abs(last - first) <= 0.01, f"first block {first:.2%}, last {last:.2%}"))
    return [Goal(r.recording, r.condition, r.formulation, name, ok, detail) for name, ok, detail in found]
