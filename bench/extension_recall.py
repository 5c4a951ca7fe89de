"""How much of a dropped track the take-wide extension gives back, and how much of it wrongly.

For every take of the accuracy matrix (``service/evaluation/matrix.py``, from its start frame,
markers absent there left out), each frame's present markers are its points, with ``--noise``
mm of Gaussian noise and ``--ghosts`` stray points a frame (each within 200 mm of a random
marker). Labels are dropped in 12-frame gaps until ``--drop`` of the present marker-frames are
unlabeled, their points left in place: what a window leaves when its gate misses a marker.
``extend_tracks`` then walks in from each gap's ends; a label given back is right when it is the
marker's own point. Per take: the share given back, the share of those wrong, and the seconds,
with the end gates (``track_extension._end_gates``) and, for comparison in the same run, with
the take-wide gate g_n alone (``--both``).

    .venv/bin/python bench/extension_recall.py [--noise 0 2] [--ghosts 0 3] [--seeds 0 1 2] [--drop 0.15] [--both]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import formulations.markers.track_extension as extension  # noqa: E402
from service.evaluation.matrix import RECORDINGS, prepare  # noqa: E402

GAP_FRAMES = 12


Scene = tuple[list[np.ndarray], np.ndarray, np.ndarray]


def scene(truth: np.ndarray, noise: float, ghosts: int, drop: float, seed: int) -> Scene:
    """Per frame the points (present markers first, then ghosts), the labels with gaps dropped,
    and the full labels (``(F, N)`` point index, -1 absent)."""
    rng = np.random.default_rng(seed)
    frames, markers = truth.shape[:2]
    present = np.isfinite(truth).all(axis=2)
    full = np.where(present, np.cumsum(present, axis=1) - 1, -1)
    points = []
    for f in range(frames):
        own = truth[f][present[f]] + rng.normal(0, noise, (present[f].sum(), 3))
        near = own[rng.integers(len(own), size=ghosts)] if len(own) else np.empty((0, 3))
        points.append(np.vstack([own, near + rng.uniform(-200, 200, (len(near), 3))]))
    labels = full.copy()
    while (labels < 0).sum() - (~present).sum() < drop * present.sum():
        f, m = rng.integers(2, max(frames - GAP_FRAMES, 3)), rng.integers(markers)
        labels[f : f + GAP_FRAMES, m] = -1
    return points, labels, full


def scored(points: list[np.ndarray], labels: np.ndarray, full: np.ndarray) -> tuple[int, int, int, float]:
    """Dropped present labels, labels given back, wrong ones among them, seconds."""
    start = time.perf_counter()
    out = extension.extend_tracks(points, labels)
    seconds = time.perf_counter() - start
    dropped = (labels < 0) & (full >= 0)
    back = (out >= 0) & (labels < 0)
    return int(dropped.sum()), int(back.sum()), int((back & (out != full)).sum()), seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 2.0])
    parser.add_argument("--ghosts", type=int, nargs="+", default=[0, 3])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--drop", type=float, default=0.15)
    parser.add_argument("--both", action="store_true", help="also with the take-wide gate alone, same run")
    args = parser.parse_args()
    end_gates = extension._end_gates
    take_wide = lambda flat, offsets, taken, f, m, step, gate: gate[m]  # noqa: E731
    variants = [("end gates", end_gates)] + ([("take-wide", take_wide)] if args.both else [])
    totals = {name: np.zeros(4) for name, _ in variants}
    print(f"{'take':18s} {'noise':>5s} {'ghosts':>6s} " + " ".join(f"{name + ': back / wrong / s':>32s}" for name, _ in variants))
    for recording in RECORDINGS:
        take = prepare(recording)
        truth = take.truth.positions[take.start :]
        for noise in args.noise:
            for ghosts in args.ghosts:
                row = np.zeros((len(variants), 4))
                for seed in args.seeds:
                    points, labels, full = scene(truth, noise, ghosts, args.drop, seed)
                    for k, (_, gates) in enumerate(variants):
                        extension._end_gates = gates
                        row[k] += scored(points, labels, full)
                cells = [f"{100 * b / d:6.2f} % {100 * w / max(b, 1):6.3f} % {s:7.3f}" for d, b, w, s in row]
                print(f"{recording.name:18s} {noise:5.1f} {ghosts:6d} " + " ".join(f"{c:>32s}" for c in cells), flush=True)
                for (name, _), values in zip(variants, row):
                    totals[name] += values
    extension._end_gates = end_gates
    for name, (d, b, w, s) in totals.items():
        print(f"all ({name}): {100 * b / d:.2f} % of {int(d):,} dropped labels given back, {100 * w / max(b, 1):.3f} % "
              f"of them wrong, {s:.2f} s")


if __name__ == "__main__":
    main()
