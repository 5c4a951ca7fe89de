"""How a formulation does on the integrality corpus: windows with their recorded ILP optima.

A corpus is a folder of window files (``service.io.window_files``) plus ``recorded.json``:
per corpus, per window, the LP objective, whether the LP was integral, and the ILP optimum.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.io.window_files import load_window
from service.labeling.loop import Progress

RECORD = "recorded.json"


@dataclass(frozen=True)
class CorpusFigures:
    """One corpus under one formulation."""

    corpus: str
    windows: int
    integral_fraction: float
    gap_median: float
    gap_max: float
    optimal_fraction: float  # returned cost equals the recorded ILP optimum
    seconds_median: float


def load_corpus(folder: Path) -> dict[str, list[dict]]:
    """``recorded.json`` of a corpus folder: corpus name -> window records.

    Checked here, before any window is solved, because the figures need at least one window
    per corpus (a median of none was a numpy traceback) and a numeric optimum to compare
    each cost with (a string or null was a TypeError after the whole corpus was solved).

    Raises:
        InputError: No such file, not JSON, no corpus, a corpus without windows, or a window
            record without a ``file`` name and a finite number as ``ilp_optimum``.
    """
    record = folder / RECORD
    if not record.is_file():
        raise InputError(f"{folder}: no integrality corpus here ({RECORD} missing)")
    try:
        corpora = json.loads(record.read_text())
    except (ValueError, UnicodeDecodeError) as error:
        raise InputError(f"{record}: not JSON ({error})") from None
    if not isinstance(corpora, dict) or not all(isinstance(v, list) for v in corpora.values()):
        raise InputError(f"{record}: expected an object of corpus name -> list of window records")
    if not corpora:
        raise InputError(f"{record}: lists no corpus; give each corpus name a list of window records")
    for name, records in corpora.items():
        if not records:
            raise InputError(f"{record}: {name} lists no window; give it at least one window record")
        for k, entry in enumerate(records):
            if not isinstance(entry, dict) or not {"file", "ilp_optimum"} <= set(entry):
                raise InputError(f"{record}: {name}[{k}] needs 'file' and 'ilp_optimum'")
            file, optimum = entry["file"], entry["ilp_optimum"]
            if not isinstance(file, str):
                raise InputError(f"{record}: {name}[{k}] 'file' must be a path in the corpus folder, not {json.dumps(file)}")
            if not _is_number(optimum):
                raise InputError(f"{record}: {name}[{k}] 'ilp_optimum' must be a finite number, not {json.dumps(optimum)}")
    return corpora


def _is_number(value: object) -> bool:
    """JSON's numbers, not true/false (Python's bools are ints) nor NaN/Infinity (json reads them)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def solve_corpus(folder: Path, name: str, formulation: Formulation,
                 progress: Progress | None = None) -> tuple[list[dict], list[WindowSolution], list[float]]:
    """Solve every window of one corpus: its records, the solutions, the seconds each took."""
    records = load_corpus(folder)[name]
    solutions, seconds = [], []
    for k, record in enumerate(records):
        problem = load_window(folder / record["file"])
        start = time.perf_counter()
        try:
            solutions.append(formulation.solve(problem))
        except FormulationError as error:  # e.g. dp-extended's state space past max_states
            raise InputError(f"{record['file']}: {error}") from None
        seconds.append(time.perf_counter() - start)
        if progress is not None:
            progress(k + 1, len(records))
    return records, solutions, seconds


def corpus_figures(folder: Path, formulation: Formulation, progress: Progress | None = None) -> list[CorpusFigures]:
    """The figures of every corpus in ``folder``; ``progress`` is called per window solved."""
    figures = []
    corpora = load_corpus(folder)
    total, done = sum(len(records) for records in corpora.values()), 0
    for name in sorted(corpora):
        step = None if progress is None else (lambda k, _, base=done: progress(base + k, total))
        records, solutions, seconds = solve_corpus(folder, name, formulation, step)
        done += len(records)
        gaps = np.array([s.gap for s in solutions])
        optimal = [abs(s.cost - r["ilp_optimum"]) <= 1e-6 * max(1.0, abs(r["ilp_optimum"])) for s, r in zip(solutions, records)]
        figures.append(CorpusFigures(
            corpus=name, windows=len(records), integral_fraction=float(np.mean([s.integral for s in solutions])),
            gap_median=float(np.median(gaps)), gap_max=float(gaps.max()), optimal_fraction=float(np.mean(optimal)),
            seconds_median=float(np.median(seconds)),
        ))
    return figures
