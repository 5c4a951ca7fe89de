"""Path-LP column generation with and without dual smoothing, on a real take's largest windows.

Labels a take once (first pass, as `markerflow track --one-pass`), keeps the windows the path
LP solved, and times ``solve_path_lp`` on the largest of them with the module's smoothing
and with none (alpha = 0), interleaved, medians of the repeats; it prints the LP seconds,
master solves and path columns, and checks both reach the same optimum.

    .venv/bin/python bench/path_lp_speed.py [--take PATH] [--start N] [--windows 40] [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import formulations.relaxation.path_lp as path_lp  # noqa: E402
import formulations.relaxation.solve_lp as solve_lp  # noqa: E402
from formulations.solvers.highs import HighsBackend  # noqa: E402
from service.cli.track import _read_input  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

TAKE = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "03_rolling.c3d"


def captured_windows(take: Path, start: int) -> list:
    """The (seconds, problem) of every path-LP solve while the take is labeled once."""
    found = []
    solve = path_lp.solve_path_lp

    def kept(problem, time_limit=None, max_rounds=path_lp.MAX_ROUNDS):
        began = time.perf_counter()
        answer = solve(problem, time_limit, max_rounds)
        found.append((time.perf_counter() - began, problem))
        return answer

    solve_lp.solve_path_lp = kept
    try:
        capture, options, _, _ = _read_input(take, False, (start, None))
        CaptureLabeling(capture, replace(options, second_pass=False)).label(None)
    finally:
        solve_lp.solve_path_lp = solve
    return found


def timed(problems: list, smoothing: float) -> tuple[float, int, int, list[float]]:
    """Seconds, master solves, path columns and objectives over ``problems`` at ``smoothing``."""
    solves = 0
    run = HighsBackend.solve

    def counted(self):
        nonlocal solves
        solves += 1
        return run(self)

    path_lp.SMOOTHING, HighsBackend.solve = smoothing, counted
    began = time.perf_counter()
    try:
        answers = [path_lp.solve_path_lp(p) for p in problems]
    finally:
        HighsBackend.solve = run
    return time.perf_counter() - began, solves, sum(a[1] for a in answers), [a[0].objective for a in answers]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--take", type=Path, default=TAKE)
    parser.add_argument("--start", type=int, default=562, help="first frame labeled (03_rolling: its fullest)")
    parser.add_argument("--windows", type=int, default=0,
                        help="time only the N slowest (0: all; choosing by time biases the comparison)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    kept = path_lp.SMOOTHING
    found = sorted(captured_windows(args.take, args.start), key=lambda f: -f[0])
    problems = [p for _, p in (found[: args.windows] if args.windows else found)]
    print(f"{len(found)} path-LP windows, {sum(s for s, _ in found):.1f} s in the labeling; timing {len(problems)} of them")
    rows: dict[float, list[tuple[float, int, int, list[float]]]] = {kept: [], 0.0: []}
    for _ in range(args.repeats):
        for alpha in rows:
            rows[alpha].append(timed(problems, alpha))
    path_lp.SMOOTHING = kept
    gap = max(abs(a - b) / max(1.0, abs(a)) for a, b in zip(rows[kept][0][3], rows[0.0][0][3]))
    print("| smoothing | LP seconds (median) | master solves | path columns |\n|---|---|---|---|")
    for alpha, runs in rows.items():
        print(f"| {alpha:g} | {statistics.median(r[0] for r in runs):.2f} | {runs[0][1]} | {runs[0][2]} |")
    print(f"largest relative difference of the optima: {gap:.1e}")


if __name__ == "__main__":
    main()
