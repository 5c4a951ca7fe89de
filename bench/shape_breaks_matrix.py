"""Shape breaks on the accuracy matrix's simulated takes: labels inside breaks, and how many are right.

The shape check (``formulations/markers/shape_breaks.py``) lowers the confidence of every
label inside a break to ``SHAPE_BREAK_CONFIDENCE``, a figure read on the real takes. Here
it is held against the matrix's recordings and conditions, where the truth of every point
is known: a right label inside a break is a false alarm.

    python bench/shape_breaks_matrix.py [--conditions default noise-4 ...] [--seeds 0] [--frames 600]
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.markers.shape_breaks import shape_breaks  # noqa: E402
from service.evaluation.cloud import evaluate  # noqa: E402
from service.evaluation.matrix import CONDITIONS, DATA, RECORDINGS, prepare, recording_named  # noqa: E402


def cell(job: tuple[str, str, int, int]) -> tuple[str, str, int, int, int, int]:
    """(recording, condition, labels in breaks, right among them, points taken, wrong among them)."""
    name, condition, seed, frames = job
    take = prepare(recording_named(name), DATA)
    scenario = replace(CONDITIONS[condition], seed=seed, start_frame=take.start, frames=min(frames, take.frames))
    run = evaluate(take.truth, scenario, "lp-l1")
    taken, truth = run.result.point_index, run.capture.point_marker

    def right(f: int, n: int) -> bool:
        return bool(truth[f][taken[f, n]] == n)

    labels = [(f, n) for f in range(1, len(taken)) for n in range(taken.shape[1]) if taken[f, n] >= 0]
    inside = [(f, b.marker) for b in shape_breaks(run.result.positions, run.result.rate)
              for f in range(max(b.start, 1), b.stop) if taken[f, b.marker] >= 0]
    return (name, condition, len(inside), sum(right(f, n) for f, n in inside), len(labels),
            sum(not right(f, n) for f, n in labels))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--conditions", nargs="*", default=["default", "noise-4", "drop-30", "ghosts-10"])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0])
    parser.add_argument("--frames", type=int, default=600)
    args = parser.parse_args()
    jobs = [(r.name, c, s, args.frames) for r in RECORDINGS for c in args.conditions for s in args.seeds]
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(cell, jobs))
    print("| recording | condition | labels in breaks | right there | wrong labels in the run |")
    print("|---|---|---|---|---|")
    for name, condition, inside, right, _, wrong in rows:
        if inside:
            print(f"| {name} | {condition} | {inside} | {right} | {wrong} |")
    inside, right = sum(r[2] for r in rows), sum(r[3] for r in rows)
    wrong = sum(r[5] for r in rows)
    print(f"\n{len(rows)} runs, {sum(r[2] > 0 for r in rows)} with a break; {inside} labels in breaks, {right} right "
          f"({100 * right / max(inside, 1):.0f} %); {wrong} wrong labels in all")


if __name__ == "__main__":
    main()
