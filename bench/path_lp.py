"""How long the window LPs of real takes take, with each interior-point backend giving the
path LP's central duals (``path_lp.INTERIOR_POINT``: HiGHS' IPX or Clarabel).

Every window a first pass of `markerflow track` solves by path pricing (``relaxation.path_lp``,
large windows without a layout term) is kept, then each is solved again by
``solve_window_lp`` (so a path LP that stalls at its round limit pays its arc-LP fallback) with
each backend, interleaved, ``--repeats`` times. Prints per take: windows, seconds (median
over the repeats), master solves, windows proven optimal, windows whose objective differs
from HiGHS'.

    .venv/bin/python bench/path_lp.py [--takes numediart-rolling ktk-racing ktk-tennis] [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any
from unittest.mock import patch

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.relaxation import path_lp, solve_lp  # noqa: E402
from formulations.relaxation.certify import Relaxation  # noqa: E402
from formulations.solvers import SolverBackend, SolveResult, highs  # noqa: E402
from formulations.solvers.clarabel_lp import ClarabelBackend  # noqa: E402
from formulations.window.problem import WindowProblem  # noqa: E402
from service.capture.capture import LabelingOptions  # noqa: E402
from service.capture.from_recording import capture_from_span  # noqa: E402
from service.evaluation.matrix import DATA, recording_named  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

BACKENDS = ("highs", "clarabel")


def windows_of(name: str) -> list[WindowProblem]:
    """The problems a first pass of the take (from its first fullest frame) hands to the path LP."""
    truth = read_labeled(DATA / recording_named(name).path)
    start = int(np.argmax((~truth.missing()).sum(axis=1)))  # as bench/real_takes.py
    capture, _ = capture_from_span(truth, start)  # shuffled, as `markerflow track` reads it
    kept: list[WindowProblem] = []

    def keep(problem: WindowProblem, time_limit: float | None = None, max_rounds: int = path_lp.MAX_ROUNDS,
             ) -> tuple[SolveResult, int]:
        kept.append(problem)
        return path_lp.solve_path_lp(problem, time_limit, max_rounds)

    with patch.object(solve_lp, "solve_path_lp", keep):  # what solve_window_lp calls
        CaptureLabeling(capture, LabelingOptions(second_pass=False)).label()
    return kept


def timed(problems: list[WindowProblem], backend: str) -> tuple[float, int, list[Relaxation]]:
    """Seconds to solve every window, master solves made (either backend), and the relaxations."""
    solves = 0

    def counted(run: Callable[[Any], SolveResult]) -> Callable[[Any], SolveResult]:
        def solve(self: SolverBackend) -> SolveResult:
            nonlocal solves
            solves += 1
            return run(self)
        return solve

    with (patch.object(path_lp, "INTERIOR_POINT", backend),
          patch.object(highs.HighsBackend, "solve", counted(highs.HighsBackend.solve)),
          patch.object(ClarabelBackend, "solve", counted(ClarabelBackend.solve))):
        began = time.perf_counter()
        results = [solve_lp.solve_window_lp(p) for p in problems]
        return time.perf_counter() - began, solves, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--takes", nargs="*", default=["numediart-rolling", "ktk-racing", "ktk-tennis"])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print("| take | windows | interior point | seconds (median) | master solves | proven | objective differs |")
    print("|---|---|---|---|---|---|---|")
    for name in args.takes:
        problems = windows_of(name)
        seconds: dict[str, list[float]] = {b: [] for b in BACKENDS}
        outcome: dict[str, tuple[int, list[Relaxation]]] = {}
        for _ in range(args.repeats):
            for backend in BACKENDS:
                took, solves, results = timed(problems, backend)
                seconds[backend].append(took)
                outcome[backend] = (solves, results)
        reference = [r.xi for r in outcome[BACKENDS[0]][1]]
        for backend in BACKENDS:
            solves, results = outcome[backend]
            value = [float(p.arc_cost @ r.xi) for p, r in zip(problems, results)]
            differs = sum(not np.isclose(v, float(p.arc_cost @ x), rtol=path_lp.PROVEN)
                          for v, p, x in zip(value, problems, reference))
            print(f"| {name} | {len(problems)} | {backend} | {statistics.median(seconds[backend]):.2f} | "
                  f"{solves} | {sum(r.optimal for r in results)} | {differs} |", flush=True)


if __name__ == "__main__":
    main()
