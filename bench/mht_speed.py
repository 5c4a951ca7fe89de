"""Milliseconds per frame of ``mht`` with I = J = 5 on whole 41-marker windows. Goal: <= 10 ms/frame.

CMU 85_02 and 135_02 (41 markers, 120 Hz) through the cloud scenario of
``markers_realtime`` (1 mm noise, 10 % deletions in 10-frame bursts, 2 ghosts per frame),
labeled with ``--formulation mht`` in 20-frame windows. Prints the median over runs of the
formulation's own time per frame (``WindowStats.solve_seconds``: the whole window, every
object) and of the whole labeling per frame, and the share of the formulation's time in
Murty's k-best (``k_best_assignments``, one profiled run).

    .venv/bin/python bench/mht_speed.py [--runs 3] [--frames 600] [--hypotheses 5] [--associations 5]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.methods.mht import Mht  # noqa: E402
from service.capture.capture import LabelingOptions  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--hypotheses", type=int, default=5)
    parser.add_argument("--associations", type=int, default=5)
    args = parser.parse_args()
    options = LabelingOptions(formulation=Mht(hypotheses=args.hypotheses, associations=args.associations))
    for name in ("85_02.c3d", "135_02.c3d"):
        truth = read_labeled(DATA / name)
        scenario = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0,
                            frames=min(args.frames, truth.n_frames))
        capture = simulate_cloud(truth, scenario).capture()
        frames = len(capture.points) - 1
        solve, total = [], []
        for _ in range(args.runs):
            start = time.perf_counter()
            _, windows = CaptureLabeling(capture, options).label()
            total.append((time.perf_counter() - start) / frames)
            solve.append(sum(w.solve_seconds for w in windows) / frames)
        profile = cProfile.Profile()
        profile.runcall(CaptureLabeling(capture, options).label)
        stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
        murty = sum(v[3] for k, v in stats.items() if k[2] == "k_best_assignments")
        solving = sum(v[3] for k, v in stats.items() if k[2] == "solve" and k[0].endswith("mht.py"))
        print(
            f"{name}: {len(truth.names)} markers, {frames} frames; mht I={args.hypotheses} J={args.associations}: "
            f"formulation {1000 * np.median(solve):.2f} ms/frame, whole labeling {1000 * np.median(total):.2f} ms/frame "
            f"(medians of {args.runs}); k-best {murty / max(solving, 1e-12):.0%} of the formulation (profiled)"
        )


if __name__ == "__main__":
    main()
