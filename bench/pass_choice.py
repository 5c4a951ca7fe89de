"""Which of the two labeling passes each judge keeps, against the truth.

For each take x condition x seed both passes are run to the end (``service.labeling.second_pass``:
the second from the first's take spreads) and scored. A row prints each pass's accuracy, its
doubtful share and its disagreement with the first frame's rigid pairs
(``formulations.markers.first_frame_shape``). The summary gives the mean accuracy over the
runs where a second pass runs (first pass between 2 % and 75 % doubtful) when the pass kept
is the less doubtful one (the old judge), the one closer to the first frame, the better
one each time (what no judge of whole passes can beat), and the two merged group by group
(``formulations.markers.pass_merge``: what ``track`` keeps).

    .venv/bin/python bench/pass_choice.py [--recordings cmu-135_02 ...] [--conditions default noise-4 ...]
        [--scenario configs/scenarios/hard.toml] [--seeds 0 1 2] [--frames 600] [--formulation lp-l1] [--jobs 2]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from contextlib import nullcontext
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.markers.take_spread import with_take_spread  # noqa: E402
from service.capture.capture import LabelingOptions  # noqa: E402
from service.evaluation.matrix import CONDITIONS, RECORDINGS, prepare, recording_named  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.scores import label_scores  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402
from service.labeling.loop import label_windows  # noqa: E402
from service.labeling.merged_windows import merged_windows  # noqa: E402
from service.labeling.second_pass import MOSTLY_DOUBTFUL, doubtful_share, judged_passes  # noqa: E402
from service.labeling.stats import DOUBTFUL_WARNING  # noqa: E402

Run = tuple[str, str, int, int, str, str | None]  # recording, condition, seed, frames, formulation, scenario file


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--recordings", nargs="+", default=[r.name for r in RECORDINGS])
    parser.add_argument("--conditions", nargs="+", default=["default", "noise-4", "drop-30", "ghosts-10"])
    parser.add_argument("--scenario", type=Path, help="a cloud scenario TOML instead of the conditions")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--formulation", default="lp-l1")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    conditions = [args.scenario.stem] if args.scenario else args.conditions
    scenario = str(args.scenario) if args.scenario else None
    runs = [(r, c, s, args.frames, args.formulation, scenario) for r in args.recordings for c in conditions for s in args.seeds]
    print(f"{'recording':18s} {'condition':10s} seed {'acc 1':>7s} {'acc 2':>7s} {'merged':>7s} {'doubt 1':>7s} "
          f"{'doubt 2':>7s} {'off 1':>6s} {'off 2':>6s}")
    rows = []
    with Pool(args.jobs) if args.jobs > 1 else nullcontext() as pool:
        for row in pool.imap(_both_passes, runs) if pool else map(_both_passes, runs):
            rows.append(row)
            run, acc, doubt, off = row
            print(f"{run[0]:18s} {run[1]:10s} {run[2]:4d} {100 * acc[0]:7.2f} {100 * acc[1]:7.2f} {100 * acc[2]:7.2f} "
                  f"{doubt[0]:7.1%} {doubt[1]:7.1%} {off[0]:6.2f} {off[1]:6.2f}", flush=True)
    _summary(rows)


def _both_passes(run: Run) -> tuple[Run, tuple[float, float, float], tuple[float, float], np.ndarray]:
    recording, condition, seed, frames, formulation, scenario_file = run
    scenario = Scenario.from_toml(Path(scenario_file)) if scenario_file else CONDITIONS[condition]
    take = prepare(recording_named(recording))
    simulated = simulate_cloud(take.truth, dataclasses.replace(
        scenario, seed=seed, start_frame=take.start, frames=min(frames, take.frames)))
    labeling = CaptureLabeling(simulated.capture(), LabelingOptions(formulation=formulation, window=scenario.window))
    first = list(labeling.windows())
    chain, start = labeling._association, labeling._first  # noqa: SLF001  (the second pass as refine runs it)
    labeled = labeling._labeled  # noqa: SLF001
    spread = with_take_spread(start, labeled(first).positions)
    second = list(label_windows(chain, labeling.formulation, spread, simulated.cloud.n_frames, scenario.window))
    passes = (first, second)
    first_score, second_score = (label_scores(simulated, labeling.result(p)).label_accuracy for p in passes)
    kept, taken, off = judged_passes(labeled(first), labeled(second), start)
    mine, theirs = (second, first) if kept == 2 else (first, second)
    merged = label_scores(simulated, labeling.result(merged_windows(mine, theirs, taken))).label_accuracy
    return run, (first_score, second_score, merged), (doubtful_share(first), doubtful_share(second)), off


def _summary(rows: list) -> None:
    judged = [(acc, doubt, off) for _, acc, doubt, off in rows if DOUBTFUL_WARNING < doubt[0] <= MOSTLY_DOUBTFUL]
    if not judged:
        print("no run where a second pass runs")
        return
    by_doubt = np.mean([acc[1] if doubt[1] < doubt[0] else acc[0] for acc, doubt, _ in judged])
    by_shape = np.mean([acc[1] if off[1] < off[0] else acc[0] for acc, _, off in judged])
    best = np.mean([max(acc[:2]) for acc, _, _ in judged])
    merged = np.mean([acc[2] for acc, _, _ in judged])
    first = np.mean([acc[0] for acc, _, _ in judged])
    print(f"\n{len(judged)} of {len(rows)} runs run a second pass; mean accuracy kept by: doubt {100 * by_doubt:.2f} %, "
          f"first frame {100 * by_shape:.2f} %, the better pass {100 * best:.2f} %, merged by group {100 * merged:.2f} %, "
          f"first pass only {100 * first:.2f} %")


if __name__ == "__main__":
    main()
