"""Cross-camera gates fixed (2 px / 3 px) against gates from frame 0's measured noise, on many takes.

Each recording of ``service.evaluation.matrix.RECORDINGS`` (its start frame and kept markers,
``prepare``) is placed in the real Pose2Sim 4-camera rig and simulated at each pixel noise
and seed (3 px blob merging, 10 % occlusion in 15-frame bursts, 2 clutter points per camera),
then labeled with ``joint-3d`` twice: with ``matcher_gates`` forced to the fixed defaults, and
as shipped (``matcher_gates(frame0_pixel_sigma(...))``). Prints per recording and noise the
share of marker-frames within 20 mm of the truth and the occluded share, each as fixed ->
measured, means over seeds, then the mean over recordings per noise.

    .venv/bin/python bench/camera_gates.py [--half validation|tuning|both] [--frames 120] [--seeds 0 1 2]
        [--noise 0.5 1.5 2.5]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import service.labeling.capture_labeling as capture_labeling  # noqa: E402
from formulations.cameras.rig import Rig  # noqa: E402
from service.capture.capture import Capture, LabelingOptions  # noqa: E402
from service.evaluation.matrix import RECORDINGS, prepare  # noqa: E402
from service.evaluation.simulate_cameras import place_in_volume, simulate_cameras  # noqa: E402
from service.io.calibration import load_calibration  # noqa: E402
from service.io.recording import Recording  # noqa: E402
from service.labeling.joint_3d import EPIPOLAR_PX, REPROJECTION_PX, matcher_gates  # noqa: E402

CALIBRATION = ROOT.parent / "shared" / "data" / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
NEAR_MM = 20.0


def scores(capture: Capture, truth: np.ndarray, fixed: bool) -> tuple[float, float]:
    """(share within NEAR_MM of the truth, occluded share) of one joint-3d labeling."""
    capture_labeling.matcher_gates = (lambda _: (EPIPOLAR_PX, REPROJECTION_PX)) if fixed else matcher_gates
    labels, _ = capture_labeling.CaptureLabeling(capture, LabelingOptions()).label()
    error = np.linalg.norm(labels.positions - truth, axis=2)
    return float(np.nanmean(error < NEAR_MM)), float(labels.occluded.mean())


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--half", default="validation", choices=("validation", "tuning", "both"))
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2])
    parser.add_argument("--noise", type=float, nargs="*", default=[0.5, 1.5, 2.5])
    args = parser.parse_args()
    cameras = load_calibration(CALIBRATION, units="mm")
    rig = Rig.of(cameras)
    totals: dict[float, list[np.ndarray]] = {noise: [] for noise in args.noise}
    print("| recording | noise px | within 20 mm fixed -> measured | occluded fixed -> measured |")
    print("|---|---|---|---|")
    for recording in (r for r in RECORDINGS if args.half in ("both", r.half)):
        take = prepare(recording)
        span = take.truth.positions[take.start: take.start + args.frames]
        placed = Recording(take.truth.names, place_in_volume(span, rig), take.truth.rate)
        for noise in args.noise:
            runs = []
            for seed in args.seeds:
                simulated = simulate_cameras(placed, rig, pixel_noise=noise, merge_radius_px=3.0, occlusion_rate=0.1,
                                             occlusion_burst_frames=15, clutter_per_camera=2, seed=seed)
                first = simulated.first_frame
                capture = Capture(first.names, first.positions[0], first.rate, cameras=cameras,
                                  detections=simulated.detections)
                runs.append([*scores(capture, placed.positions, True), *scores(capture, placed.positions, False)])
            near_fixed, occluded_fixed, near, occluded = np.mean(runs, axis=0)
            totals[noise].append(np.mean(runs, axis=0))
            print(f"| {recording.name} | {noise:g} | {near_fixed:.2%} -> {near:.2%} | "
                  f"{occluded_fixed:.2%} -> {occluded:.2%} |", flush=True)
    for noise, rows in totals.items():
        mean = np.mean(rows, axis=0)
        print(f"| mean of {len(rows)} | {noise:g} | {mean[0]:.2%} -> {mean[2]:.2%} | {mean[1]:.2%} -> {mean[3]:.2%} |")


if __name__ == "__main__":
    main()
