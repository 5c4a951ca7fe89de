"""Fill error over the accuracy matrix's takes: the tied fill against the rigid refill.

Each take of ``service/evaluation/matrix.py`` is simulated and labeled once per condition and
seed (lp-l1); the labeling's fill tied to both sightings (``gap_ends``) and the same fill
refilled from rigid donors (``rigid_fill``) are scored against the clean truth over the
occluded marker-frames that have one (the file's own gaps have none). The labels are the same
for both: the fill never feeds back into labeling.

    .venv/bin/python bench/fill_matrix.py [--conditions default drop-30] [--seeds 0] [--frames 600] [--jobs 2]

Prints per row the marker-frames scored and RMSE / median (mm) of each fill, then the pooled
figures and the rows where the refill has the lower RMSE.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import service.labeling.capture_labeling as capture_labeling  # noqa: E402
from formulations.markers.rigid_fill import rigid_fill  # noqa: E402
from service.evaluation.cloud import evaluate  # noqa: E402
from service.evaluation.matrix import CONDITIONS, RECORDINGS, prepare, recording_named  # noqa: E402

Errors = tuple[np.ndarray, np.ndarray]


def cell(key: tuple[str, str, int, int]) -> tuple[str, str, int, Errors]:
    """The tied and the refilled fill's errors (mm) of one take, condition and seed."""
    capture_labeling.rigid_fill = lambda positions, filled: filled  # the labeler stops at the tie
    name, condition, seed, cap = key
    take = prepare(recording_named(name))
    frames = min(cap, take.frames) if cap else take.frames
    run = evaluate(take.truth, replace(CONDITIONS[condition], seed=seed, start_frame=take.start, frames=frames), "lp-l1")
    result, truth = run.result, run.capture.truth.positions
    scored = result.occluded.copy()
    scored[0] = False
    errors = []
    for fill in (result.filled, rigid_fill(result.positions, result.filled)):
        error = np.linalg.norm(fill - truth, axis=2)
        errors.append(error[scored & np.isfinite(error)])
    return name, condition, seed, (errors[0], errors[1])


def _figures(error: np.ndarray) -> str:
    return f"{np.sqrt(np.mean(error**2)):7.1f}/{np.median(error):5.1f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--conditions", nargs="+", default=["default", "drop-30"], choices=list(CONDITIONS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--frames", type=int, default=600, help="cap on frames per take; 0: full length")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    keys = [(r.name, c, s, args.frames) for r in RECORDINGS for c in args.conditions for s in args.seeds]
    with Pool(args.jobs) as pool:
        rows = [row for row in pool.map(cell, keys) if row[3][0].size]
    print(f"{'recording':18s} {'condition':9s} {'seed':>4s} {'scored':>7s} {'tied rmse/med':>13s} {'refilled':>13s}")
    for name, condition, seed, (tied, refilled) in rows:
        print(f"{name:18s} {condition:9s} {seed:4d} {tied.size:7d} {_figures(tied):>13s} {_figures(refilled):>13s}")
    tied, refilled = (np.concatenate([row[3][k] for row in rows]) for k in (0, 1))
    lower = sum(np.mean(r[3][1] ** 2) < np.mean(r[3][0] ** 2) for r in rows)
    print(f"pooled: tied {_figures(tied)}  refilled {_figures(refilled)}  refill lower on {lower} of {len(rows)} rows")


if __name__ == "__main__":
    main()
