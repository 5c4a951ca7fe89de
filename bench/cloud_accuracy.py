"""Label accuracy, swaps, speed and the doubtful labels, per recording, formulation and seed.

By default CMU 85_02 through the issue's cloud scenario (1 mm noise, 10 % deletions in
10-frame bursts, 2 ghosts per frame), one run per seed; ``--scenario`` takes any cloud
scenario TOML (e.g. ``configs/scenarios/hard.toml``), ``--recordings`` other takes of
the accuracy matrix by name (``service/evaluation/matrix.py``: each from its first frame
with the most markers present, markers absent there left out), ``--frames`` caps each take.
With mu > 0, layout pairs join each marker to its two most rigid neighbours where the two
are already coupled.

Per row: accuracy per seed and its median, swaps summed over the seeds, share of windows
proven optimal, the largest gap, the median ms per frame, and over all seeds' labels the
doubtful share (labels with confidence below ``DOUBTFUL_BELOW``) and the doubtful recall
(wrong labels among them / wrong labels; "-" when no label was wrong); then the same two
without the marker-frames where the file's own labels jump to another marker
(``service/evaluation/label_jumps.py``: there neither right nor wrong is known), nor the
labels of markers the file does not see on those marker-frames' points (``doubt_counts``),
and the share of labels left out so.

    .venv/bin/python bench/cloud_accuracy.py [--seeds 6] [--mu 0 0.05 0.2] [--formulations lp-l1 nn-hungarian]
        [--scenario configs/scenarios/hard.toml] [--recordings cmu-85_02 cmu-135_02 numediart-rolling]
        [--frames 600] [--mht-reading]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from service.capture.capture import LabelingOptions  # noqa: E402
from service.evaluation.doubt_scores import DoubtCounts, doubt_counts  # noqa: E402
from service.evaluation.label_jumps import label_jumps  # noqa: E402
from service.evaluation.matrix import prepare, recording_named  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.scores import label_scores  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.evaluation.simulated import SimulatedCapture  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

RECORDING = "cmu-85_02"
ISSUE_SCENARIO = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--mu", type=float, nargs="+", default=[0.0])
    parser.add_argument("--formulations", nargs="+", default=["lp-l1"])
    parser.add_argument("--scenario", type=Path, help="a cloud scenario TOML (default: the issue's)")
    parser.add_argument("--recordings", nargs="+", default=[RECORDING], help="accuracy-matrix take names")
    parser.add_argument("--frames", type=int, default=0, help="frames per take (0: the whole take)")
    parser.add_argument("--mht-reading", action="store_true", help="read doubtful takes by mht too (LabelingOptions.mht_reading)")
    args = parser.parse_args()
    scenario = Scenario.from_toml(args.scenario) if args.scenario else ISSUE_SCENARIO
    print(f"{'recording':18s} {'formulation':13s} {'mu':>4s} {'accuracy per seed':{8 * args.seeds}s} {'median':>7s} "
          f"{'swaps':>5s} {'integral':>8s} {'max gap':>8s} {'ms/frame':>8s} {'doubtful':>8s} {'recall':>6s} "
          f"{'off file jumps':>15s} {'left out':>8s}")
    for recording in args.recordings:
        take = prepare(recording_named(recording))
        frames = min(args.frames, take.frames) if args.frames else take.frames
        simulations = [simulate_cloud(take.truth, dataclasses.replace(scenario, seed=s, start_frame=take.start,
                                                                      frames=frames)) for s in range(args.seeds)]
        jumps = label_jumps(take.truth)[take.start : take.start + frames]
        for name, mu in [(f, m) for f in args.formulations for m in args.mu]:
            print(_row(recording, name, mu, simulations, jumps, scenario.window, args.mht_reading), flush=True)


def _row(
    recording: str, name: str, mu: float, simulations: list[SimulatedCapture], jumps: np.ndarray, window: int, mht: bool,
) -> str:
    accuracy, swaps, integral, gaps, speed = [], 0, [], [], []
    doubt, known = DoubtCounts(0, 0, 0, 0), DoubtCounts(0, 0, 0, 0)
    for simulated in simulations:
        start = time.perf_counter()
        options = LabelingOptions(formulation=name, layout_weight=mu, window=window, mht_reading=mht)
        result, windows = CaptureLabeling(simulated.capture(), options).label()
        speed.append((time.perf_counter() - start) / simulated.cloud.n_frames)
        scores = label_scores(simulated, result)
        accuracy.append(scores.label_accuracy)
        swaps += scores.swaps
        integral += [w.integral for w in windows]
        gaps += [w.gap for w in windows]
        doubt = _sum(doubt, doubt_counts(simulated, result))
        known = _sum(known, doubt_counts(simulated, result, jumps))
    per_seed = " ".join(f"{a:.4f}" for a in accuracy)
    return (f"{recording:18s} {name:13s} {mu:4.2f} {per_seed:{8 * len(simulations)}s} {np.median(accuracy):7.4f} "
            f"{swaps:5d} {np.mean(integral):8.1%} {max(gaps):8.1e} {1000 * np.median(speed):8.2f} "
            f"{_doubt(doubt, 8)} {_doubt(known, 8)} {1 - known.labels / max(doubt.labels, 1):8.2%}")


def _sum(a: DoubtCounts, b: DoubtCounts) -> DoubtCounts:
    return DoubtCounts(*(x + y for x, y in zip(dataclasses.astuple(a), dataclasses.astuple(b))))


def _doubt(counts: DoubtCounts, width: int) -> str:
    share, recall = counts.scores().values()
    return f"{share:{width}.2%} {'-' if recall is None else f'{recall:.3f}':>6s}"


if __name__ == "__main__":
    main()
