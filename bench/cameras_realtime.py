"""Milliseconds per frame for 41 markers seen by 4 cameras, from 2D detections to labeled 3D.

CMU 85_02 placed in the real Pose2Sim 4-camera rig through the issue's scenario
(``configs/scenarios/cmu-85-02-pose2sim-cameras.toml``: 0.5 px noise, 3 px blob merging,
10 % occlusion in 15-frame bursts, 2 clutter points per camera). Prints medians over runs.

``joint-3d``: matching (epipolar gating, triangulation, growth and merging of the cross-camera
points, plus their detection resources), labeling (window LP on those points), and the total.
The matcher works on blocks of frames (``service.labeling.joint_3d``); one frame at a time is printed
beside it, measured in the same run. ``per-camera``: the total (its own stages interleave).
Goal: <= 4 ms per frame in total.

    .venv/bin/python bench/cameras_realtime.py [--runs 5] [--frames 0] [--association joint-3d|per-camera]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.simulate_cameras import (  # noqa: E402
    CameraCapture,
    CameraRig,
    place_in_volume,
    simulate_cameras,
)
from service.io.calibration import load_calibration  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.io.recording import Recording  # noqa: E402
from service.labeling.cloud import CloudLabeler  # noqa: E402
from service.labeling.joint_3d import cross_camera_cloud  # noqa: E402

SCENARIO = ROOT / "configs" / "scenarios" / "cmu-85-02-pose2sim-cameras.toml"
RECORDING = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def simulate(frames: int) -> tuple[list, CameraCapture]:
    scenario = Scenario.from_toml(SCENARIO)
    cameras = load_calibration(scenario.calibration, units="mm")
    rig = CameraRig.from_cameras(cameras)
    truth = read_labeled(RECORDING)
    positions = truth.positions[: frames or truth.n_frames]
    capture = simulate_cameras(
        Recording(truth.names, place_in_volume(positions, rig, up_axis=scenario.up_axis), truth.rate), rig,
        pixel_noise=scenario.pixel_noise, merge_radius_px=scenario.merge_radius_px,
        occlusion_rate=scenario.occlusion_rate, occlusion_burst_frames=scenario.occlusion_burst_frames,
        clutter_per_camera=scenario.clutter_per_camera, seed=scenario.seed,
    )
    return cameras, capture


def joint_3d(cameras: list, capture: CameraCapture, block_frames: int) -> dict[str, float]:
    """Seconds per frame: matching (all frames, with resources), labeling, total."""
    n = len(capture.detections)
    start = time.perf_counter()
    cloud, _ = cross_camera_cloud(cameras, capture.detections, capture.truth.rate, block_frames=block_frames)
    for f in range(n):
        cloud.resources[f]  # matches the frame's block, then builds its resource rows
    matched = time.perf_counter()
    CloudLabeler().label(cloud, capture.first_frame.names, capture.first_frame.positions[0])
    done = time.perf_counter()
    return {"matching": (matched - start) / n, "labeling": (done - matched) / n, "total": (done - start) / n}


def per_camera(cameras: list, capture: CameraCapture) -> dict[str, float]:
    try:
        from service.capture.capture import Capture
        from service.labeling.per_camera import PerCameraLabeler
    except ImportError as error:
        raise SystemExit(f"--association per-camera is not available in this tree ({error})") from None
    first = capture.first_frame
    job = Capture(list(first.names), first.positions[0], first.rate, cameras=cameras, detections=capture.detections)
    labeler = PerCameraLabeler()
    start = time.perf_counter()
    labeler.assemble(job, list(labeler.windows(job)))
    return {"total": (time.perf_counter() - start) / len(capture.detections)}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--frames", type=int, default=0, help="0: the whole recording")
    parser.add_argument("--association", choices=("joint-3d", "per-camera"), default="joint-3d")
    args = parser.parse_args()
    cameras, capture = simulate(args.frames)
    n_markers, n_frames = capture.marker_detection.shape[2], len(capture.detections)
    print(f"85_02: {n_frames} frames, {n_markers} markers, {len(cameras)} cameras, {args.association}")
    if args.association == "per-camera":
        runs = [per_camera(cameras, capture) for _ in range(args.runs)]
        print(f"total {1000 * np.median([r['total'] for r in runs]):.2f} ms/frame")
    else:
        for block in (20, 1):
            runs = [joint_3d(cameras, capture, block) for _ in range(args.runs)]
            figures = {k: 1000 * float(np.median([r[k] for r in runs])) for k in runs[0]}
            print(f"matching in blocks of {block:2d} frame(s): matching {figures['matching']:.2f}  "
                  f"labeling {figures['labeling']:.2f}  total {figures['total']:.2f} ms/frame")
    print(f"(medians of {args.runs} runs; real time at 120 Hz is 8.33 ms per frame, the goal 4 ms)")


if __name__ == "__main__":
    main()
