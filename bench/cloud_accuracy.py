"""Label accuracy, integrality and speed per formulation and layout weight.

CMU 85_02 through the issue's cloud scenario (1 mm noise, 10 % deletions in 10-frame
bursts, 2 ghosts per frame), one run per seed. With mu > 0, layout pairs join each marker
to its two most rigid neighbours where the two are already coupled.

    .venv/bin/python bench/cloud_accuracy.py [--seeds 6] [--mu 0 0.05 0.2] [--formulations lp-l1 nn-hungarian]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from service.capture.capture import LabelingOptions  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.scores import label_scores  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

RECORDING = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--mu", type=float, nargs="+", default=[0.0])
    parser.add_argument("--formulations", nargs="+", default=["lp-l1"])
    args = parser.parse_args()
    truth = read_labeled(RECORDING)
    simulations = [simulate_cloud(truth, Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10,
                                               ghosts_per_frame=2.0, seed=s)) for s in range(args.seeds)]
    print(f"{'formulation':14s} {'mu':>5s} {'accuracy per seed':40s} {'median':>7s} {'swaps':>5s} "
          f"{'integral':>8s} {'max gap':>8s} {'ms/frame':>8s}")
    for name, mu in [(f, m) for f in args.formulations for m in args.mu]:
        accuracy, swaps, integral, gaps, speed = [], 0, [], [], []
        for simulated in simulations:
            start = time.perf_counter()
            options = LabelingOptions(formulation=name, layout_weight=mu)
            result, windows = CaptureLabeling(simulated.capture(), options).label()
            speed.append((time.perf_counter() - start) / simulated.cloud.n_frames)
            scores = label_scores(simulated, result)
            accuracy.append(scores.label_accuracy)
            swaps += scores.swaps
            integral += [w.integral for w in windows]
            gaps += [w.gap for w in windows]
        per_seed = " ".join(f"{a:.4f}" for a in accuracy)
        print(f"{name:14s} {mu:5.2f} {per_seed:40s} {np.median(accuracy):7.4f} {swaps:5d} {np.mean(integral):8.1%} "
              f"{max(gaps):8.1e} {1000 * np.median(speed):8.2f}")


if __name__ == "__main__":
    main()
