"""Seconds per frame for a 41-marker, 120 Hz recording labeled in 20-frame windows.

CMU 85_02 and 135_02 (41 markers, 120 Hz) through the issue's cloud scenario (1 mm
noise, 10 % deletions in 10-frame bursts, 2 ghosts per frame). Prints medians over runs
of one labeling pass per frame and where the time goes (goal: <= 4 ms per frame), and the
default labeling's per frame, second pass included when it runs.

With ``--model`` each run also labels the same capture, same labeled first frame, under a
subject model fitted on the take's other frames (segment-pose prediction and fill,
acquisition, recovery), alternating with the run without, and prints the difference:
the goal is at most 1 ms per frame more.

    .venv/bin/python bench/markers_realtime.py [--runs 5] [--frames 1200] [--model]
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
from service.capture.capture import Capture, LabelingOptions  # noqa: E402
from service.capture.model_input import with_model  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart"


def measure(path: Path, frames: int, runs: int, model: bool = False) -> dict[str, float]:
    truth = read_labeled(path)
    scenario = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0,
                        frames=min(frames, truth.n_frames))
    simulated = simulate_cloud(truth, scenario)
    captures = {"": simulated.capture()}
    if model:
        other = scenario.frames if truth.n_frames - scenario.frames >= 100 else 0  # a speed bench: a take with
        # no frames left over is fitted on the labeled ones, which changes what is labeled, not its cost
        rest = np.where(truth.missing()[other:, :, None], np.nan, truth.positions[other:])
        fitted = fit_subject(truth.names, rest).model
        captures["model_"] = with_model(captures[""], fitted, keep_labels=True)
    rows = []
    for _ in range(runs):
        row: dict[str, float] = {}
        for prefix, capture in captures.items():  # alternated, so both see the same machine load
            row |= {prefix + k: v for k, v in _run(capture, simulated.cloud.n_frames - 1).items()}
        rows.append(row)
    return {k: float(np.median([r[k] for r in rows])) for k in rows[0]} | {"frames": simulated.cloud.n_frames}


def _run(capture: Capture, n: int) -> dict[str, float]:
    """One pass's time per frame and where it goes (what labeling as frames arrive costs), and
    the default labeling's with its second pass (docs/track.md, "Second pass") when it runs."""
    start = time.perf_counter()
    _, windows = CaptureLabeling(capture, LabelingOptions(second_pass=False)).label()
    total = time.perf_counter() - start
    start = time.perf_counter()
    CaptureLabeling(capture).label()
    twice = time.perf_counter() - start
    prepare = sum(w.prepare_seconds for w in windows)
    formulation = sum(w.build_seconds + w.solve_seconds + w.round_seconds for w in windows)
    confidence = sum(w.confidence_seconds for w in windows)
    lp_windows = sum(w.components.get("coupled", 0) > 0 for w in windows)
    return {"total": total / n, "prepare": prepare / n, "formulation": formulation / n,
            "confidence": confidence / n, "other": (total - prepare - formulation - confidence) / n,
            "lp_window_share": lp_windows / len(windows), "twice": twice / n}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--frames", type=int, default=1200)
    parser.add_argument("--model", action="store_true", help="also label under a subject model; print the difference")
    args = parser.parse_args()
    print(f"{'recording':16s} {'frames':>6s} {'ms/frame':>9s} {'candidates+network':>19s} "
          f"{'formulation':>12s} {'confidence':>11s} {'other':>7s} {'windows with an LP':>19s} {'with 2nd pass':>14s}")
    for name in ("85_02.c3d", "135_02.c3d"):
        m = measure(DATA / name, args.frames, args.runs, args.model)
        for prefix in ("", "model_") if args.model else ("",):
            print(f"{name + (' model' if prefix else ''):16s} {m['frames']:6d} {1000 * m[prefix + 'total']:9.2f} "
                  f"{1000 * m[prefix + 'prepare']:19.2f} {1000 * m[prefix + 'formulation']:12.2f} "
                  f"{1000 * m[prefix + 'confidence']:11.2f} {1000 * m[prefix + 'other']:7.2f} "
                  f"{m[prefix + 'lp_window_share']:19.0%} {1000 * m[prefix + 'twice']:14.2f}")
        if args.model:
            print(f"{'':16s} model adds {1000 * (m['model_total'] - m['total']):+.2f} ms/frame (median of each; goal <= 1)")
    print(f"(medians of {args.runs} runs; real time at 120 Hz is 8.33 ms per frame, the goal 4 ms)")


if __name__ == "__main__":
    main()
