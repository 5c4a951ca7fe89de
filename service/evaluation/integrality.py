"""How a formulation does on the integrality corpus: windows with their recorded ILP optima.

A corpus is a folder of window files (``service.io.window_files``) plus ``recorded.json``:
per corpus, per window, the LP objective, whether the LP was integral, and the ILP optimum.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formulations.methods.formulation import Formulation
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.io.window_files import load_window

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
    """``recorded.json`` of a corpus folder: corpus name -> window records."""
    record = folder / RECORD
    if not record.is_file():
        raise InputError(f"{folder}: no integrality corpus here ({RECORD} missing)")
    return json.loads(record.read_text())


def solve_corpus(folder: Path, name: str, formulation: Formulation) -> tuple[list[dict], list[WindowSolution], list[float]]:
    """Solve every window of one corpus: its records, the solutions, the seconds each took."""
    records = load_corpus(folder)[name]
    solutions, seconds = [], []
    for record in records:
        problem = load_window(folder / record["file"])
        start = time.perf_counter()
        solutions.append(formulation.solve(problem))
        seconds.append(time.perf_counter() - start)
    return records, solutions, seconds


def corpus_figures(folder: Path, formulation: Formulation) -> list[CorpusFigures]:
    """The figures of every corpus in ``folder``."""
    figures = []
    for name in sorted(load_corpus(folder)):
        records, solutions, seconds = solve_corpus(folder, name, formulation)
        gaps = np.array([s.gap for s in solutions])
        optimal = [abs(s.cost - r["ilp_optimum"]) <= 1e-6 * max(1.0, abs(r["ilp_optimum"])) for s, r in zip(solutions, records)]
        figures.append(CorpusFigures(
            corpus=name, windows=len(records), integral_fraction=float(np.mean([s.integral for s in solutions])),
            gap_median=float(np.median(gaps)), gap_max=float(gaps.max()), optimal_fraction=float(np.mean(optimal)),
            seconds_median=float(np.median(seconds)),
        ))
    return figures
