"""Identification of one unlabeled frame from a subject model: accuracy and milliseconds.

A model is fitted on the first half of CMU 85_02 (41 markers); every 5th frame of the second
half gets 1 mm noise, 10 % of its markers deleted and 5 ghosts (200 mm from the body), is
shuffled and identified. Prints the share of visible markers named right, the wrong names,
and the median and 90th percentile time per frame. Goal: <= 50 ms per frame.

    .venv/bin/python bench/identify.py [--step 5] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.subject.fit import fit_subject  # noqa: E402
from formulations.subject.geometry import ModelGeometry  # noqa: E402
from formulations.subject.identify import identify  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402

TAKE = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
GHOSTS = 5


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--step", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    take = read_labeled(TAKE)
    positions = np.where(take.missing()[:, :, None], np.nan, take.positions)
    half = take.n_frames // 2
    geometry = ModelGeometry.of(fit_subject(take.names, positions[:half]).model)
    columns = [take.names.index(n) for n in geometry.names]
    rng = np.random.default_rng(args.seed)
    right = wrong = visible = 0
    times = []
    for frame in range(half, take.n_frames, args.step):
        truth = positions[frame, columns] + rng.normal(0, 1.0, (len(columns), 3))
        keep = np.flatnonzero(rng.random(len(columns)) > 0.1)
        ghosts = truth[rng.integers(0, len(columns), GHOSTS)] + rng.normal(0, 200, (GHOSTS, 3))
        points = np.concatenate([truth[keep], ghosts])
        owner = np.concatenate([keep, np.full(GHOSTS, -1)])
        order = rng.permutation(len(points))
        began = time.perf_counter()
        found = identify(geometry, points[order])
        times.append(1000 * (time.perf_counter() - began))
        named = np.flatnonzero(found.named)
        good = owner[order][found.point[named]] == named
        right, wrong, visible = right + int(good.sum()), wrong + int((~good).sum()), visible + len(keep)
    print(f"{TAKE.name}: model fitted on frames 0-{half - 1}, {len(columns)} markers, "
          f"{len(times)} frames identified with {GHOSTS} ghosts")
    print(f"named right {right / visible:.1%} of visible markers, named wrong {wrong / visible:.2%}, "
          f"ms per frame median {np.median(times):.1f}, p90 {np.percentile(times, 90):.1f}")


if __name__ == "__main__":
    main()
